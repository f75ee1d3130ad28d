//! Random paths and the MIS weight every bidirectional technique gives them, for the test
//! that the weights are a partition of unity — of the CPU's weights (`mis.rs`) and, through
//! the same paths, of the GPU's. A path runs from the camera x₀ over surfaces with random
//! glossy or diffuse materials to a point x_k on an area light; its subpath quantities are
//! built with the `SubpathMis` updates the passes use, from the BSDFs' pdfs along the path.

use glam::{Vec2, Vec3};
use vcm_scene::Material;
use vcm_scene::bsdf::{Bsdf, BsdfParams, TransportMode};
use vcm_scene::sampling::{Rng, Sampler};

use super::mis::{
    ConnectionPdfs, LightSamplePdfs, MisFactors, SubpathMis, camera_connection_weight,
    connection_weight, emission_hit_weight, light_sample_weight, merge_weight,
};
use crate::Algorithm;

/// Area of the light triangle at the path's end.
pub const LIGHT_AREA: f32 = 0.3;
/// Area of one pixel on the image plane at unit distance.
pub const PIXEL_AREA: f32 = 1e-5;
/// Light paths per frame.
pub const LIGHT_PATHS: f32 = 4096.0;
/// Merge radius.
pub const RADIUS: f32 = 0.01;

/// A path x₀ (the camera) … x_k (a point on an area light) with a one-sided BSDF at every
/// inner vertex, whose shading normal is its geometric normal.
pub struct MisTestPath {
    /// x₀ … x_k.
    pub points: Vec<Vec3>,
    /// The geometric normal at each vertex.
    pub normals: Vec<Vec3>,
    /// The material at each inner vertex (`None` at the camera and the light).
    pub materials: Vec<Option<BsdfParams>>,
    /// The camera's viewing direction.
    pub camera_forward: Vec3,
    bsdfs: Vec<Option<Bsdf>>,
}

impl MisTestPath {
    /// A random path of `k` segments whose every vertex faces both neighbours at a cosine of
    /// at least 0.1.
    pub fn random(k: usize, rng: &mut Rng) -> MisTestPath {
        loop {
            let path = MisTestPath::candidate(k, rng);
            let faces = |i: usize, j: usize| path.normals[i].dot(path.dir(i, j)) > 0.1;
            let valid = (1..=k).all(|i| faces(i, i - 1) && (i == k || faces(i, i + 1)))
                && path.camera_forward.dot(path.dir(0, 1)) > 0.5;
            if valid {
                return path;
            }
        }
    }

