//! Procedural shapes for generated scenes and tests.

use std::collections::HashMap;

use glam::Vec3;

/// A unit sphere around the origin as an icosahedron refined `subdivisions` times (each
/// triangle split in four, new vertices pushed onto the sphere): 20·4^subdivisions triangles,
/// counter-clockwise seen from outside (facing outward).
pub fn icosphere(subdivisions: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let phi = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ]
    .map(|(x, y, z)| Vec3::new(x, y, z).normalize())
    .to_vec();
    let mut triangles: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut midpoints = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                positions.push((positions[a as usize] + positions[b as usize]).normalize());
                positions.len() as u32 - 1
            })
        };
        triangles = triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let ab = midpoint(a, b, &mut positions);
                let bc = midpoint(b, c, &mut positions);
                let ca = midpoint(c, a, &mut positions);
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (positions, triangles)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_is_a_closed_outward_facing_unit_sphere() {
        for subdivisions in 0..3 {
            let (positions, triangles) = icosphere(subdivisions);
            assert_eq!(triangles.len(), 20 * 4usize.pow(subdivisions));
            // Euler: V − E + F = 2 with E = 3F/2 for a closed triangle mesh.
            assert_eq!(
                positions.len() + triangles.len() - 3 * triangles.len() / 2,
                2
            );
            assert!(positions.iter().all(|p| (p.length() - 1.0).abs() < 1e-6));
            for [a, b, c] in &triangles {
                let [a, b, c] = [a, b, c].map(|&i| positions[i as usize]);
                assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "inward triangle");
            }
        }
    }
}
