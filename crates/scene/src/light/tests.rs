//! Light sampling tests: Monte Carlo estimates against closed forms, with tolerances of four
//! standard errors of the estimator (fixed seeds).

use glam::{Vec2, Vec3};

use super::*;
use crate::material::AlphaMask;
use crate::sampling::{Rng, Sampler};
use crate::texture::{ColorEncoding, TextureRef};

/// Mean and standard error of `n` samples of `f`.
fn estimate(n: usize, seed: u64, mut f: impl FnMut(&mut Rng) -> f64) -> (f64, f64) {
    let mut rng = Rng::new(seed, 0);
    let (mut sum, mut sum_sq) = (0.0, 0.0);
    for _ in 0..n {
        let x = f(&mut rng);
        sum += x;
        sum_sq += x * x;
    }
    let mean = sum / n as f64;
    let variance = (sum_sq / n as f64 - mean * mean).max(0.0);
    (mean, (variance / n as f64).sqrt())
}

fn assert_close(what: &str, (mean, stderr): (f64, f64), expected: f64) {
    let tolerance = 4.0 * stderr + 1e-9 * expected.abs();
    assert!(
        (mean - expected).abs() <= tolerance,
        "{what}: estimate {mean} ± {stderr}, expected {expected}"
    );
}

fn ceiling_triangle(radiance: Vec3) -> AreaLight {
    // In the plane z = 1, wound clockwise seen from above: its front face looks down (-Z).
    let corners = [
        Vec3::new(-0.5, -0.3, 1.0),
        Vec3::new(0.2, 0.6, 1.0),
        Vec3::new(0.7, -0.4, 1.0),
    ];
    let normal = (corners[1] - corners[0])
        .cross(corners[2] - corners[0])
        .normalize();
    assert!(normal.z < 0.0);
    AreaLight {
        triangle: 0,
        corners,
        uvs: [Vec2::ZERO; 3],
        normal,
        area: 0.5
            * (corners[1] - corners[0])
                .cross(corners[2] - corners[0])
                .length(),
        emission: radiance,
        texture: None,
        cut_out: None,
    }
}

/// Irradiance at the origin (normal +Z) from a uniform Lambertian polygon of radiance 1
/// (Lambert's formula: E = ½ Σ βᵢ · n·(vᵢ×vᵢ₊₁)/|vᵢ×vᵢ₊₁|).
fn polygon_irradiance(corners: &[Vec3; 3]) -> f64 {
    let v = corners.map(|c| c.normalize());
    let mut sum = 0.0;
    for i in 0..3 {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let angle = f64::from(a.dot(b).clamp(-1.0, 1.0).acos());
        sum += angle * f64::from(a.cross(b).normalize().z);
    }
    0.5 * sum.abs()
}

#[test]
fn area_light_sampling_reproduces_the_analytic_irradiance() {
    let light = Light::Area(ceiling_triangle(Vec3::ONE));
    let estimate = estimate(200_000, 1, |rng| {
        let s = light.illuminate(&[], Vec3::ZERO, rng.uniform2()).unwrap();
        f64::from(s.value.x * s.direction.z / s.direct_pdf_w)
    });
    let Light::Area(area) = &light else {
        unreachable!()
    };
    assert_close("irradiance", estimate, polygon_irradiance(&area.corners));
}

/// A constant environment of radiance L gives irradiance π L on any surface it sees whole.
#[test]
fn environment_sampling_reproduces_the_irradiance_of_a_uniform_sky() {
    let light = Light::Environment(EnvironmentLight {
        radiance: Vec3::splat(0.75),
        map: None,
        scene_center: Vec3::ZERO,
        scene_radius: 3.0,
    });
    let normal = Vec3::new(0.6, 0.0, 0.8);
    let estimate = estimate(200_000, 7, |rng| {
        let s = light.illuminate(&[], Vec3::ONE, rng.uniform2()).unwrap();
        assert_eq!(s.distance, f32::INFINITY);
        f64::from(s.value.x * s.direction.dot(normal).max(0.0) / s.direct_pdf_w)
    });
    assert_close("irradiance", estimate, 0.75 * std::f64::consts::PI);
    assert!(!light.is_delta() && !light.is_finite());
}

#[test]
fn emission_sampling_integrates_to_the_light_power() {
    let r = 2.0;
    let lights = [
        Light::Area(ceiling_triangle(Vec3::new(2.0, 1.0, 0.5))),
        Light::Point(PointLight {
            position: Vec3::ONE,
            intensity: Vec3::new(3.0, 2.0, 1.0),
        }),
        Light::Spot(SpotLight {
            position: Vec3::ZERO,
            direction: Vec3::new(0.0, 0.6, -0.8),
            intensity: Vec3::splat(5.0),
            cos_inner: 0.3f32.cos(),
            cos_outer: 0.7f32.cos(),
        }),
        Light::Directional(DirectionalLight {
            direction: -Vec3::Y,
            irradiance: Vec3::splat(1.5),
            scene_center: Vec3::ZERO,
            scene_radius: r,
        }),
        Light::Environment(EnvironmentLight {
            radiance: Vec3::new(0.5, 1.0, 2.0),
            map: None,
            scene_center: Vec3::ONE,
            scene_radius: r,
        }),
        Light::Environment(EnvironmentLight {
            radiance: Vec3::new(0.5, 1.0, 2.0),
            map: Some(std::sync::Arc::new(
                EnvironmentMap::new(
                    4,
                    2,
                    (0..8).map(|i| Vec3::new(i as f32, 1.0, 0.5)).collect(),
                )
                .unwrap(),
            )),
            scene_center: Vec3::ONE,
            scene_radius: r,
        }),
    ];
    for (i, light) in lights.iter().enumerate() {
        let estimate = estimate(200_000, 2 + i as u64, |rng| {
            let e = light.emit(&[], rng.uniform2(), rng.uniform2()).unwrap();
            f64::from(channel_mean(e.value) * e.cos_at_light / e.emission_pdf_w)
        });
        assert_close(
            &format!("power of light {i}"),
            estimate,
            f64::from(light.power(&[])),
        );
    }
}

