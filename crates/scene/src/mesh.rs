//! Triangle geometry in world space: one flat vertex array for the whole scene.

use glam::{Vec2, Vec3, Vec4};

/// An axis-aligned bounding box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Bounds {
    /// The empty box (grows to anything).
    pub const EMPTY: Bounds = Bounds {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// True when nothing was added.
    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    /// Center of the box.
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Radius of the bounding sphere around [`Bounds::center`].
    pub fn radius(&self) -> f32 {
        (self.max - self.min).length() * 0.5
    }
}

/// All triangles of a scene, flattened and transformed to world space.
///
/// Vertex attributes are always present: a zero normal or tangent means "absent" (the geometric
/// normal or a generated frame is used instead).
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions (world space).
    pub positions: Vec<Vec3>,
    /// Vertex normals (world space, unit) or zero.
    pub normals: Vec<Vec3>,
    /// Texture coordinates (set 0).
    pub uvs: Vec<Vec2>,
    /// Tangents (world space xyz, bitangent sign in w) or zero.
    pub tangents: Vec<Vec4>,
    /// Vertex colors (glTF `COLOR_0`: linear RGB in [0, 1], multiplying the base color), one
    /// per vertex, or empty when no vertex has a color other than white.
    pub colors: Vec<Vec3>,
    /// Vertex indices of each triangle, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle.
    pub material_ids: Vec<u32>,
}

/// A point on a surface, with everything shading needs.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    /// World-space position.
    pub position: Vec3,
    /// Unit geometric normal from the winding order (the front side).
    pub geometric_normal: Vec3,
    /// Unit shading normal (interpolated, normal-mapped), in the geometric normal's hemisphere.
    pub shading_normal: Vec3,
    /// Texture coordinates.
    pub uv: Vec2,
    /// The interpolated vertex color, which multiplies the material's base color (white
    /// where the mesh has no vertex colors).
    pub vertex_color: Vec3,
    /// Material index.
    pub material: u32,
    /// Triangle index.
    pub triangle: u32,
}