    fn candidate(k: usize, rng: &mut Rng) -> MisTestPath {
        let mut u3 = || Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) * 2.0 - 1.0;
        let points: Vec<Vec3> = (0..=k).map(|_| u3() * 2.0).collect();
        let jitter: Vec<Vec3> = (0..=k).map(|_| u3() * 0.3).collect();
        let towards = |from: usize, to: usize| (points[to] - points[from]).normalize();
        let normals: Vec<Vec3> = (0..=k)
            .map(|i| {
                let mut n = jitter[i];
                if i > 0 {
                    n += towards(i, i - 1);
                }
                if i < k {
                    n += towards(i, i + 1);
                }
                n.normalize()
            })
            .collect();
        let mut materials = vec![None];
        for _ in 1..k {
            let material = Material {
                roughness: 0.3 + 0.7 * rng.uniform(),
                metallic: if rng.uniform() < 0.3 { 1.0 } else { 0.0 },
                ..Material::diffuse("test", Vec3::splat(0.7))
            };
            materials.push(Some(material.bsdf_params(&[], Vec2::ZERO)));
        }
        materials.push(None);
        let bsdfs = (materials.iter().zip(&normals))
            .map(|(params, &n)| params.map(|params| Bsdf::new(&params, n, n, false)))
            .collect();
        let camera_forward = (towards(0, 1) + jitter[0] * 0.5).normalize();
        MisTestPath {
            points,
            normals,
            materials,
            camera_forward,
            bsdfs,
        }
    }

    /// The number of segments, k.
    pub fn k(&self) -> usize {
        self.points.len() - 1
    }

    fn dir(&self, from: usize, to: usize) -> Vec3 {
        (self.points[to] - self.points[from]).normalize()
    }

    fn dist_sq(&self, a: usize, b: usize) -> f32 {
        self.points[a].distance_squared(self.points[b])
    }

    /// |cos| at vertex `at` toward vertex `to` (geometric normal).
    fn cos(&self, at: usize, to: usize) -> f32 {
        self.normals[at].dot(self.dir(at, to)).abs()
    }

    /// pdf at `at` of sampling the direction to `to` given the direction to `from`.
    fn pdf(&self, at: usize, from: usize, to: usize) -> f32 {
        let bsdf = self.bsdfs[at].as_ref().expect("inner vertex");
        let eval = bsdf.eval(
            self.dir(at, from),
            self.dir(at, to),
            TransportMode::Radiance,
        );
        assert!(eval.f_cos.max_element() > 0.0, "the path must carry light");
        eval.pdf_fwd
    }

    /// The solid-angle pdf of the camera ray x₀ → x₁: 1 / (A_pixel cos³).
    fn camera_pdf_w(&self) -> f32 {
        let cos = self.camera_forward.dot(self.dir(0, 1));
        1.0 / (PIXEL_AREA * cos.powi(3))
    }

    /// (direct pdf, emission pdf) of the light point x_k emitting toward x_{k−1}: 1 / A and
    /// cos / (π A).
    fn light_pdfs(&self) -> (f32, f32) {
        let k = self.k();
        let cos = self.cos(k, k - 1);
        (
            1.0 / LIGHT_AREA,
            cos * std::f32::consts::FRAC_1_PI / LIGHT_AREA,
        )
    }

    /// The MIS factors at inner vertex `i`: without the merge beside the light x_k.
    fn factors_at(&self, i: usize, factors: &MisFactors) -> MisFactors {
        if i == self.k() - 1 {
            factors.beside_light()
        } else {
            *factors
        }
    }

    /// The camera subpath's quantities on arriving at vertex `j` (1 ≤ j ≤ k).
    fn camera_mis(&self, j: usize, factors: &MisFactors) -> SubpathMis {
        let mut mis = SubpathMis::camera(self.camera_pdf_w(), factors);
        for i in 1..=j {
            if i > 1 {
                let (fwd, rev) = (self.pdf(i - 1, i - 2, i), self.pdf(i - 1, i, i - 2));
                let here = self.factors_at(i - 1, factors);
                mis.scatter(self.cos(i - 1, i), fwd, rev, false, &here);
            }
            mis.arrive(Some(self.dist_sq(i - 1, i)), self.cos(i, i - 1));
        }
        mis
    }

    /// The light subpath's quantities on arriving at vertex `j` (1 ≤ j < k).
    fn light_mis(&self, j: usize, factors: &MisFactors) -> SubpathMis {
        let k = self.k();
        let (direct, emission) = self.light_pdfs();
        let cos_light = self.cos(k, k - 1);
        let mut mis = SubpathMis::light(direct, emission, cos_light, false, true, factors);
        for i in (j..k).rev() {
            if i < k - 1 {
                let (fwd, rev) = (self.pdf(i + 1, i + 2, i), self.pdf(i + 1, i, i + 2));
                let here = self.factors_at(i + 1, factors);
                mis.scatter(self.cos(i + 1, i), fwd, rev, false, &here);
            }
            mis.arrive(Some(self.dist_sq(i + 1, i)), self.cos(i, i + 1));
        }
        mis
    }

    /// The MIS factors of `algorithm` for these paths: [η_VCM where merging, 1/η_VCM where
    /// connecting and merging, 1/η_VCM where merging, 1 where connecting].
    pub fn factors(algorithm: Algorithm) -> [f32; 4] {
        let f = Self::mis_factors(algorithm);
        [f.merge, f.connect, f.hit, f.connections]
    }

    fn mis_factors(algorithm: Algorithm) -> MisFactors {
        MisFactors::new(
            algorithm.connects(),
            algorithm.merges(),
            RADIUS,
            LIGHT_PATHS,
        )
    }

    /// The weights of every technique of `algorithm` that samples this path, as the passes
    /// compute them, in this order: the camera path hitting the light; where the algorithm
    /// connects, the light sample at x_{k−1}, the connections of camera vertex x_t to light
    /// vertex x_{t+1} for t = 1 … k − 2, the splat of light vertex x₁ through the camera;
    /// where it merges, the merges at x_j for j = 1 … k − 1 (… k − 2 where it connects too).
    pub fn weights(&self, algorithm: Algorithm) -> Vec<f32> {
        let factors = Self::mis_factors(algorithm);
        let k = self.k();
        let mut weights = Vec::new();
        let (direct, emission) = self.light_pdfs();
        weights.push(emission_hit_weight(
            &self.camera_mis(k, &factors),
            direct,
            emission,
            &factors,
        ));
        if algorithm.connects() {
            let pdfs = LightSamplePdfs {
                direct_pdf_w: direct * self.dist_sq(k - 1, k) / self.cos(k, k - 1),
                emission_pdf_w: emission,
                cos_at_light: self.cos(k, k - 1),
                cos_at_receiver: self.cos(k - 1, k),
                bsdf_fwd_pdf_w: self.pdf(k - 1, k - 2, k),
                bsdf_rev_pdf_w: self.pdf(k - 1, k, k - 2),
            };
            weights.push(light_sample_weight(
                &self.camera_mis(k - 1, &factors),
                &pdfs,
                &factors,
            ));
            for t in 1..k.saturating_sub(1) {
                let d2 = self.dist_sq(t, t + 1);
                let pdfs = ConnectionPdfs {
                    camera_fwd_pdf_a: self.pdf(t, t - 1, t + 1) * self.cos(t + 1, t) / d2,
                    camera_rev_pdf_w: self.pdf(t, t + 1, t - 1),
                    light_fwd_pdf_a: self.pdf(t + 1, t + 2, t) * self.cos(t, t + 1) / d2,
                    light_rev_pdf_w: self.pdf(t + 1, t, t + 2),
                };
                weights.push(connection_weight(
                    (
                        &self.camera_mis(t, &factors),
                        &self.light_mis(t + 1, &factors),
                    ),
                    &pdfs,
                    (&factors, &self.factors_at(t + 1, &factors)),
                ));
            }
            let camera_pdf_a = self.camera_pdf_w() * self.cos(1, 0) / self.dist_sq(0, 1);
            weights.push(camera_connection_weight(
                &self.light_mis(1, &factors),
                camera_pdf_a,
                self.pdf(1, 0, 2),
                &self.factors_at(1, &factors),
            ));
        }
        if algorithm.merges() {
            // Where connections run, nothing merges beside the light.
            let last = if algorithm.connects() { k - 1 } else { k };
            for j in 1..last {
                weights.push(merge_weight(
                    &self.camera_mis(j, &factors),
                    &self.light_mis(j, &factors),
                    self.pdf(j, j - 1, j + 1),
                    self.pdf(j, j + 1, j - 1),
                    &factors,
                ));
            }
        }
        weights
    }
}
