//! Scenes built in code and frame statistics shared by the integration tests.

use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{DVec3, Vec2, Vec3, Vec4};
use vcm::{Algorithm, Film, Integrator, MergeRadius, PathTracer, PtSettings, Vcm, VcmSettings};
use vcm_scene::light::{EnvironmentLight, EnvironmentMap, Light};
use vcm_scene::sampling::SampleSequence;
use vcm_scene::{Camera, Material, Mesh, Scene};
use vcm_traversal::{CpuBvh, CpuBvhOptions, Traversal};

/// The path tracer (`None`) and every algorithm of the VCM integrator.
pub const EVERY_ALGORITHM: [Option<Algorithm>; 6] = [
    None,
    Some(Algorithm::LightTracing),
    Some(Algorithm::Bpt),
    Some(Algorithm::Ppm),
    Some(Algorithm::Bpm),
    Some(Algorithm::Vcm),
];

/// A camera at `position` looking down -Z with +Y up and vertical field of view `yfov` (rad).
pub fn camera(position: Vec3, yfov: f32) -> Camera {
    Camera {
        position,
        right: Vec3::X,
        up: Vec3::Y,
        forward: -Vec3::Z,
        yfov,
        aspect_ratio: None,
    }
}

/// A mesh without normals, texture coordinates or tangents.
pub fn mesh(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>, material_ids: Vec<u32>) -> Mesh {
    let n = positions.len();
    Mesh {
        positions,
        normals: vec![Vec3::ZERO; n],
        uvs: vec![Vec2::ZERO; n],
        tangents: vec![Vec4::ZERO; n],
        colors: Vec::new(),
        triangles,
        material_ids,
    }
}

/// The two triangles of the quad `corners` (counter-clockwise seen from the front), appended
/// to `positions` / `triangles`.
pub fn push_quad(positions: &mut Vec<Vec3>, triangles: &mut Vec<[u32; 3]>, corners: [Vec3; 4]) {
    let base = positions.len() as u32;
    positions.extend(corners);
    triangles.push([base, base + 1, base + 2]);
    triangles.push([base, base + 2, base + 3]);
}

/// A unit icosphere around the origin, `subdivisions` times refined, with every triangle
/// facing inward (counter-clockwise seen from the center).
pub fn inward_icosphere(subdivisions: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let (positions, outward) = vcm_scene::shapes::icosphere(subdivisions);
    let inward = outward.into_iter().map(|[a, b, c]| [a, c, b]).collect();
    (positions, inward)
}

/// A sky of `radiance` (times `map` where given) around `mesh`: light paths from it start
/// on the disk of the mesh's bounding sphere.
pub fn sky(radiance: Vec3, map: Option<Arc<EnvironmentMap>>, mesh: &Mesh) -> Light {
    let bounds = mesh.bounds();
    Light::Environment(EnvironmentLight {
        radiance,
        map,
        scene_center: bounds.center(),
        scene_radius: bounds.radius(),
    })
}

/// A scene from parts, with no textures and no warnings.
pub fn scene(mesh: Mesh, materials: Vec<Material>, lights: Vec<Light>, camera: Camera) -> Scene {
    Scene::new(
        PathBuf::from("test"),
        mesh,
        materials,
        Vec::new(),
        lights,
        camera,
        Vec::new(),
    )
}

/// A scene of the project's `scenes/` folder, by file name.
pub fn scene_file(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    Scene::load(&path).unwrap()
}

/// The CPU traversal backend over `scene`.
pub fn cpu_traversal(scene: &Scene) -> Arc<dyn Traversal> {
    Arc::new(CpuBvh::new(&scene.triangle_corners(), CpuBvhOptions::default()).unwrap())
}

/// Path tracer settings for a `width` × `height` image whose frames are independent
/// ([`SampleSequence::Independent`]): the statistical tests estimate errors from the spread
/// between frames, which stratification across frames would overstate.
pub fn pt_settings(width: u32, height: u32) -> PtSettings {
    PtSettings {
        sequence: SampleSequence::Independent,
        ..PtSettings::new(width, height)
    }
}

