//! Furnaces with stiff contents: inside a closed sphere that emits Le = 1 and reflects with
//! Lambertian albedo ρ = 1/2, the radiance is Le / (1 − ρ) = 2 everywhere, and stays 2 when
//! objects that absorb nothing (albedo 1: perfect and glossy mirrors of F0 = 1, glass, white
//! Lambertian surfaces) are put inside. Any leak (a ray escaping through a surface it started
//! on into an object's black interior) shows as a value below 2, any energy gain above it.

use std::ops::Range;

use glam::Vec3;
use vcm::Algorithm;
use vcm_scene::Material;

use super::harness::{self, ALL_BUT_LIGHT_TRACING, REGIONS, Setup};
use super::scenes::{Placement, SceneParts, camera_looking};
use crate::common;

/// The furnace's value Le / (1 − ρ).
const FURNACE_VALUE: f64 = 2.0;

/// The furnace wall: emits 1, reflects half.
fn wall_material() -> Material {
    Material {
        emission: Vec3::ONE,
        ..Material::diffuse("furnace", Vec3::splat(0.5))
    }
}

/// Solid (or `thin_walled`) glass of `roughness` and `ior`.
fn glass(roughness: f32, ior: f32, thin_walled: bool) -> Material {
    Material {
        metallic: 0.0,
        roughness,
        transmission: 1.0,
        ior,
        thin_walled,
        ..Material::default()
    }
}

/// A mirror (Schlick F0 = 1: reflects everything) of perceptual roughness `roughness`.
fn mirror(roughness: f32) -> Material {
    Material {
        metallic: 1.0,
        roughness,
        ..Material::default()
    }
}

/// The camera of most furnaces: inside, looking at the object at the center.
fn center_view() -> vcm_scene::Camera {
    common::camera(Vec3::new(0.0, 0.0, 0.85), 1.0)
}

/// The unit furnace sphere (320 inward triangles) around the origin, seen by `camera`.
fn furnace(camera: vcm_scene::Camera) -> SceneParts {
    let mut parts = SceneParts::new(camera);
    let wall = parts.material(wall_material());
    let (positions, triangles) = common::inward_icosphere(2);
    parts.mesh(&positions, &triangles, wall);
    parts
}

/// Adds a sphere of `radius` around the origin, facing outward, made of `material`.
fn add_sphere(parts: &mut SceneParts, radius: f32, material: Material) {
    let material = parts.material(material);
    let (positions, triangles) = vcm_scene::shapes::icosphere(2);
    let positions: Vec<Vec3> = positions.into_iter().map(|p| p * radius).collect();
    parts.mesh(&positions, &triangles, material);
}

/// Renders `parts` with each of `algorithms` over the frames `iterations` and asserts the
/// furnace value in every region (nothing may be dropped). Regions, not pixels: behind
/// glass and along mirror chains a few long paths carry much of a pixel's value, a tail
/// that one pixel's 100 samples measure too coarsely for a standard error.
fn assert_furnace_value(
    parts: &SceneParts,
    algorithms: &[Option<Algorithm>],
    setup: Setup,
    placement: Placement,
    iterations: Range<u32>,
    label: &str,
) {
    for &algorithm in algorithms {
        let scene = parts.build(placement);
        let mut integrator = harness::integrator(scene, algorithm, setup);
        let series = common::region_means_from(integrator.as_mut(), iterations.clone(), REGIONS);
        let label = format!("{label}, {}", harness::name(algorithm));
        harness::assert_regions_equal(&series, FURNACE_VALUE, &label);
    }
}

/// With 256 light paths a frame, merging within 10% of the sphere finds about one light
/// vertex per query; within a distance r of a point a sphere has area π r² exactly
/// (Archimedes), so the large radius adds no bias on the spheres here.
fn setup(seed: u64) -> Setup {
    Setup::new(seed, 0.1)
}

#[test]
fn glass_of_ior_1_0001_and_3_keeps_the_furnace_value() {
    for ior in [1.0001, 3.0] {
        let mut parts = furnace(center_view());
        add_sphere(&mut parts, 0.35, glass(0.0, ior, false));
        let label = format!("glass of IOR {ior}");
        let frames = 0..100;
        assert_furnace_value(
            &parts,
            &ALL_BUT_LIGHT_TRACING,
            setup(11),
            Placement::IDENTITY,
            frames,
            &label,
        );
    }
}

/// Glass of roughness 0.01 (GGX α = 10⁻⁴, the sharpest rough lobe), solid and thin-walled:
/// refraction through lobes that narrow loses and gains nothing. PPM is left out for the
/// reason given below for glossy mirrors.
#[test]
fn polished_glass_keeps_the_furnace_value() {
    for thin_walled in [false, true] {
        let mut parts = furnace(center_view());
        add_sphere(&mut parts, 0.35, glass(0.01, 1.5, thin_walled));
        let label = format!("polished glass, thin-walled {thin_walled}");
        let algorithms = [
            None,
            Some(Algorithm::Bpt),
            Some(Algorithm::Bpm),
            Some(Algorithm::Vcm),
        ];
        assert_furnace_value(
            &parts,
            &algorithms,
            setup(11),
            Placement::IDENTITY,
            0..100,
            &label,
        );
    }
}

