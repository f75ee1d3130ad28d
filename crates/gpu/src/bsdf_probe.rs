//! The GPU's BSDF sampling checked with the shared chi-square harness: bsdf.wgsl samples a
//! batch of directions on the GPU (`shaders/bsdf_probe.wgsl`), the CPU histograms them
//! against the CPU's pdf, and each sample's pdfs (forward and reverse) and f·|cos| (of
//! radiance and of importance transport) are compared with the CPU's.
//! Skipped without a graphics adapter unless `VCM_REQUIRE_GPU=1`.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use vcm_scene::bsdf::{Bsdf, BsdfParams, Lobes, Pdfs, TransportMode};
use vcm_scene::frame::Frame;
use vcm_scene::sampling::{Rng, Sampler};
use vcm_scene::testing::{Chi2Config, chi2_test};
use vcm_traversal_wgpu::{GpuDevice, device_or_skip};

use crate::probe::run_probe;
use crate::scene_data::{lookup_tables, pack_material};
use crate::shader::{BSDF_WGSL, host_constants};

const PROBE_WGSL: &str = include_str!("../shaders/bsdf_probe.wgsl");

/// `ProbeInput` of `bsdf_probe.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ProbeInput {
    n_g: [f32; 4],
    n_s: [f32; 4],
    wo: [f32; 4],
    u: [f32; 4],
}

/// `ProbeOutput` of `bsdf_probe.wgsl`.
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
#[repr(C)]
struct ProbeOutput {
    wi: [f32; 4],
    f_cos: [f32; 4],
    importance: [f32; 4],
    valid: [u32; 4],
}

/// `KIND_SPECULAR` of `bsdf.wgsl`.
const KIND_SPECULAR: u32 = 2;

/// Samples `material` (one side unless `double_sided`) at the surface with normals `n_g`
/// (geometric) and `n_s` (shading) from `wo` with each of `numbers` (u_lobe, u) on the GPU.
fn sample_on_gpu(
    gpu: &GpuDevice,
    (params, double_sided): (&BsdfParams, bool),
    (n_g, n_s, wo): (Vec3, Vec3, Vec3),
    numbers: &[[f32; 3]],
) -> Vec<ProbeOutput> {
    let material = pack_material(Some(&Lobes::new(params).flat()), double_sided);
    let inputs: Vec<ProbeInput> = numbers
        .iter()
        .map(|&[u_lobe, ux, uy]| ProbeInput {
            n_g: n_g.extend(0.0).to_array(),
            n_s: n_s.extend(0.0).to_array(),
            wo: wo.extend(0.0).to_array(),
            u: [u_lobe, ux, uy, 0.0],
        })
        .collect();
    let source = format!("{}{BSDF_WGSL}\n{PROBE_WGSL}", host_constants());
    run_probe(
        gpu,
        (source, "probe_bsdf"),
        &[
            bytemuck::bytes_of(&material),
            bytemuck::cast_slice(&lookup_tables()),
            bytemuck::cast_slice(&inputs),
        ],
        numbers.len(),
    )
}

/// Chi-square tests in this module (Šidák-corrected together).
const FAMILY: usize = 24;
/// Samples per test.
const SAMPLES: usize = 200_000;

/// The GPU's samples of `params` from `wo` follow the CPU's pdf (chi-square over the
/// sphere), and each sampled direction's pdfs and f·|cos| in both transport modes are the
/// CPU's up to rounding. The shading normal leans off the geometric one, so that importance
/// transport's correction for it matters.
fn check(gpu: &GpuDevice, name: &str, params: &BsdfParams, wo: Vec3) {
    let n_g = Vec3::new(0.2, 0.3, 0.93).normalize();
    let n_s = Vec3::new(0.3, 0.25, 0.92).normalize();
    let config = Chi2Config {
        frame: Frame::from_z(n_g),
        sample_count: SAMPLES,
        ..Chi2Config::default()
    };
    // The numbers the harness would draw, in its order.
    let mut rng = Rng::new(config.seed, 0);
    let numbers: Vec<[f32; 3]> = (0..SAMPLES)
        .map(|_| {
            let (u_lobe, u) = (rng.uniform(), rng.uniform2());
            [u_lobe, u.x, u.y]
        })
        .collect();
    let samples = sample_on_gpu(gpu, (params, false), (n_g, n_s, wo), &numbers);
    let cpu = Bsdf::new(params, n_g, n_s, false);
    let glossy = |s: &ProbeOutput| s.valid[0] == 1 && s.wi[3].to_bits() != KIND_SPECULAR;
    let mut differing = 0;
    for s in samples.iter().filter(|s| glossy(s)) {
        let wi = Vec3::from_slice(&s.wi[..3]);
        let close = |a: f32, b: f32| (a - b).abs() <= 1e-4 * a.abs().max(b.abs()) + 1e-7;
        let same = |mode, gpu: &[f32; 4]| {
            let eval = cpu.eval_with(wo, wi, mode, Pdfs::Both);
            close(eval.pdf_fwd, gpu[3])
                && close(eval.pdf_rev, f32::from_bits(s.valid[1]))
                && (0..3).all(|k| close(eval.f_cos[k], gpu[k]))
        };
        let alike = same(TransportMode::Radiance, &s.f_cos)
            && same(TransportMode::Importance, &s.importance);
        differing += usize::from(!alike);
    }
    assert!(
        differing * 1000 <= SAMPLES,
        "{name}, wo = {wo}: {differing} samples' pdf or f·cos differ from the CPU's"
    );
    let mut next = samples.iter();
    let result = chi2_test(
        |_| {
            let s = next.next().expect("one sample per call");
            glossy(s).then(|| Vec3::from_slice(&s.wi[..3]))
        },
        |wi| f64::from(cpu.pdf(wo, wi)),
        &config,
        FAMILY,
    );
    assert!(result.passed, "{name}, wo = {wo}: {result:?}");
}

#[test]
fn gpu_bsdf_sampling_follows_the_cpu_pdf() {
    let Some(gpu) = device_or_skip() else { return };
    let base = BsdfParams {
        base_color: Vec3::new(0.8, 0.5, 0.3),
        metallic: 0.0,
        ..BsdfParams::default()
    };
    let materials = [
        (
            "plastic r=0.4",
            BsdfParams {
                roughness: 0.4,
                ..base
            },
        ),
        (
            "smooth coat over diffuse",
            BsdfParams {
                roughness: 0.0,
                ..base
            },
        ),
        (
            "gold r=0.3",
            BsdfParams {
                metallic: 1.0,
                roughness: 0.3,
                ..base
            },
        ),
        (
            "rough glass r=0.3",
            BsdfParams {
                transmission: 1.0,
                roughness: 0.3,
                thin_walled: false,
                ..base
            },
        ),
        (
            "rough sheet r=0.4",
            BsdfParams {
                transmission: 1.0,
                roughness: 0.4,
                thin_walled: true,
                ..base
            },
        ),
        (
            "mixture",
            BsdfParams {
                metallic: 0.3,
                transmission: 0.4,
                roughness: 0.5,
                ..base
            },
        ),
    ];
    let n_g = Vec3::new(0.2, 0.3, 0.93).normalize();
    let frame = Frame::from_z(n_g);
    for (name, params) in &materials {
        for (cos, back) in [(0.1, false), (0.6, false), (1.0, false), (0.5, true)] {
            if back && params.transmission == 0.0 {
                continue;
            }
            let sin = (1.0f32 - cos * cos).sqrt();
            let local = Vec3::new(sin * 0.6, sin * 0.8, if back { -cos } else { cos });
            check(&gpu, name, params, frame.to_world(local));
        }
    }
}
