// For tests only (`bsdf_probe.rs`): samples bsdf.wgsl for a batch of inputs, so that the
// CPU can histogram the GPU's directions against the CPU's pdf. Composed after the host
// constants and bsdf.wgsl.

// One query: the geometric normal (w: the material index, as bits), the shading normal,
// the outgoing direction and the numbers (u_lobe, u.x, u.y).
struct ProbeInput {
    n_g: vec4<f32>,
    n_s: vec4<f32>,
    wo: vec4<f32>,
    u: vec4<f32>,
}

// Its answer: the direction (w: the lobe kind, as bits), f·|cos| of radiance transport (w:
// the pdf), f·|cos| of importance transport (w: the pdf), in `valid.x` 1 where sampling
// succeeded and in `valid.y` the reverse pdf (as bits).
struct ProbeOutput {
    wi: vec4<f32>,
    f_cos: vec4<f32>,
    importance: vec4<f32>,
    valid: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> materials: array<Material>;
@group(0) @binding(1) var<storage, read> tables: array<f32>;
@group(0) @binding(2) var<storage, read> probe_inputs: array<ProbeInput>;
@group(0) @binding(3) var<storage, read_write> probe_outputs: array<ProbeOutput>;

@compute @workgroup_size(64)
fn probe_bsdf(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i >= arrayLength(&probe_inputs) {
        return;
    }
    let p = probe_inputs[i];
    let b = bsdf_new(materials[bitcast<u32>(p.n_g.w)], p.n_g.xyz, p.n_s.xyz);
    let out = outgoing(b, p.wo.xyz);
    var answer = ProbeOutput(vec4(0.0), vec4(0.0), vec4(0.0), vec4(0u));
    if out.valid {
        let s = bsdf_sample(b, out, p.u.x, p.u.yz, false, true);
        let t = bsdf_sample(b, out, p.u.x, p.u.yz, true, true);
        answer = ProbeOutput(
            vec4(s.wi, bitcast<f32>(s.kind)),
            vec4(s.f_cos, s.pdf_fwd),
            vec4(t.f_cos, t.pdf_fwd),
            vec4(u32(s.valid), bitcast<u32>(s.pdf_rev), 0u, 0u),
        );
    }
    probe_outputs[i] = answer;
}