/// Unit normal of the triangle with corners `[a, b, c]` (counter-clockwise winding faces it),
/// zero for a degenerate triangle.
#[inline]
fn normal_of([a, b, c]: &[Vec3; 3]) -> Vec3 {
    (*b - *a).cross(*c - *a).normalize_or_zero()
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    #[inline]
    pub fn corners(&self, t: usize) -> [Vec3; 3] {
        self.triangles[t].map(|i| self.positions[i as usize])
    }

    /// Surface area of triangle `t`.
    pub fn area(&self, t: usize) -> f32 {
        let [a, b, c] = self.corners(t);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Unit geometric normal of triangle `t` (counter-clockwise winding faces it).
    #[inline]
    pub fn geometric_normal(&self, t: usize) -> Vec3 {
        normal_of(&self.corners(t))
    }

    /// Texture coordinates at barycentrics (u, v) on triangle `t`.
    #[inline]
    pub fn uv_at(&self, t: usize, u: f32, v: f32) -> Vec2 {
        let [i0, i1, i2] = self.triangles[t].map(|i| i as usize);
        self.uvs[i0] * (1.0 - u - v) + self.uvs[i1] * u + self.uvs[i2] * v
    }

    /// The vertex color at (u, v) on triangle `t` (white without vertex colors). Interpolated
    /// from the first corner, so a triangle with three equal corners has exactly their color.
    #[inline]
    pub fn color_at(&self, t: usize, u: f32, v: f32) -> Vec3 {
        if self.colors.is_empty() {
            return Vec3::ONE;
        }
        let [c0, c1, c2] = self.triangles[t].map(|i| self.colors[i as usize]);
        c0 + (c1 - c0) * u + (c2 - c0) * v
    }

    /// Per material (`material_count` of them), whether a triangle using it has a vertex
    /// color other than white: its base color then varies over the surface.
    pub fn tinted_materials(&self, material_count: usize) -> Vec<bool> {
        let mut tinted = vec![false; material_count];
        if !self.colors.is_empty() {
            for (tri, &material) in self.triangles.iter().zip(&self.material_ids) {
                if tri.iter().any(|&i| self.colors[i as usize] != Vec3::ONE) {
                    tinted[material as usize] = true;
                }
            }
        }
        tinted
    }

    /// The unit-length interpolated vertex normal at (u, v), or `fallback` where the
    /// interpolation vanishes.
    #[inline]
    fn interpolated_normal(&self, t: usize, u: f32, v: f32, fallback: Vec3) -> Vec3 {
        let [i0, i1, i2] = self.triangles[t].map(|i| i as usize);
        let n = self.normals[i0] * (1.0 - u - v) + self.normals[i1] * u + self.normals[i2] * v;
        n.try_normalize().unwrap_or(fallback)
    }

    /// The interpolated vertex tangent at (u, v) (handedness in w).
    fn interpolated_tangent(&self, t: usize, u: f32, v: f32) -> Vec4 {
        let [i0, i1, i2] = self.triangles[t].map(|i| i as usize);
        self.tangents[i0] * (1.0 - u - v) + self.tangents[i1] * u + self.tangents[i2] * v
    }

    /// The surface point at barycentrics (u, v) on triangle `t`, with texture coordinates
    /// `uv` (computed by the caller, who may need them first).
    ///
    /// `normal_map` is the tangent-space normal from the material's normal map, if any; only
    /// then are tangents interpolated.
    #[inline]
    pub fn surface_point(
        &self,
        t: usize,
        u: f32,
        v: f32,
        uv: Vec2,
        normal_map: Option<Vec3>,
    ) -> SurfacePoint {
        let corners = self.corners(t);
        let geometric_normal = normal_of(&corners);
        let mut shading = self.interpolated_normal(t, u, v, geometric_normal);
        if let Some(m) = normal_map {
            let tangent = self.interpolated_tangent(t, u, v);
            if let Some(tan) = tangent.truncate().try_normalize() {
                let sign = if tangent.w < 0.0 { -1.0 } else { 1.0 };
                let tan = (tan - shading * shading.dot(tan)).normalize_or_zero();
                let bitangent = shading.cross(tan) * sign;
                let mapped = tan * m.x + bitangent * m.y + shading * m.z;
                shading = mapped.try_normalize().unwrap_or(shading);
            }
        }
        if shading.dot(geometric_normal) < 0.0 {
            shading = -shading;
        }
        SurfacePoint {
            position: corners[0] * (1.0 - u - v) + corners[1] * u + corners[2] * v,
            geometric_normal,
            shading_normal: shading,
            uv,
            vertex_color: self.color_at(t, u, v),
            material: self.material_ids[t],
            triangle: t as u32,
        }
    }

    /// Bounding box of all vertices that triangles use.
    pub fn bounds(&self) -> Bounds {
        let mut bounds = Bounds::EMPTY;
        for tri in &self.triangles {
            for &i in tri {
                bounds.grow(self.positions[i as usize]);
            }
        }
        bounds
    }

    /// Generates per-vertex tangents from texture coordinates for the triangles in `range`
    /// (used where a normal map needs them and the file has none).
    ///
    /// Per-triangle tangents (from the UV parameterization) are accumulated on the vertices,
    /// weighted by triangle area, then orthogonalized against the vertex normal (Lengyel's method).
    pub fn generate_tangents(&mut self, range: std::ops::Range<usize>) {
        let mut tangent = vec![Vec3::ZERO; self.positions.len()];
        let mut bitangent = vec![Vec3::ZERO; self.positions.len()];
        for tri in &self.triangles[range.clone()] {
            let [i0, i1, i2] = tri.map(|i| i as usize);
            let (e1, e2) = (
                self.positions[i1] - self.positions[i0],
                self.positions[i2] - self.positions[i0],
            );
            let (d1, d2) = (self.uvs[i1] - self.uvs[i0], self.uvs[i2] - self.uvs[i0]);
            let det = d1.x * d2.y - d2.x * d1.y;
            if det.abs() < 1e-20 || !det.is_finite() {
                continue;
            }
            let t = (e1 * d2.y - e2 * d1.y) / det;
            let b = (e2 * d1.x - e1 * d2.x) / det;
            for i in [i0, i1, i2] {
                tangent[i] += t;
                bitangent[i] += b;
            }
        }
        for tri in &self.triangles[range] {
            for &i in tri {
                let i = i as usize;
                let n = self.normals[i].try_normalize().unwrap_or(Vec3::ZERO);
                let t = (tangent[i] - n * n.dot(tangent[i])).normalize_or_zero();
                // glTF's v runs down the image while a normal map's +Y points up it, so the
                // bitangent N × T · w must point along −∂P/∂v (as MikkTSpace's does).
                let sign = if n.cross(t).dot(bitangent[i]) > 0.0 {
                    -1.0
                } else {
                    1.0
                };
                self.tangents[i] = t.extend(sign);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The unit square in z = 0 facing +z, textured as glTF maps an image onto it: v = 0 at
    /// the top of the image, here y = 1.
    fn quad() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            normals: vec![Vec3::Z; 4],
            uvs: vec![Vec2::Y, Vec2::ONE, Vec2::X, Vec2::ZERO],
            tangents: vec![Vec4::ZERO; 4],
            colors: Vec::new(),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            material_ids: vec![0, 0],
        }
    }

    #[test]
    fn vertex_colors_interpolate_and_mark_their_materials() {
        let mut m = quad();
        m.material_ids = vec![0, 1];
        assert_eq!(m.color_at(0, 0.3, 0.3), Vec3::ONE);
        assert_eq!(m.tinted_materials(2), [false, false]);
        let red = Vec3::new(0.8, 0.1, 0.1);
        // Vertex 1 belongs to the first triangle only.
        m.colors = vec![red, Vec3::ZERO, red, red];
        assert_eq!(m.tinted_materials(2), [true, true]);
        assert_eq!(
            m.color_at(1, 0.3, 0.6),
            red,
            "equal corners give exactly their color"
        );
        let p = m.surface_point(0, 0.25, 0.5, Vec2::ZERO, None);
        assert!(
            (p.vertex_color - red * 0.75).length() < 1e-6,
            "{}",
            p.vertex_color
        );
        m.colors[0] = Vec3::ONE;
        m.colors[2] = Vec3::ONE;
        m.colors[3] = Vec3::ONE;
        assert_eq!(m.tinted_materials(2), [true, false]);
    }

    #[test]
    fn geometry_queries() {
        let m = quad();
        assert_eq!(m.geometric_normal(0), Vec3::Z);
        assert!((m.area(0) - 0.5).abs() < 1e-6);
        let p = m.surface_point(0, 0.5, 0.25, m.uv_at(0, 0.5, 0.25), None);
        assert!((p.position - Vec3::new(0.75, 0.25, 0.0)).length() < 1e-6);
        assert_eq!(m.bounds().max, Vec3::new(1.0, 1.0, 0.0));
    }

    /// Generated tangents follow +u, and a normal map's +X and +Y (green: up the image) tilt
    /// the shading normal toward the image's right and top, as MikkTSpace tangents do.
    #[test]
    fn generated_tangents_follow_u_and_normal_map_tilts_shading_normal() {
        let mut m = quad();
        m.generate_tangents(0..2);
        for t in &m.tangents {
            assert!((t.truncate() - Vec3::X).length() < 1e-5, "{t}");
            assert_eq!(t.w, 1.0);
        }
        for tilted in [Vec3::new(0.6, 0.0, 0.8), Vec3::new(0.0, 0.6, 0.8)] {
            let p = m.surface_point(0, 0.3, 0.3, m.uv_at(0, 0.3, 0.3), Some(tilted));
            assert!((p.shading_normal - tilted).length() < 1e-5, "{tilted}");
        }
    }

    #[test]
    fn shading_normal_is_flipped_into_the_geometric_hemisphere() {
        let mut m = quad();
        m.normals = vec![-Vec3::Z; 4];
        let p = m.surface_point(1, 0.2, 0.2, m.uv_at(1, 0.2, 0.2), None);
        assert_eq!(p.shading_normal, Vec3::Z);
    }
}
