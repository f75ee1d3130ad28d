//! Scale invariance: a room lit by an area light, rendered at scales 10⁻⁴, 10⁴ and 10⁵ and
//! moved thousands of its sizes away from the origin, gives the image of scale 1 with every
//! algorithm (each compared with itself, so that the radius bias of photon mapping, relative
//! to the scene's size, is the same on both sides).

use glam::Vec3;
use vcm_scene::Material;

use super::harness::{self, REGIONS, Setup};
use super::scenes::{Placement, SceneParts, emitter};
use crate::common;
use crate::common::EVERY_ALGORITHM;

const FRAMES: u32 = 200;

/// Floor, back and left walls, a floating double-sided occluder and a ceiling light facing
/// down, seen from the open side.
fn room() -> SceneParts {
    let mut parts = SceneParts::new(common::camera(Vec3::new(0.0, 0.5, 2.5), 0.9));
    let white = parts.material(Material::diffuse("white", Vec3::splat(0.7)));
    let grey = parts.material(Material::diffuse("grey", Vec3::splat(0.5)));
    let red = parts.material(Material::diffuse("red", Vec3::new(0.6, 0.2, 0.2)));
    let green = parts.material(Material {
        double_sided: true,
        ..Material::diffuse("green", Vec3::new(0.3, 0.6, 0.3))
    });
    let light = parts.material(emitter(5.0));
    let v = Vec3::new;
    parts.quad(
        [
            v(-1.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(1.0, 0.0, -1.0),
            v(-1.0, 0.0, -1.0),
        ],
        white,
    );
    parts.quad(
        [
            v(-1.0, 0.0, -1.0),
            v(1.0, 0.0, -1.0),
            v(1.0, 1.2, -1.0),
            v(-1.0, 1.2, -1.0),
        ],
        grey,
    );
    parts.quad(
        [
            v(-1.0, 0.0, 1.0),
            v(-1.0, 0.0, -1.0),
            v(-1.0, 1.2, -1.0),
            v(-1.0, 1.2, 1.0),
        ],
        red,
    );
    parts.quad(
        [
            v(-0.2, 0.5, 0.2),
            v(0.4, 0.5, 0.2),
            v(0.4, 0.5, -0.4),
            v(-0.2, 0.5, -0.4),
        ],
        green,
    );
    parts.quad(
        [
            v(-0.3, 1.0, -0.3),
            v(0.3, 1.0, -0.3),
            v(0.3, 1.0, 0.3),
            v(-0.3, 1.0, 0.3),
        ],
        light,
    );
    parts
}

#[test]
fn every_algorithm_renders_the_same_image_at_any_scale_and_place() {
    let placements = [
        Placement::scaled(1e-4),
        Placement::scaled(1e4),
        Placement::scaled(1e5),
        Placement {
            scale: 1.0,
            offset: Vec3::new(4e3, -3e3, 2e3),
        },
    ];
    let parts = room();
    // Merging within 5% of the scene: enough light vertices per query that 200 frames
    // measure the spread; the bias it brings is the same at every scale.
    let render = |placement, algorithm, seed| {
        let scene = parts.build(placement);
        let mut integrator = harness::integrator(scene, algorithm, Setup::new(seed, 0.05));
        common::region_means(integrator.as_mut(), FRAMES, REGIONS)
    };
    for algorithm in EVERY_ALGORITHM {
        let reference = render(Placement::IDENTITY, algorithm, 1);
        assert!(reference.image_mean > 0.0);
        for placement in placements {
            let moved = render(placement, algorithm, 2);
            let label = format!("{}, {placement:?}", harness::name(algorithm));
            harness::assert_regions_agree(&moved, &reference, &label);
        }
    }
}
