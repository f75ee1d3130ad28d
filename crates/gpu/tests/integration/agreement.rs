//! The GPU's path tracer and bidirectional algorithms (light tracing, BPT, PPM, BPM, VCM) draw
//! the CPU's numbers for the same paths and shade them with the same operations (picking the
//! same cached light vertices, merging with the same ones in the same order): the images agree pixel by pixel up to rounding, except
//! where a rounding difference flips one of a path's decisions (a lobe, roulette, a hit at a
//! triangle's edge, the pixel a light vertex projects to) and that path goes elsewhere.

use glam::Vec3;
use vcm::{Algorithm, PtSettings, VcmSettings};
use vcm_gpu::GpuBidirectional;
use vcm_scene::sampling::SampleSequence;

use serde_json::json;

use crate::common::{
    cpu_bidir_image, cpu_image, gpu, gpu_bidir_image, gpu_image, lit_khronos_model, scene,
    scene_variant, scene_variant_with,
};

/// The share of pixels whose channels all agree within `RELATIVE` (or `ABSOLUTE` near
/// black) in two images of the same paths.
fn share_alike(cpu: &[Vec3], gpu: &[Vec3]) -> f64 {
    let close = |a: f32, b: f32| (a - b).abs() <= ABSOLUTE.max(RELATIVE * a.abs().max(b.abs()));
    let alike = cpu
        .iter()
        .zip(gpu)
        .filter(|(a, b)| close(a.x, b.x) && close(a.y, b.y) && close(a.z, b.z))
        .count();
    alike as f64 / cpu.len() as f64
}

const RELATIVE: f32 = 1e-4;
const ABSOLUTE: f32 = 1e-6;

/// Every scene of `scenes/`, both sample sequences, several samples per pixel per frame and
/// a path length limit: at least 99% of the pixels agree within rounding, i.e. all of a
/// pixel's paths followed the CPU's (on lavapipe 0–7 pixels of 1,728 differ per scene, paths
/// that a rounding difference sent past an edge).
///
/// On `large` a few light paths store another number of vertices than on the CPU (its long
/// paths meet many edges), which moves every later vertex of their iteration's cache: BPT's
/// and VCM's camera vertices, which pick vertices from the whole cache by index, then
/// connect to others (on lavapipe 39% of BPT's pixels agree), and BPM's merge with other
/// vertices around those paths (97%). There those three are compared in expectation.
#[test]
fn gpu_paths_are_the_cpu_paths() {
    let Some(gpu) = gpu() else { return };
    let per_path = Cache::PathByPath;
    let cases = [
        ("cornell-box", SampleSequence::Sobol, None, 2, per_path),
        (
            "cornell-indirect",
            SampleSequence::Independent,
            None,
            1,
            per_path,
        ),
        ("cornell-specular", SampleSequence::Sobol, None, 2, per_path),
        (
            "cornell-specular-close",
            SampleSequence::Sobol,
            Some(6),
            1,
            per_path,
        ),
        (
            "cornell-water",
            SampleSequence::Independent,
            None,
            2,
            per_path,
        ),
        (
            "large",
            SampleSequence::Sobol,
            None,
            1,
            Cache::InExpectation,
        ),
    ];
    for (name, sequence, max_depth, samples, cache) in cases {
        let settings = (sequence, max_depth, samples);
        check_agreement_with(&gpu, name, &scene(name), settings, cache);
    }
}

/// With fewer or more light paths than pixels the light pass's dispatches cover whichever
/// are more, each invocation following a pixel's camera sample, a light path, or both; the
/// paths are still the CPU's (light tracing, BPT and VCM, 98% of the pixels as above).
#[test]
fn other_numbers_of_light_paths_follow_the_cpu_paths() {
    let Some(gpu) = gpu() else { return };
    let scene = scene("cornell-water");
    let (width, height, samples) = (48, 36, 2);
    for light_paths_per_pixel in [0.5, 2.5] {
        for algorithm in [Algorithm::LightTracing, Algorithm::Bpt, Algorithm::Vcm] {
            let settings = VcmSettings {
                seed: 11,
                light_paths_per_pixel,
                ..VcmSettings::new(algorithm, width, height)
            };
            let cpu = cpu_bidir_image(&scene, settings, 2, samples);
            let on_gpu = gpu_bidir_image(&gpu, &scene, settings, 2, samples);
            let what = format!("{light_paths_per_pixel} per pixel, {}", algorithm.name());
            assert_alike(&what, &cpu, &on_gpu, 0.98);
        }
    }
}

/// How the images of BPT, BPM and VCM — whose camera vertices read many light paths' cached
/// vertices — are compared with the CPU's.
#[derive(Clone, Copy, PartialEq)]
enum Cache {
    /// Pixel by pixel, as the others.
    PathByPath,
    /// The images' sums within 1% (they agree to 3·10⁻⁴ on `large`).
    InExpectation,
}

