//! Scenes and ray workloads for the traversal benchmark: the committed Cornell box
//! (`scenes/cornell-box.gltf`) and a generated ~1M-triangle scene, with rays drawn by the
//! project's generator and warps from `vcm_scene::sampling`.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3, vec3};
use vcm_scene::Camera;
use vcm_scene::frame::Frame;
use vcm_scene::light::Light;
use vcm_scene::sampling::{
    Rng, Sampler, sample_cosine_hemisphere, sample_uniform_sphere, sample_uniform_triangle,
};
use vcm_traversal::{HitBatch, RayBatch, Traversal};

/// Triangles, a camera framing them and the emitting triangles shadow rays aim at.
pub struct Scene {
    /// Benchmark group name.
    pub name: &'static str,
    /// The geometry; index = primitive id.
    pub triangles: Vec<[Vec3; 3]>,
    /// The camera for primary rays.
    pub camera: Camera,
    /// Emitting triangles, all of the same area (so each is picked with equal probability).
    pub emitters: Vec<[Vec3; 3]>,
}

/// Image resolution of the primary rays (one ray per pixel).
pub const RESOLUTION: u32 = 512;

/// The three ray sets traced against one scene.
pub struct Workload {
    /// One camera ray per pixel, row by row: coherent.
    pub primary: RayBatch,
    /// Cosine-distributed rays from the primary hits: incoherent.
    pub bounce: RayBatch,
    /// Rays from the primary hits to points on the emitters, for occlusion.
    pub shadow: RayBatch,
}

impl Workload {
    /// Primary rays from the scene's camera at [`RESOLUTION`]²; bounce and shadow rays from
    /// their hit points in `bvh`.
    pub fn new(scene: &Scene, bvh: &dyn Traversal) -> Self {
        let primary = primary_rays(&scene.camera, RESOLUTION);
        let mut hits = HitBatch::default();
        bvh.intersect(&primary, &mut hits);
        let points = SurfacePoints::from_hits(&scene.triangles, &primary, &hits);
        let mut rng = Rng::new(1, 0);
        Self {
            bounce: points.bounce_rays(&mut rng),
            shadow: points.shadow_rays(&scene.emitters, &mut rng),
            primary,
        }
    }
}

/// One ray through the centre of every pixel of a square `resolution²` image, row by row.
pub fn primary_rays(camera: &Camera, resolution: u32) -> RayBatch {
    let mut rays = RayBatch::with_capacity((resolution * resolution) as usize);
    for y in 0..resolution {
        for x in 0..resolution {
            let raster = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let direction = camera.direction(resolution, resolution, raster);
            rays.push(camera.position, direction, 0.0, f32::INFINITY);
        }
    }
    rays
}

/// The committed Cornell box scene (made by `examples/make_scenes.rs`): its triangles, its
/// camera and its area lights.
pub fn cornell_box() -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell-box.gltf");
    let scene = vcm_scene::Scene::load(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let emitters = scene
        .lights
        .iter()
        .filter_map(|light| match light {
            Light::Area(area) => Some(area.corners),
            _ => None,
        })
        .collect();
    Scene {
        name: "cornell_box",
        triangles: scene.triangle_corners(),
        camera: scene.camera,
        emitters,
    }
}

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// Smooth pseudo-random relief: a sum of sines with random directions and phases.
struct Relief {
    waves: Vec<(Vec3, f32, f32)>,
}

impl Relief {
    fn new(rng: &mut Rng, octaves: usize, base_frequency: f32) -> Self {
        let waves = (0..octaves)
            .map(|k| {
                let direction = sample_uniform_sphere(rng.uniform2());
                let frequency = base_frequency * 2f32.powi(k as i32);
                (
                    direction * frequency,
                    TAU * rng.uniform(),
                    0.55f32.powi(k as i32),
                )
            })
            .collect();
        Self { waves }
    }

    fn at(&self, p: Vec3) -> f32 {
        let sum: f32 = self
            .waves
            .iter()
            .map(|&(k, phase, amplitude)| amplitude * (k.dot(p) + phase).sin())
            .sum();
        sum / 1.8
    }
}

/// A closed UV sphere with `rings × segments` quads, displaced radially by `relief`.
fn displaced_sphere(
    center: Vec3,
    radius: f32,
    rings: usize,
    segments: usize,
    relief: &Relief,
    amount: f32,
) -> Vec<[Vec3; 3]> {
    let vertex = |ring: usize, segment: usize| {
        let theta = PI * ring as f32 / rings as f32;
        let phi = TAU * (segment % segments) as f32 / segments as f32;
        let n = if ring == 0 || ring == rings {
            vec3(0.0, if ring == 0 { 1.0 } else { -1.0 }, 0.0)
        } else {
            vec3(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            )
        };
        center + n * radius * (1.0 + amount * relief.at(n))
    };
    let mut tris = Vec::with_capacity(2 * rings * segments);
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (vertex(ring, segment), vertex(ring, segment + 1));
            let (c, d) = (vertex(ring + 1, segment), vertex(ring + 1, segment + 1));
            if ring != 0 {
                tris.push([a, b, c]);
            }
            if ring != rings - 1 {
                tris.push([b, d, c]);
            }
        }
    }
    tris
}

