//! The first rays of new camera paths, computed for several paths at once.

use glam::Vec3;
use vcm_scene::camera::Projection;
use vcm_scene::sampling::SobolSampler;

use crate::lanes::LANES;

/// The unit directions of the camera rays of `paths` (at most [`LANES`]; the rest of the
/// array repeats the last), each through its pixel jittered uniformly:
/// `projection.direction(xy + sampler.uniform2())` for each path's pixel (`y · width + x`)
/// and sampler as `parts` gives them, the same bits, with the samplers' first pairs and
/// the directions computed in SIMD lanes. The samplers do not move: the caller skips the
/// pair each one used.
pub(crate) fn jittered_directions<P>(
    paths: &[P],
    projection: &Projection,
    width: u32,
    parts: impl Fn(&P) -> (u32, &SobolSampler),
) -> [Vec3; LANES] {
    debug_assert!(!paths.is_empty() && paths.len() <= LANES);
    let at = |lane: usize| parts(&paths[lane.min(paths.len() - 1)]);
    let samplers: [&SobolSampler; LANES] = std::array::from_fn(|lane| at(lane).1);
    let [[jitter_x, jitter_y]] = SobolSampler::peek_lanes(samplers, [0]);
    let mut raster = [[0.0; LANES]; 2];
    for lane in 0..LANES {
        let pixel = at(lane).0;
        raster[0][lane] = (pixel % width) as f32 + jitter_x[lane];
        raster[1][lane] = (pixel / width) as f32 + jitter_y[lane];
    }
    let [x, y, z] = projection.directions(raster);
    std::array::from_fn(|lane| Vec3::new(x[lane], y[lane], z[lane]))
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, UVec2, Vec2};
    use vcm_scene::camera::Camera;
    use vcm_scene::sampling::Sampler;

    use super::*;

    #[test]
    fn directions_are_those_of_one_path_at_a_time_bit_for_bit() {
        let camera = Camera::from_transform(Mat4::from_rotation_x(0.2), 0.9, None).unwrap();
        let (width, height) = (37, 23);
        let projection = camera.projection(width, height);
        let paths: Vec<(u32, SobolSampler)> = (0..5)
            .map(|k| {
                (
                    k * 170 % (width * height),
                    SobolSampler::new(&[9, u64::from(k)], 3),
                )
            })
            .collect();
        let directions =
            jittered_directions(&paths, &projection, width, |(pixel, rng)| (*pixel, rng));
        for (lane, (pixel, rng)) in paths.iter().enumerate() {
            let mut rng = rng.clone();
            let xy = UVec2::new(pixel % width, pixel / width).as_vec2();
            let raster: Vec2 = xy + rng.uniform2();
            let one = projection.direction(raster);
            assert_eq!(
                directions[lane].to_array().map(f32::to_bits),
                one.to_array().map(f32::to_bits)
            );
        }
        assert_eq!(directions[5..], [directions[4]; 3]);
    }
}