/// Settings of `algorithm` for a `width` × `height` image whose frames are independent, as
/// in [`pt_settings`].
pub fn vcm_settings(algorithm: Algorithm, width: u32, height: u32) -> VcmSettings {
    VcmSettings {
        sequence: SampleSequence::Independent,
        ..VcmSettings::new(algorithm, width, height)
    }
}

/// A path tracer over `scene` with the CPU backend.
pub fn path_tracer(scene: Scene, settings: PtSettings) -> PathTracer {
    let traversal = cpu_traversal(&scene);
    PathTracer::new(Arc::new(scene), traversal, settings).unwrap()
}

/// The VCM integrator (any of its algorithms) over `scene` with the CPU backend.
pub fn vcm(scene: Scene, settings: VcmSettings) -> Vcm {
    let traversal = cpu_traversal(&scene);
    Vcm::new(Arc::new(scene), traversal, settings).unwrap()
}

/// The path tracer (`None`) or `algorithm` rendering `scene` at `size`² from `seed`, with
/// independent frames, merging (where it merges) within `radius_fraction` of the scene's
/// radius.
pub fn integrator(
    scene: &Scene,
    algorithm: Option<Algorithm>,
    size: u32,
    seed: u64,
    radius_fraction: f32,
) -> Box<dyn Integrator> {
    match algorithm {
        None => Box::new(path_tracer(
            scene.clone(),
            PtSettings {
                seed,
                ..pt_settings(size, size)
            },
        )),
        Some(algorithm) => Box::new(vcm(
            scene.clone(),
            VcmSettings {
                seed,
                radius: MergeRadius::SceneFraction(radius_fraction),
                ..vcm_settings(algorithm, size, size)
            },
        )),
    }
}

/// Per-pixel and image-wide means over independent frames, with standard errors computed from
/// the spread of the per-frame values (channel means of RGB).
pub struct FrameSeries {
    /// All frames merged.
    pub film: Film,
    /// Mean over frames per pixel.
    pub pixel_mean: Vec<f64>,
    /// Standard error of `pixel_mean`, from each pixel's own frames.
    pub pixel_std_err: Vec<f64>,
    /// Standard error of a pixel mean with the per-frame variance pooled over all pixels
    /// (for images whose pixels all see one distribution).
    pub pooled_pixel_std_err: f64,
    /// Mean over frames of the image mean.
    pub image_mean: f64,
    /// Standard error of `image_mean`.
    pub image_std_err: f64,
}

/// Mean and standard error of the mean of `values` (n ≥ 2).
fn mean_and_std_err(values: impl ExactSizeIterator<Item = f64> + Clone) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.clone().sum::<f64>() / n;
    let variance = values.map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (variance / n).sqrt())
}

/// Renders `frames` frames (iterations 0, 1, …), each into its own film.
pub fn render_series(tracer: &mut dyn Integrator, frames: u32) -> FrameSeries {
    let (width, height) = tracer.image_size();
    let mut film = Film::new(width, height);
    let mut per_frame: Vec<Vec<f64>> = Vec::new();
    for iteration in 0..frames {
        let mut frame = Film::new(width, height);
        tracer.render_frame(&mut frame, iteration);
        per_frame.push(
            frame
                .mean()
                .iter()
                .map(|rgb| f64::from(rgb.element_sum()) / 3.0)
                .collect(),
        );
        film.merge(&frame);
    }
    let pixels = (width * height) as usize;
    let (pixel_mean, pixel_std_err): (Vec<f64>, Vec<f64>) = (0..pixels)
        .map(|p| mean_and_std_err(per_frame.iter().map(|f| f[p])))
        .unzip();
    let pooled_pixel_std_err =
        (pixel_std_err.iter().map(|e| e * e).sum::<f64>() / pixels as f64).sqrt();
    let image_means = per_frame
        .iter()
        .map(|f| f.iter().sum::<f64>() / pixels as f64);
    let (image_mean, image_std_err) = mean_and_std_err(image_means.collect::<Vec<_>>().into_iter());
    FrameSeries {
        film,
        pixel_mean,
        pixel_std_err,
        pooled_pixel_std_err,
        image_mean,
        image_std_err,
    }
}