/// A `cells × cells` height field over `[-half, half]²`.
fn terrain(cells: usize, half: f32, relief: &Relief) -> Vec<[Vec3; 3]> {
    let p = |i: usize, j: usize| {
        let x = -half + 2.0 * half * i as f32 / cells as f32;
        let z = -half + 2.0 * half * j as f32 / cells as f32;
        vec3(x, relief.at(vec3(x, 0.0, z)), z)
    };
    let mut tris = Vec::with_capacity(2 * cells * cells);
    for i in 0..cells {
        for j in 0..cells {
            tris.extend(quad(p(i, j), p(i, j + 1), p(i + 1, j + 1), p(i + 1, j)));
        }
    }
    tris
}

/// About a million triangles: a finely tessellated terrain, a large displaced sphere and
/// 1200 scattered rocks, seen from above the terrain's edge, under a square light.
pub fn million_triangles() -> Scene {
    let mut rng = Rng::new(7, 0);
    let ground = Relief::new(&mut rng, 7, 0.15);
    let mut triangles = terrain(450, 12.0, &ground);
    let bumps = Relief::new(&mut rng, 6, 2.0);
    triangles.extend(displaced_sphere(
        vec3(0.0, 3.5, 0.0),
        3.0,
        200,
        400,
        &bumps,
        0.06,
    ));
    for _ in 0..1200 {
        let xz = rng.uniform2() * 22.0 - 11.0;
        let radius = 0.08 + 0.37 * rng.uniform();
        let center = vec3(xz.x, ground.at(vec3(xz.x, 0.0, xz.y)) + radius * 0.5, xz.y);
        triangles.extend(displaced_sphere(center, radius, 10, 20, &bumps, 0.25));
    }
    let position = vec3(0.0, 9.0, 17.0);
    let forward = (vec3(0.0, 1.0, 0.0) - position).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let light = |x: f32, z: f32| vec3(x, 20.0, z);
    Scene {
        name: "million_triangles",
        triangles,
        camera: Camera {
            position,
            right,
            up: right.cross(forward),
            forward,
            yfov: 55f32.to_radians(),
            aspect_ratio: None,
        },
        emitters: quad(
            light(-4.0, -4.0),
            light(4.0, -4.0),
            light(4.0, 4.0),
            light(-4.0, 4.0),
        )
        .to_vec(),
    }
}

/// Points where primary rays hit, offset off the surface, with the normal facing the ray.
pub struct SurfacePoints {
    origins: Vec<Vec3>,
    normals: Vec<Vec3>,
}

impl SurfacePoints {
    /// Collects the hits of `rays` against `triangles`.
    pub fn from_hits(triangles: &[[Vec3; 3]], rays: &RayBatch, hits: &HitBatch) -> Self {
        let mut points = Self {
            origins: Vec::new(),
            normals: Vec::new(),
        };
        for i in (0..rays.len()).filter(|&i| hits.is_hit(i)) {
            let [p0, p1, p2] = triangles[hits.prim[i] as usize];
            let direction = rays.direction(i);
            let mut normal = (p1 - p0).cross(p2 - p0).normalize();
            if normal.dot(direction) > 0.0 {
                normal = -normal;
            }
            let hit = rays.origin(i) + direction * hits.t[i];
            let offset = 1e-4 * hit.abs().max_element().max(1.0);
            points.origins.push(hit + normal * offset);
            points.normals.push(normal);
        }
        points
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.origins.len()
    }

    /// Cosine-distributed diffuse bounce rays, one per point.
    pub fn bounce_rays(&self, rng: &mut Rng) -> RayBatch {
        let mut rays = RayBatch::with_capacity(self.len());
        for (&origin, &normal) in self.origins.iter().zip(&self.normals) {
            let local = sample_cosine_hemisphere(rng.uniform2());
            rays.push(
                origin,
                Frame::from_z(normal).to_world(local),
                0.0,
                f32::INFINITY,
            );
        }
        rays
    }

    /// Shadow rays from every point to a uniform point on a random one of `emitters`,
    /// stopping just short of it.
    pub fn shadow_rays(&self, emitters: &[[Vec3; 3]], rng: &mut Rng) -> RayBatch {
        assert!(!emitters.is_empty(), "shadow rays need an emitter");
        let mut rays = RayBatch::with_capacity(self.len());
        for &origin in &self.origins {
            let [p0, p1, p2] = emitters[rng.next_u32() as usize % emitters.len()];
            let b = sample_uniform_triangle(rng.uniform2());
            let target = p0 * b.x + p1 * b.y + p2 * b.z;
            rays.push(origin, target - origin, 0.0, 1.0 - 1e-4);
        }
        rays
    }
}
