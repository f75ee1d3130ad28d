//! Procedural scenes and ray workloads for the traversal benchmark.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Quat, Vec3, vec3};
use vcm_traversal::{HitBatch, RayBatch};

/// PCG32 random numbers with a fixed seed, so every run traces the same rays.
pub struct Pcg(u64);

impl Pcg {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        let mut rng = Self(seed.wrapping_add(0x853c_49e6_748f_ea9b));
        rng.next_u32();
        rng
    }

    fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
}

/// A pinhole camera.
pub struct Camera {
    position: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
}

impl Camera {
    /// A camera at `position` looking at `target` with vertical field of view `fov_y` radians.
    pub fn look_at(position: Vec3, target: Vec3, fov_y: f32) -> Self {
        let forward = (target - position).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let scale = (fov_y * 0.5).tan();
        Self {
            position,
            forward,
            right: right * scale,
            up: up * scale,
        }
    }

    /// One ray through the centre of every pixel of a square image, row by row.
    pub fn primary_rays(&self, resolution: usize) -> RayBatch {
        let mut rays = RayBatch::with_capacity(resolution * resolution);
        for y in 0..resolution {
            for x in 0..resolution {
                let sx = (x as f32 + 0.5) / resolution as f32 * 2.0 - 1.0;
                let sy = 1.0 - (y as f32 + 0.5) / resolution as f32 * 2.0;
                let direction = (self.forward + self.right * sx + self.up * sy).normalize();
                rays.push(self.position, direction, 0.0, f32::INFINITY);
            }
        }
        rays
    }
}

/// A rectangular area light `corner + s·edge_s + t·edge_t`, `s, t ∈ [0, 1)`.
pub struct QuadLight {
    corner: Vec3,
    edge_s: Vec3,
    edge_t: Vec3,
}

impl QuadLight {
    fn sample(&self, rng: &mut Pcg) -> Vec3 {
        self.corner + self.edge_s * rng.f32() + self.edge_t * rng.f32()
    }

    fn triangles(&self) -> [[Vec3; 3]; 2] {
        let [a, b, c] = [
            self.corner,
            self.corner + self.edge_s,
            self.corner + self.edge_t,
        ];
        let d = b + self.edge_t;
        [[a, b, d], [a, d, c]]
    }
}

/// Triangles, a camera framing them and an area light.
pub struct Scene {
    /// Benchmark group name.
    pub name: &'static str,
    /// The geometry; index = primitive id.
    pub triangles: Vec<[Vec3; 3]>,
    /// The camera for primary rays.
    pub camera: Camera,
    /// The light shadow rays aim at.
    pub light: QuadLight,
}