#[test]
fn near_specular_and_glossy_mirrors_keep_the_furnace_value() {
    // Roughness 0 is a perfect mirror; 0.01 (α = 10⁻⁴, the floor every roughness below
    // it is raised to) is the sharpest GGX lobe, 0.1 (α = 10⁻²) a glossy one.
    let mut parts = furnace(center_view());
    add_sphere(&mut parts, 0.35, mirror(0.0));
    let frames = 0..100;
    assert_furnace_value(
        &parts,
        &ALL_BUT_LIGHT_TRACING,
        setup(12),
        Placement::IDENTITY,
        frames,
        "perfect mirror",
    );
    // Photon mapping merges where the camera first meets the glossy mirror, through a lobe
    // 10⁻⁸ … 10⁻⁴ sr wide that the few light vertices near a query almost never fall in: an
    // unbiased estimate whose mass sits in samples 100 frames do not draw. BPM: see below.
    let glossy = [None, Some(Algorithm::Bpt), Some(Algorithm::Vcm)];
    for roughness in GLOSSY {
        let mut parts = furnace(center_view());
        add_sphere(&mut parts, 0.35, mirror(roughness));
        let label = format!("mirror of roughness {roughness}");
        assert_furnace_value(
            &parts,
            &glossy,
            setup(12),
            Placement::IDENTITY,
            0..100,
            &label,
        );
    }
}

/// Perceptual roughness of the sharpest GGX lobe (α = 10⁻⁴) and of a glossy one (α = 10⁻²).
const GLOSSY: [f32; 2] = [0.01, 0.1];

/// Half of the value seen on the mirror is the wall's emission reflected once. Bidirectional
/// photon mapping once found it only by merging at the mirror, like PPM above (a light vertex
/// has to fall into the lobe), and 100 frames gave 1.41–1.48 instead of 2 at every merge
/// radius. It now also counts the camera path hitting the wall, which the mirror's own
/// sampling finds, weighted against the merges.
#[test]
fn bidirectional_photon_mapping_on_glossy_mirrors_keeps_the_furnace_value() {
    for roughness in GLOSSY {
        let mut parts = furnace(center_view());
        add_sphere(&mut parts, 0.35, mirror(roughness));
        let label = format!("mirror of roughness {roughness}");
        let bpm = [Some(Algorithm::Bpm)];
        assert_furnace_value(&parts, &bpm, setup(12), Placement::IDENTITY, 0..100, &label);
    }
}

#[test]
fn a_camera_grazing_the_wall_sees_the_furnace_value() {
    // The camera sits 10⁻⁶ above a facet of the wall near one corner and looks across it
    // with a field of view of 4.5·10⁻⁵ rad, 5·10⁻⁶ … 5·10⁻⁵ rad below the facet's plane:
    // every pixel meets the facet at cosines of 5·10⁻⁶ … 5·10⁻⁵, 0.02 to 0.2 away. Light
    // tracing is left out: the patch it sees is 10⁻⁶ of the facet's area.
    let (positions, triangles) = common::inward_icosphere(2);
    let [a, b, c] = triangles[0].map(|i| positions[i as usize]);
    let normal = (b - a).cross(c - a).normalize();
    let across = ((b + c) * 0.5 - a).normalize();
    let down = 2.75e-5f32;
    let forward = (across - normal * down).normalize();
    let position = a + ((a + b + c) / 3.0 - a) * 0.05 + normal * 1e-6;
    let camera = camera_looking(position, forward, normal, 4.5e-5);
    let parts = furnace(camera);
    let setup = setup(13);
    assert_furnace_value(
        &parts,
        &ALL_BUT_LIGHT_TRACING,
        setup,
        Placement::IDENTITY,
        0..100,
        "grazing camera",
    );
}

/// Each triangle of `triangles` split into three around a point 10⁻⁶ of the way from its
/// first edge's midpoint to its third corner (one sliver, two halves), plus two degenerate
/// triangles on that edge: a repeated corner and a collinear midpoint.
fn slivered(positions: &[Vec3], triangles: &[[u32; 3]]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut out_positions = positions.to_vec();
    let mut out = Vec::new();
    for &[a, b, c] in triangles {
        let [pa, pb, pc] = [a, b, c].map(|i| positions[i as usize]);
        let mid = (pa + pb) * 0.5;
        let (m, p) = (out_positions.len() as u32, out_positions.len() as u32 + 1);
        out_positions.extend([mid, mid + (pc - mid) * 1e-6]);
        out.extend([[a, b, p], [b, c, p], [c, a, p], [a, a, b], [a, m, b]]);
    }
    (out_positions, out)
}