/// Means over frames of image blocks and of the whole image, with standard errors from the
/// spread of the per-frame values (channel means of RGB).
pub struct RegionSeries {
    /// Mean of each block, row by row.
    pub means: Vec<f64>,
    /// Standard error of each block's mean.
    pub errors: Vec<f64>,
    /// Mean of the whole image.
    pub image_mean: f64,
    /// Standard error of `image_mean`.
    pub image_error: f64,
}

impl RegionSeries {
    /// z-scores of the region means against `reference`'s, and last that of the image mean
    /// (its standard error is about 1/√regions² of a region's, so it sees a small bias that
    /// the regions would not). Asserts that no region of the reference is black.
    pub fn z_scores(&self, reference: &RegionSeries) -> Vec<f64> {
        let z = |m: f64, e: f64, rm: f64, re: f64| (m - rm) / (e * e + re * re).sqrt();
        let regions = self.means.iter().zip(&self.errors);
        let mut scores: Vec<f64> = regions
            .zip(reference.means.iter().zip(&reference.errors))
            .enumerate()
            .map(|(r, ((&m, &e), (&rm, &re)))| {
                assert!(rm > 0.0, "region {r} of the reference is black");
                z(m, e, rm, re)
            })
            .collect();
        scores.push(z(
            self.image_mean,
            self.image_error,
            reference.image_mean,
            reference.image_error,
        ));
        scores
    }
}

/// Renders `frames` frames (iterations 0, 1, …) and measures the image split into
/// `regions` × `regions` blocks. Asserts that no sample was dropped.
pub fn region_means(integrator: &mut dyn Integrator, frames: u32, regions: usize) -> RegionSeries {
    region_means_from(integrator, 0..frames, regions)
}

/// [`region_means`] over the frames of `iterations` (late iterations of progressive photon
/// mapping merge within a smaller radius).
pub fn region_means_from(
    integrator: &mut dyn Integrator,
    iterations: Range<u32>,
    regions: usize,
) -> RegionSeries {
    let (width, height) = integrator.image_size();
    let (block_w, block_h) = (width as usize / regions, height as usize / regions);
    let mut per_frame = Vec::new();
    for iteration in iterations {
        let mut film = Film::new(width, height);
        integrator.render_frame(&mut film, iteration);
        assert_eq!(film.dropped(), 0);
        let mut means = vec![0.0; regions * regions];
        for (i, rgb) in film.mean().iter().enumerate() {
            let (x, y) = (i % width as usize / block_w, i / width as usize / block_h);
            if x < regions && y < regions {
                means[y * regions + x] +=
                    f64::from(rgb.element_sum()) / 3.0 / (block_w * block_h) as f64;
            }
        }
        per_frame.push(means);
    }
    let (means, errors) = (0..regions * regions)
        .map(|r| mean_and_std_err(per_frame.iter().map(|f| f[r])))
        .unzip();
    let image_means: Vec<f64> = per_frame
        .iter()
        .map(|f| f.iter().sum::<f64>() / f.len() as f64)
        .collect();
    let (image_mean, image_error) = mean_and_std_err(image_means.into_iter());
    RegionSeries {
        means,
        errors,
        image_mean,
        image_error,
    }
}

/// Subsamples per pixel side for analytic pixel values.
const QUADRATURE: u32 = 32;

/// Box-filtered values of a `size` × `size` image of the plane z = 0 seen by `camera`: the
/// mean of `radiance_at(point)` over each pixel (midpoint rule, 32 × 32 subsamples).
pub fn plane_pixel_values(
    camera: &Camera,
    size: u32,
    radiance_at: impl Fn(DVec3) -> f64,
) -> Vec<f64> {
    let eye = camera.position.as_dvec3();
    let step = 1.0 / QUADRATURE as f32;
    let pixel_value = |pixel: u32| {
        let corner = Vec2::new((pixel % size) as f32, (pixel / size) as f32);
        let sum: f64 = (0..QUADRATURE * QUADRATURE)
            .map(|i| {
                let offset =
                    Vec2::new((i % QUADRATURE) as f32 + 0.5, (i / QUADRATURE) as f32 + 0.5);
                let dir = camera
                    .direction(size, size, corner + offset * step)
                    .as_dvec3();
                radiance_at(eye + dir * (-eye.z / dir.z))
            })
            .sum();
        sum / f64::from(QUADRATURE * QUADRATURE)
    };
    (0..size * size).map(pixel_value).collect()
}