fn quad(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> [[Vec3; 3]; 2] {
    [[a, b, c], [a, c, d]]
}

/// The 12 triangles of the unit cube `[-0.5, 0.5]³` under `transform`.
fn cube(transform: Affine3A) -> Vec<[Vec3; 3]> {
    let corner = |i: usize| {
        let p = vec3((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) - 0.5;
        transform.transform_point3(p)
    };
    let faces = [
        [0, 2, 6, 4],
        [1, 5, 7, 3],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 6, 7, 5],
    ];
    faces
        .iter()
        .flat_map(|&[a, b, c, d]| quad(corner(a), corner(b), corner(c), corner(d)))
        .collect()
}

/// The classic Cornell box: a 2-unit room open at +z, a ceiling light and two rotated boxes
/// (36 triangles).
pub fn cornell_box() -> Scene {
    let p = |x: f32, y: f32, z: f32| vec3(x, y, z);
    let mut triangles = Vec::new();
    triangles.extend(quad(
        p(-1., 0., -1.),
        p(1., 0., -1.),
        p(1., 0., 1.),
        p(-1., 0., 1.),
    ));
    triangles.extend(quad(
        p(-1., 2., -1.),
        p(-1., 2., 1.),
        p(1., 2., 1.),
        p(1., 2., -1.),
    ));
    triangles.extend(quad(
        p(-1., 0., -1.),
        p(-1., 2., -1.),
        p(1., 2., -1.),
        p(1., 0., -1.),
    ));
    triangles.extend(quad(
        p(-1., 0., -1.),
        p(-1., 0., 1.),
        p(-1., 2., 1.),
        p(-1., 2., -1.),
    ));
    triangles.extend(quad(
        p(1., 0., -1.),
        p(1., 2., -1.),
        p(1., 2., 1.),
        p(1., 0., 1.),
    ));
    let light = QuadLight {
        corner: p(-0.25, 1.98, -0.25),
        edge_s: p(0.5, 0.0, 0.0),
        edge_t: p(0.0, 0.0, 0.5),
    };
    triangles.extend(light.triangles());
    let short_box = Affine3A::from_scale_rotation_translation(
        Vec3::splat(0.6),
        Quat::from_rotation_y(-17.5f32.to_radians()),
        p(0.35, 0.3, 0.35),
    );
    let tall_box = Affine3A::from_scale_rotation_translation(
        p(0.6, 1.2, 0.6),
        Quat::from_rotation_y(17.5f32.to_radians()),
        p(-0.35, 0.6, -0.3),
    );
    triangles.extend(cube(short_box));
    triangles.extend(cube(tall_box));
    Scene {
        name: "cornell_box",
        triangles,
        camera: Camera::look_at(p(0.0, 1.0, 3.9), p(0.0, 1.0, 0.0), 40f32.to_radians()),
        light,
    }
}

/// Smooth pseudo-random relief: a sum of sines with random directions and phases.
struct Relief {
    waves: Vec<(Vec3, f32, f32)>,
}

impl Relief {
    fn new(rng: &mut Pcg, octaves: usize, base_frequency: f32) -> Self {
        let waves = (0..octaves)
            .map(|k| {
                let z = rng.range(-1.0, 1.0);
                let phi = rng.range(0.0, TAU);
                let r = (1.0 - z * z).sqrt();
                let direction = vec3(r * phi.cos(), r * phi.sin(), z);
                let frequency = base_frequency * 2f32.powi(k as i32);
                (
                    direction * frequency,
                    rng.range(0.0, TAU),
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
/// 1200 scattered rocks, seen from above the terrain's edge.
pub fn million_triangles() -> Scene {
    let mut rng = Pcg::new(7);
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
        let (x, z) = (rng.range(-11.0, 11.0), rng.range(-11.0, 11.0));
        let radius = rng.range(0.08, 0.45);
        let center = vec3(x, ground.at(vec3(x, 0.0, z)) + radius * 0.5, z);
        triangles.extend(displaced_sphere(center, radius, 10, 20, &bumps, 0.25));
    }
    Scene {
        name: "million_triangles",
        triangles,
        camera: Camera::look_at(
            vec3(0.0, 9.0, 17.0),
            vec3(0.0, 1.0, 0.0),
            55f32.to_radians(),
        ),
        light: QuadLight {
            corner: vec3(-4.0, 20.0, -4.0),
            edge_s: vec3(8.0, 0.0, 0.0),
            edge_t: vec3(0.0, 0.0, 8.0),
        },
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
    pub fn bounce_rays(&self, rng: &mut Pcg) -> RayBatch {
        let mut rays = RayBatch::with_capacity(self.len());
        for (&origin, &normal) in self.origins.iter().zip(&self.normals) {
            let (tangent, bitangent) = normal.any_orthonormal_pair();
            let (r, phi) = (rng.f32().sqrt(), rng.range(0.0, TAU));
            let local = vec3(r * phi.cos(), r * phi.sin(), (1.0 - r * r).max(0.0).sqrt());
            let direction = tangent * local.x + bitangent * local.y + normal * local.z;
            rays.push(origin, direction, 0.0, f32::INFINITY);
        }
        rays
    }

    /// Shadow rays from every point to a random point on `light`, stopping just short of it.
    pub fn shadow_rays(&self, light: &QuadLight, rng: &mut Pcg) -> RayBatch {
        let mut rays = RayBatch::with_capacity(self.len());
        for &origin in &self.origins {
            rays.push(origin, light.sample(rng) - origin, 0.0, 1.0 - 1e-4);
        }
        rays
    }
}