/// A cut-out emitter sends light only from where its surface is: both sampling routines
/// refuse points in the cut-away part, so the emitted power is that of the rest.
#[test]
fn cut_out_emitters_emit_only_where_present() {
    // Alpha 0, 0, 1, 1 across; bilinear filtering ramps it from 0 at u = 3/8 to 1 at u = 5/8.
    let texels = vec![[0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 255], [0, 0, 0, 255]];
    let textures = [Texture::new("mask".into(), 4, 1, texels, ColorEncoding::Linear).unwrap()];
    let mut light = ceiling_triangle(Vec3::new(2.0, 1.0, 0.5));
    // u = 1/4 + b1/2: the surface (alpha ≥ ½, u ≥ ½) is where b1 ≥ ½, a quarter of the area.
    light.uvs = [
        Vec2::new(0.25, 0.5),
        Vec2::new(0.75, 0.5),
        Vec2::new(0.25, 0.5),
    ];
    light.cut_out = Some(AlphaMask {
        alpha: 1.0,
        texture: Some(TextureRef::new(0)),
        cutoff: 0.5,
    });
    let [c0, c1, c2] = light.corners;
    let b1 = |p: Vec3| (p - c0).cross(c2 - c0).length() / (c1 - c0).cross(c2 - c0).length();
    let full_power = f64::from(light.power(&textures));
    let light = Light::Area(light);
    let estimate = estimate(200_000, 7, |rng| {
        let Some(e) = light.emit(&textures, rng.uniform2(), rng.uniform2()) else {
            return 0.0;
        };
        assert!(b1(e.position) >= 0.5 - 1e-4, "emitted from a cut-out point");
        f64::from(channel_mean(e.value) * e.cos_at_light / e.emission_pdf_w)
    });
    assert_close("power of the present quarter", estimate, 0.25 * full_power);
    let mut rng = Rng::new(8, 0);
    let illuminated = (0..10_000).filter_map(|_| {
        let s = light.illuminate(&textures, Vec3::ZERO, rng.uniform2())?;
        Some(s.direction * s.distance)
    });
    let points: Vec<Vec3> = illuminated.collect();
    assert!((2_000..3_000).contains(&points.len()), "{}", points.len());
    assert!(points.iter().all(|&p| b1(p) >= 0.5 - 1e-4));
}

#[test]
fn hit_and_sampled_pdfs_agree_for_area_lights() {
    let area = ceiling_triangle(Vec3::ONE);
    let light = Light::Area(area.clone());
    let receiver = Vec3::new(0.1, 0.0, 0.0);
    let sample = light
        .illuminate(&[], receiver, Vec2::new(0.3, 0.6))
        .unwrap();
    let hit = area
        .radiance_on_hit(&[], sample.direction, 0.2, 0.2)
        .unwrap();
    assert!((hit.emission_pdf_w - sample.emission_pdf_w).abs() < 1e-5);
    assert!((hit.direct_pdf_a - 1.0 / area.area).abs() < 1e-5);
    let distance_sq = sample.distance * sample.distance;
    assert!(
        (sample.direct_pdf_w - hit.direct_pdf_a * distance_sq / sample.cos_at_light).abs()
            < 1e-3 * sample.direct_pdf_w
    );
    // One-sided: a receiver above the light (behind its front face) gets nothing.
    assert!(
        light
            .illuminate(&[], Vec3::new(0.0, 0.0, 2.0), Vec2::new(0.3, 0.6))
            .is_none()
    );
}

#[test]
fn spot_lights_respect_their_cones() {
    let spot = SpotLight {
        position: Vec3::ZERO,
        direction: -Vec3::Z,
        intensity: Vec3::ONE,
        cos_inner: 0.9,
        cos_outer: 0.8,
    };
    assert_eq!(spot.falloff(0.95), 1.0);
    assert_eq!(spot.falloff(0.7), 0.0);
    assert!((spot.falloff(0.85) - 0.25).abs() < 1e-5);
    let light = Light::Spot(spot);
    assert!(
        light
            .illuminate(&[], Vec3::new(0.0, 0.0, -1.0), Vec2::ZERO)
            .is_some()
    );
    assert!(
        light
            .illuminate(&[], Vec3::new(1.0, 0.0, -0.1), Vec2::ZERO)
            .is_none()
    );
    assert!(light.is_delta() && light.is_finite());
}

#[test]
fn lights_are_selected_in_proportion_to_power() {
    let lights = [
        Light::Point(PointLight {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        }),
        Light::Point(PointLight {
            position: Vec3::ZERO,
            intensity: Vec3::splat(3.0),
        }),
        Light::Area(ceiling_triangle(Vec3::ZERO)),
    ];
    let sampler = LightSampler::new(&lights, &[], 1);
    assert!((sampler.pmf(0) - 0.25).abs() < 1e-6);
    assert!((sampler.pmf(1) - 0.75).abs() < 1e-6);
    assert_eq!(sampler.pmf(2), 0.0);
    assert_eq!(sampler.light_of_triangle(0), Some(2));
    for i in 0..1000 {
        let (light, _) = sampler.sample(i as f32 / 1000.0).unwrap();
        assert_ne!(light, 2, "a light without power was chosen");
    }
    assert!(LightSampler::new(&[], &[], 0).sample(0.5).is_none());
}