/// Asserts that the rendered image matches `expected` (per pixel): the image mean within 4
/// standard errors, every pixel within 5 of its own (with 64 pixels the chance of a false
/// failure stays below 1e-4). Both allow 1e-5 of the brightest expected pixel besides, for
/// f32 rounding along the path and for slivers of a pixel too small for its few samples to
/// land in (a spot cone's edge crossing a corner: no sample there means a standard error of 0).
pub fn assert_pixels_match(series: &FrameSeries, expected: &[f64], label: &str) {
    let floor = 1e-5 * expected.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    let want = expected.iter().sum::<f64>() / expected.len() as f64;
    let (mean, se) = (series.image_mean, series.image_std_err);
    assert!(
        (mean - want).abs() <= 4.0 * se + floor,
        "{label}: image mean {mean} vs {want} ± 4·{se}"
    );
    for (p, want) in expected.iter().enumerate() {
        let (m, e) = (series.pixel_mean[p], series.pixel_std_err[p]);
        assert!(
            (m - want).abs() <= 5.0 * e + floor,
            "{label}, pixel {p}: {m} vs {want} ± 5·{e}"
        );
    }
    assert_eq!(series.film.dropped(), 0, "{label}");
}

/// A square of half side `half` in the plane z = 0, facing +Z.
pub fn push_floor(positions: &mut Vec<Vec3>, triangles: &mut Vec<[u32; 3]>, half: f32) {
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .map(|(x, y)| Vec3::new(x * half, y * half, 0.0));
    push_quad(positions, triangles, corners);
}

/// A diffuse square of half side `half` at z = 0 under a unit point light at (0, 0, 1),
/// seen by `camera`.
pub fn lit_floor(half: f32, camera: Camera) -> Scene {
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    push_floor(&mut positions, &mut triangles, half);
    scene(
        mesh(positions, triangles, vec![0, 0]),
        vec![Material::diffuse("floor", Vec3::splat(0.5))],
        vec![Light::Point(vcm_scene::light::PointLight {
            position: Vec3::new(0.0, 0.0, 1.0),
            intensity: Vec3::ONE,
        })],
        camera,
    )
}

/// The scene `name` with every vertex normal leaning about 31° off its triangle's normal,
/// each vertex its own way (a fixed pseudo-random direction): smooth-shaded geometry whose
/// shading normals differ from the geometric ones everywhere.
pub fn with_leaning_normals(name: &str) -> Scene {
    let loaded = scene_file(name);
    let mut mesh = loaded.mesh.clone();
    for t in 0..mesh.triangle_count() {
        let n = mesh.geometric_normal(t);
        for &i in &mesh.triangles[t] {
            let k = i as f32;
            let jitter = Vec3::new((k * 12.9898).sin(), (k * 78.233).sin(), (k * 37.719).sin());
            let aside = (jitter - n * n.dot(jitter)).normalize_or_zero();
            mesh.normals[i as usize] = (n + aside * 0.6).normalize();
        }
    }
    // The Cornell scenes have no punctual lights: the area lights are made again.
    rebuilt(loaded, mesh, Vec::new())
}

/// `loaded` assembled again with `mesh` and `punctual_lights` (its area lights made anew from
/// the emissive triangles).
pub fn rebuilt(loaded: Scene, mesh: Mesh, punctual_lights: Vec<Light>) -> Scene {
    let Scene {
        path,
        materials,
        textures,
        camera,
        ..
    } = loaded;
    let warnings = Vec::new();
    Scene::new(
        path,
        mesh,
        materials,
        textures,
        punctual_lights,
        camera,
        warnings,
    )
}
