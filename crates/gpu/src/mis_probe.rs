//! The MIS partition of unity on the GPU's weights: for random paths from the camera over
//! glossy and diffuse surfaces to an area light (`vcm::mis_paths`), bidir.wgsl's subpath
//! updates and weights (`shaders/mis_probe.wgsl`, with bsdf.wgsl's pdfs) give every
//! technique of BPT, BPM and VCM a weight; they sum to one, and each is the CPU's.
//! Skipped without a graphics adapter unless `VCM_REQUIRE_GPU=1`.

use bytemuck::{Pod, Zeroable};
use vcm::Algorithm;
use vcm::mis_paths::{LIGHT_AREA, LIGHT_PATHS, MisTestPath, PIXEL_AREA};
use vcm_scene::bsdf::Lobes;
use vcm_scene::sampling::Rng;
use vcm_traversal_wgpu::device_or_skip;

use crate::probe::run_probe;
use crate::scene_data::{lookup_tables, pack_material};
use crate::shader::{BIDIR_WGSL, BSDF_WGSL, CACHE_WGSL, SAMPLER_WGSL, host_constants};

const PROBE_WGSL: &str = include_str!("../shaders/mis_probe.wgsl");

/// `MAX_VERTICES` of `mis_probe.wgsl`.
const MAX_VERTICES: usize = 7;
/// `MAX_WEIGHTS` of `mis_probe.wgsl`.
const MAX_WEIGHTS: usize = 15;

/// `ProbePath` of `mis_probe.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ProbePath {
    points: [[f32; 4]; MAX_VERTICES],
    normals: [[f32; 4]; MAX_VERTICES],
    camera_forward: [f32; 3],
    k: u32,
    factors: [f32; 4],
    first_material: u32,
    padding: [u32; 3],
}

/// `ProbeWeights` of `mis_probe.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
struct ProbeWeights {
    weights: [f32; MAX_WEIGHTS],
    count: u32,
}

/// The probe's source: what bidir.wgsl needs before it, bidir.wgsl, the probe.
fn probe_source() -> String {
    format!(
        "{}{SAMPLER_WGSL}\n{BSDF_WGSL}\n{CACHE_WGSL}\n{BIDIR_WGSL}\n\
         const LIGHT_AREA: f32 = {LIGHT_AREA:?}f;\nconst PIXEL_AREA: f32 = {PIXEL_AREA:?}f;\n\
         const LIGHT_PATHS: f32 = {LIGHT_PATHS:?}f;\n{PROBE_WGSL}",
        host_constants()
    )
}

#[test]
fn the_gpu_weights_of_every_technique_sum_to_one_and_are_the_cpus() {
    let Some(gpu) = device_or_skip() else { return };
    let algorithms = [Algorithm::Bpt, Algorithm::Bpm, Algorithm::Vcm];
    let mut rng = Rng::new(2025, 0);
    let paths: Vec<MisTestPath> = (2..=6)
        .flat_map(|k| (0..200).map(move |_| k))
        .map(|k| MisTestPath::random(k, &mut rng))
        .collect();
    let mut materials = Vec::new();
    let mut queries = Vec::new();
    for path in &paths {
        let first_material = materials.len() as u32;
        let inner = path.materials.iter().flatten();
        materials
            .extend(inner.map(|params| pack_material(Some(&Lobes::new(params).flat()), false)));
        let mut query = ProbePath {
            camera_forward: path.camera_forward.to_array(),
            k: path.k() as u32,
            first_material,
            ..ProbePath::zeroed()
        };
        for (j, (p, n)) in path.points.iter().zip(&path.normals).enumerate() {
            query.points[j] = p.extend(0.0).to_array();
            query.normals[j] = n.extend(0.0).to_array();
        }
        for algorithm in algorithms {
            let factors = MisTestPath::factors(algorithm);
            queries.push(ProbePath { factors, ..query });
        }
    }
    let answers: Vec<ProbeWeights> = run_probe(
        &gpu,
        (probe_source(), "probe_mis"),
        &[
            bytemuck::cast_slice(&materials),
            bytemuck::cast_slice(&lookup_tables()),
            bytemuck::cast_slice(&queries),
        ],
        queries.len(),
    );
    let cases = paths
        .iter()
        .flat_map(|path| algorithms.map(|algorithm| (path, algorithm)));
    for ((path, algorithm), answer) in cases.zip(&answers) {
        let k = path.k();
        let weights = &answer.weights[..answer.count as usize];
        let sum: f32 = weights.iter().sum();
        assert!(
            (sum - 1.0).abs() < 1e-3,
            "{algorithm:?}, {k} segments: the GPU's weights {weights:?} sum to {sum}"
        );
        assert!(weights.iter().all(|w| (0.0..=1.0).contains(w)));
        let cpu = path.weights(algorithm);
        let close = cpu.len() == weights.len()
            && cpu.iter().zip(weights).all(|(a, b)| (a - b).abs() <= 1e-4);
        assert!(
            close,
            "{algorithm:?}, {k} segments: the GPU's weights {weights:?}, the CPU's {cpu:?}"
        );
    }
}

#[test]
fn the_probe_validates() {
    let validated = vcm_traversal_wgpu::shader::validate_module(&probe_source(), &["probe_mis"]);
    if let Err(error) = validated {
        panic!("{error}");
    }
}