/// The lobes `scenes/` leaves out: on `cornell-specular`, a rough (GGX) conductor and a
/// rough thick glass sphere; then a rough thin-walled sheet, a plastic (diffuse under a GGX
/// layer, KHR_materials_specular) and a double-sided wall seen from behind; and absorbing
/// water (KHR_materials_volume attenuation) in `cornell-water`.
#[test]
fn gpu_paths_are_the_cpu_paths_on_every_lobe() {
    let Some(gpu) = gpu() else { return };
    let rough = scene_variant("cornell-specular", |g| {
        let materials = g["materials"].as_array_mut().unwrap();
        materials[4]["pbrMetallicRoughness"]["roughnessFactor"] = json!(0.3);
        materials[5]["pbrMetallicRoughness"]["roughnessFactor"] = json!(0.2);
    });
    check_agreement(
        &gpu,
        "rough cornell-specular",
        &rough,
        (SampleSequence::Sobol, None, 2),
    );
    let thin = scene_variant("cornell-specular", |g| {
        let materials = g["materials"].as_array_mut().unwrap();
        materials[1]["doubleSided"] = json!(true);
        materials[4] = json!({
            "name": "plastic",
            "pbrMetallicRoughness": {
                "baseColorFactor": [0.2, 0.4, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4
            }
        });
        let glass = &mut materials[5];
        glass["pbrMetallicRoughness"]["roughnessFactor"] = json!(0.3);
        glass["extensions"]
            .as_object_mut()
            .unwrap()
            .remove("KHR_materials_volume");
    });
    check_agreement(
        &gpu,
        "thin cornell-specular",
        &thin,
        (SampleSequence::Independent, None, 2),
    );
    let murky = scene_variant("cornell-water", |g| {
        let water = &mut g["materials"].as_array_mut().unwrap()[4];
        water["extensions"]["KHR_materials_volume"] = json!({
            "thicknessFactor": 1.0, "attenuationColor": [0.4, 0.7, 0.9], "attenuationDistance": 0.5
        });
    });
    assert!(murky.features.absorbing_volumes);
    check_agreement(
        &gpu,
        "murky cornell-water",
        &murky,
        (SampleSequence::Sobol, None, 2),
    );
}

/// Every kind of light: `cornell-specular` with a point light, a spot light, a directional
/// light through its open front and a constant environment beside its area light; then
/// with an environment map.
#[test]
fn gpu_paths_are_the_cpu_paths_under_every_light() {
    let Some(gpu) = gpu() else { return };
    // A quarter turn about x: the spot light's −z looks down.
    let half = std::f64::consts::FRAC_1_SQRT_2;
    let lit = scene_variant("cornell-specular", |g| {
        let used = g["extensionsUsed"].as_array_mut().unwrap();
        used.extend([json!("KHR_lights_punctual"), json!("VCM_environment")]);
        g["extensions"] = json!({
            "KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1.0, 0.8, 0.6], "intensity": 0.8},
                {"type": "spot", "color": [0.6, 0.8, 1.0], "intensity": 3.0,
                 "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}},
                {"type": "directional", "color": [1.0, 1.0, 1.0], "intensity": 0.7}
            ]},
            "VCM_environment": {"color": [0.3, 0.4, 0.5], "strength": 0.5}
        });
        let nodes = g["nodes"].as_array_mut().unwrap();
        let first = nodes.len();
        nodes.extend([
            json!({"translation": [-0.4, 0.3, 0.2], "extensions": {"KHR_lights_punctual": {"light": 0}}}),
            json!({"translation": [0.4, 0.9, 0.2], "rotation": [-half, 0.0, 0.0, half],
                   "extensions": {"KHR_lights_punctual": {"light": 1}}}),
            json!({"rotation": [-0.2, 0.1, 0.0, 0.9746794],
                   "extensions": {"KHR_lights_punctual": {"light": 2}}}),
        ]);
        let roots = g["scenes"][0]["nodes"].as_array_mut().unwrap();
        roots.extend((first..first + 3).map(|n| json!(n)));
    });
    let counts = lit.features.lights;
    assert_eq!(
        (
            counts.point,
            counts.spot,
            counts.directional,
            counts.environment
        ),
        (1, 1, 1, 1)
    );
    check_agreement(
        &gpu,
        "lit cornell-specular",
        &lit,
        (SampleSequence::Sobol, None, 2),
    );

    // An environment map: 4 × 2 texels of different colours (Radiance RGBE, uncompressed),
    // one black, seen through the box's open front and sampled by its texels' weights.
    let mut sky = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n".to_vec();
    for rgbe in [
        [128, 64, 32, 130],
        [32, 64, 128, 129],
        [0, 0, 0, 0],
        [128, 128, 128, 128],
        [64, 128, 64, 131],
        [128, 32, 32, 129],
        [96, 96, 128, 130],
        [128, 128, 64, 127],
    ] {
        sky.extend(rgbe);
    }
    let mapped = scene_variant_with(
        "cornell-specular",
        |g| {
            let used = g["extensionsUsed"].as_array_mut().unwrap();
            used.push(json!("VCM_environment"));
            g["extensions"] = json!({"VCM_environment": {"image": "sky.hdr", "strength": 0.8}});
        },
        &[("sky.hdr", &sky)],
    );
    assert_eq!(mapped.features.lights.environment, 1);
    let settings = (SampleSequence::Independent, None, 2);
    check_agreement(&gpu, "mapped cornell-specular", &mapped, settings);
}