#[test]
fn coincident_degenerate_and_sliver_triangles_keep_the_furnace_value() {
    // The wall is made of slivers and zero-area triangles; the object in the middle is two
    // coincident white spheres, one of them triangulated into slivers, which round their
    // shared surface differently: a ray leaving one must not stop on the other's black back.
    let mut parts = SceneParts::new(center_view());
    let wall = parts.material(wall_material());
    let (positions, triangles) = common::inward_icosphere(2);
    let (positions, triangles) = slivered(&positions, &triangles);
    parts.mesh(&positions, &triangles, wall);
    let white = parts.material(Material::diffuse("white", Vec3::ONE));
    let (positions, triangles) = vcm_scene::shapes::icosphere(2);
    let positions: Vec<Vec3> = positions.into_iter().map(|p| p * 0.35).collect();
    parts.mesh(&positions, &triangles, white);
    let (positions, triangles) = slivered(&positions, &triangles);
    parts.mesh(&positions, &triangles, white);
    assert_furnace_value(
        &parts,
        &ALL_BUT_LIGHT_TRACING,
        setup(14),
        Placement::IDENTITY,
        0..100,
        "slivers",
    );
}

/// Adds a closed box between corners `lo` and `hi` (faces outward) made of `material`.
fn add_box(parts: &mut SceneParts, lo: Vec3, hi: Vec3, material: u32) {
    let corner =
        |i: u32| Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo);
    let positions: Vec<Vec3> = (0..8).map(corner).collect();
    // Each face counter-clockwise seen from outside: -z, +z, -y, +y, -x, +x.
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let triangles: Vec<[u32; 3]> = faces
        .iter()
        .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
        .collect();
    parts.mesh(&positions, &triangles, material);
}

#[test]
fn hundred_bounce_mirror_chains_keep_the_furnace_value() {
    // Two mirror slabs 0.02 apart; the camera between them looks 14° off their normal, so
    // its rays bounce 70 to 170 times before leaving the gap. With glossy mirrors every one
    // of those vertices is connected and merged, and its MIS quantities carried on.
    // Russian roulette leaves these lossless chains alone (continuation probability 1 up
    // to 1024 segments): with a cap of 0.95, 1 path in 2000 left a 150-bounce chain with a
    // weight of 2000, and 100 frames saw the mean of that tail only from below. With the
    // cap from 256 segments on, the glossy chains, whose directions wander towards the
    // normal and bounce longer, still read 1.975–1.985 ± 0.005 after 400 frames.
    for roughness in [0.0, 0.04] {
        let position = Vec3::ZERO;
        let forward = Vec3::new(0.25, 0.0, 1.0).normalize();
        let mut parts = furnace(camera_looking(position, forward, Vec3::Y, 0.2));
        let material = parts.material(mirror(roughness));
        add_box(
            &mut parts,
            Vec3::new(-0.5, -0.5, 0.01),
            Vec3::new(0.5, 0.5, 0.03),
            material,
        );
        add_box(
            &mut parts,
            Vec3::new(-0.5, -0.5, -0.03),
            Vec3::new(0.5, 0.5, -0.01),
            material,
        );
        for algorithm in ALL_BUT_LIGHT_TRACING {
            // Merging within 0.1 of the scene's radius (the other furnaces') reaches five
            // times across the gap and past its ends, where the light vertices of each path
            // length lie unevenly: a blur that is not zero even here (VCM's lower regions
            // read 1.55 ± 0.09 once a light path's first vertex stopped merging). At 0.01
            // merging's blur is below the noise.
            let setup = Setup::new(15, 0.01);
            let mut integrator =
                harness::integrator(parts.build(Placement::IDENTITY), algorithm, setup);
            let series = common::region_means(integrator.as_mut(), 100, REGIONS);
            let label = format!(
                "mirror chain, roughness {roughness}, {}",
                harness::name(algorithm)
            );
            // Photon mapping merges at the first glossy vertex, where the light vertices
            // almost never fall in the lobe (see the glossy mirrors above): bounded only.
            if roughness > 0.0 && algorithm == Some(Algorithm::Ppm) {
                harness::assert_regions_at_most(&series, FURNACE_VALUE, &label);
            } else {
                harness::assert_regions_equal(&series, FURNACE_VALUE, &label);
            }
        }
    }
}

#[test]
fn merging_after_a_billion_iterations_keeps_the_furnace_value() {
    let parts = furnace(center_view());
    let late = 1_000_000_000..1_000_000_100;
    // The default α shrinks the radius 13-fold by then: photon mapping still finds a few
    // hundred light vertices in 100 frames.
    let photon_mapping = [Some(Algorithm::Ppm), Some(Algorithm::Bpm)];
    assert_furnace_value(
        &parts,
        &photon_mapping,
        setup(16),
        Placement::IDENTITY,
        late.clone(),
        "late",
    );
    // α = 1/4 shrinks it 2400-fold (to 4·10⁻⁵ of the scene, 4·10⁻⁹ at scale 10⁻⁴): VCM then
    // weights merging down to nothing, through MIS factors of 10⁻¹⁸ and 10¹⁸.
    let steep = Setup {
        alpha: 0.25,
        ..setup(17)
    };
    for placement in [Placement::IDENTITY, Placement::scaled(1e-4)] {
        let label = format!("steep, {placement:?}");
        assert_furnace_value(
            &parts,
            &[Some(Algorithm::Vcm)],
            steep,
            placement,
            late.clone(),
            &label,
        );
    }
}