/// Textured models: base colour, metallic-roughness, normal and emissive textures, authored
/// tangents with mirrored texture coordinates (alpha masks, which need the traversal's mask
/// test, are tested from the root package: `gpu_shading_tests_alpha_masks_as_the_cpu_does`) (`../shared/scenes/khronos-samples/`, lit by a
/// point light and a sky). The GPU scales texture coordinates in f32 where the CPU uses f64,
/// so a texel lookup may differ in its last bits; the pixels still agree within 10⁻⁴.
#[test]
fn gpu_paths_are_the_cpu_paths_on_textured_models() {
    let Some(gpu) = gpu() else { return };
    for file in [
        "WaterBottle/glTF/WaterBottle.gltf",
        "Avocado/glTF/Avocado.gltf",
        "NormalTangentMirrorTest/glTF/NormalTangentMirrorTest.gltf",
    ] {
        let scene = lit_khronos_model(file);
        check_agreement(&gpu, file, &scene, (SampleSequence::Sobol, None, 2));
    }
}

/// Renders `scene` with path tracing and every bidirectional algorithm on the CPU and the GPU
/// with `(sequence, max_depth, samples per frame)` and checks what
/// [`gpu_paths_are_the_cpu_paths`] says of each pair (of the bidirectional algorithms, 98% of
/// the pixels).
fn check_agreement(
    gpu: &std::sync::Arc<vcm_traversal_wgpu::GpuDevice>,
    name: &str,
    scene: &std::sync::Arc<vcm_scene::Scene>,
    settings: (SampleSequence, Option<u32>, u32),
) {
    check_agreement_with(gpu, name, scene, settings, Cache::PathByPath);
}

/// [`check_agreement`], with BPT, BPM and VCM compared as `cache` says.
fn check_agreement_with(
    gpu: &std::sync::Arc<vcm_traversal_wgpu::GpuDevice>,
    name: &str,
    scene: &std::sync::Arc<vcm_scene::Scene>,
    (sequence, max_depth, samples): (SampleSequence, Option<u32>, u32),
    cache: Cache,
) {
    let (width, height, seed, frames) = (48, 36, 11, 4 / samples);
    let settings = PtSettings {
        seed,
        sequence,
        max_depth,
        ..PtSettings::new(width, height)
    };
    let cpu = cpu_image(scene, settings, frames, samples);
    let on_gpu = gpu_image(gpu, scene, settings, frames, samples);
    assert_alike(&format!("{name}, path tracing"), &cpu, &on_gpu, 0.99);
    for algorithm in GpuBidirectional::ALGORITHMS {
        let settings = VcmSettings {
            seed,
            sequence,
            max_depth,
            ..VcmSettings::new(algorithm, width, height)
        };
        let cpu = cpu_bidir_image(scene, settings, frames, samples);
        let on_gpu = gpu_bidir_image(gpu, scene, settings, frames, samples);
        let what = format!("{name}, {}", algorithm.name());
        let reads_many = [Algorithm::Bpt, Algorithm::Bpm, Algorithm::Vcm].contains(&algorithm);
        if reads_many && cache == Cache::InExpectation {
            let sum = |image: &[Vec3]| {
                image
                    .iter()
                    .map(|p| f64::from(p.element_sum()))
                    .sum::<f64>()
            };
            let (a, b) = (sum(&cpu), sum(&on_gpu));
            assert!((a - b).abs() <= 0.01 * a, "{what}: sums {a} and {b}");
        } else {
            // A light path's splats reach as many pixels as it has vertices, and camera
            // vertices connect to and merge with light vertices: a path that a rounding
            // difference sends elsewhere changes several pixels (on lavapipe up to 15 of
            // 1,728 on `large` for light tracing, against 7 for path tracing).
            assert_alike(&what, &cpu, &on_gpu, 0.98);
        }
    }
}

/// At least the share `least` of the pixels of `cpu` and `gpu` agree within rounding.
fn assert_alike(what: &str, cpu: &[Vec3], gpu: &[Vec3], least: f64) {
    let alike = share_alike(cpu, gpu);
    assert!(
        alike >= least,
        "{what}: {:.2}% of the pixels agree",
        100.0 * alike
    );
}
