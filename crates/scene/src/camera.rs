//! The pinhole camera: glTF perspective cameras look down their local -Z axis with +Y up.

use glam::{Mat4, Vec2, Vec3};

use crate::mesh::Bounds;

/// A pinhole perspective camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position (world space).
    pub position: Vec3,
    /// Unit vector to the right of the image.
    pub right: Vec3,
    /// Unit vector to the top of the image.
    pub up: Vec3,
    /// Unit viewing direction (the camera's local -Z).
    pub forward: Vec3,
    /// Full vertical field of view in radians.
    pub yfov: f32,
    /// Width / height from the file, if it gives one (the output size may override it).
    pub aspect_ratio: Option<f32>,
}

impl Camera {
    /// A camera from its node's world transform (scale and shear are removed).
    pub fn from_transform(world: Mat4, yfov: f32, aspect_ratio: Option<f32>) -> Option<Camera> {
        let right = world.x_axis.truncate().try_normalize()?;
        let up_raw = world.y_axis.truncate();
        let forward = (-world.z_axis.truncate()).try_normalize()?;
        let up = (up_raw - forward * forward.dot(up_raw)).try_normalize()?;
        let valid = yfov.is_finite() && yfov > 0.0 && yfov < std::f32::consts::PI;
        valid.then_some(Camera {
            position: world.w_axis.truncate(),
            right: forward.cross(up).try_normalize().unwrap_or(right),
            up,
            forward,
            yfov,
            aspect_ratio: aspect_ratio.filter(|a| a.is_finite() && *a > 0.0),
        })
    }

    /// The default camera: frames `bounds` from +Z with a 45° vertical field of view.
    pub fn framing(bounds: &Bounds) -> Camera {
        let yfov = 45f32.to_radians();
        let (center, radius) = if bounds.is_empty() {
            (Vec3::ZERO, 1.0)
        } else {
            (bounds.center(), bounds.radius().max(f32::MIN_POSITIVE))
        };
        let distance = radius / (0.5 * yfov).sin();
        Camera {
            position: center + Vec3::Z * distance,
            right: Vec3::X,
            up: Vec3::Y,
            forward: -Vec3::Z,
            yfov,
            aspect_ratio: None,
        }
    }

    /// The camera's projection onto a `width` × `height` image.
    pub fn projection(&self, width: u32, height: u32) -> Projection {
        let tan_y = (0.5 * self.yfov).tan();
        Projection {
            camera: *self,
            size: Vec2::new(width as f32, height as f32),
            half_extent: Vec2::new(tan_y * width as f32 / height as f32, tan_y),
        }
    }

    /// The unit direction through the raster position `raster` of a `width` × `height`
    /// image (see [`Projection::direction`]).
    #[inline]
    pub fn direction(&self, width: u32, height: u32, raster: Vec2) -> Vec3 {
        self.projection(width, height).direction(raster)
    }

    /// Where `point` appears in a `width` × `height` image (see [`Projection::raster_of`]).
    pub fn raster_of(&self, width: u32, height: u32, point: Vec3) -> Option<Vec2> {
        self.projection(width, height).raster_of(point)
    }

    /// Area of one pixel of a `width` × `height` image (see [`Projection::pixel_area`]).
    pub fn pixel_area(&self, width: u32, height: u32) -> f32 {
        self.projection(width, height).pixel_area()
    }
}

/// A perspective camera that a node of a glTF file places in the scene
/// ([`Scene::cameras`](crate::Scene::cameras)).
#[derive(Clone, Debug, PartialEq)]
pub struct FileCamera {
    /// Index of the camera in the file's `cameras` array.
    pub index: usize,
    /// The camera's name in the file, if it has one.
    pub name: Option<String>,
    /// The name of the node that places it, if that node has one.
    pub node: Option<String>,
    /// The camera where the node places it.
    pub camera: Camera,
}

impl FileCamera {
    /// Whether `choice` is this camera's name or its node's name.
    pub fn is_named(&self, choice: &str) -> bool {
        self.name.as_deref() == Some(choice) || self.node.as_deref() == Some(choice)
    }
}

impl std::fmt::Display for FileCamera {
    /// The index, then the names the camera answers to: `1 'Top' (node 'TopCamera')`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.index)?;
        if let Some(name) = &self.name {
            write!(f, " '{name}'")?;
        }
        if let Some(node) = &self.node {
            write!(f, " (node '{node}')")?;
        }
        Ok(())
    }
}

/// A camera's mapping between an image's raster positions and directions, with the image
/// plane's extent worked out once (a tangent) for all the rays of that image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    camera: Camera,
    /// Image width and height in pixels.
    size: Vec2,
    /// Half extents of the image plane at unit distance: (tan(xfov/2), tan(yfov/2)).
    half_extent: Vec2,
}

impl Projection {
    /// Half extents of the image plane at unit distance: (tan(xfov/2), tan(yfov/2)).
    pub fn half_extent(&self) -> Vec2 {
        self.half_extent
    }

    /// The unit direction through the raster position `raster` (pixels; (0,0) is the top-left
    /// corner of the image, (width, height) the bottom-right).
    #[inline]
    pub fn direction(&self, raster: Vec2) -> Vec3 {
        let [[x], [y], [z]] = self.directions([[raster.x], [raster.y]]);
        Vec3::new(x, y, z)
    }

    /// [`direction`](Self::direction) of each of `L` raster positions, given as their x
    /// and y coordinates, in loops over the lanes that the compiler vectorizes: for starting
    /// many camera paths at once. Each lane gets the bits a one-lane call gives it.
    #[inline(always)]
    pub fn directions<const L: usize>(&self, raster: [[f32; L]; 2]) -> [[f32; L]; 3] {
        let (c, h) = (&self.camera, self.half_extent);
        let mut out = [[0.0; L]; 3];
        for lane in 0..L {
            let ndc_x = 2.0 * raster[0][lane] / self.size.x - 1.0;
            let ndc_y = 1.0 - 2.0 * raster[1][lane] / self.size.y;
            let (a, b) = (ndc_x * h.x, ndc_y * h.y);
            for (axis, coordinate) in out.iter_mut().enumerate() {
                coordinate[lane] = c.forward[axis] + c.right[axis] * a + c.up[axis] * b;
            }
        }
        for lane in 0..L {
            let [x, y, z] = [out[0][lane], out[1][lane], out[2][lane]];
            // `Vec3::normalize`: times the reciprocal of the length.
            let inv_length = 1.0 / (x * x + y * y + z * z).sqrt();
            for axis in &mut out {
                axis[lane] *= inv_length;
            }
        }
        out
    }

    /// The raster position where `point` appears, or `None` when it is behind the camera or
    /// outside the image.
    pub fn raster_of(&self, point: Vec3) -> Option<Vec2> {
        let (c, h) = (&self.camera, self.half_extent);
        let d = point - c.position;
        let z = d.dot(c.forward);
        if z <= 0.0 {
            return None;
        }
        let ndc = Vec2::new(d.dot(c.right) / (z * h.x), d.dot(c.up) / (z * h.y));
        let raster = Vec2::new(
            (ndc.x + 1.0) * 0.5 * self.size.x,
            (1.0 - ndc.y) * 0.5 * self.size.y,
        );
        let inside =
            raster.x >= 0.0 && raster.y >= 0.0 && raster.x < self.size.x && raster.y < self.size.y;
        inside.then_some(raster)
    }

    /// Area of one pixel on the image plane at unit distance from the eye. The camera's
    /// directional pdf per pixel sample is `distance² / (pixel_area · cos³θ)` in solid angle.
    pub fn pixel_area(&self) -> f32 {
        let h = self.half_extent;
        4.0 * h.x * h.y / (self.size.x * self.size.y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ray_and_projection_are_inverse() {
        let cam = Camera::from_transform(
            Mat4::from_translation(Vec3::new(0.0, 1.0, 5.0)),
            0.8,
            Some(1.5),
        )
        .unwrap();
        for raster in [
            Vec2::new(10.5, 20.25),
            Vec2::new(299.0, 0.5),
            Vec2::new(150.0, 100.0),
        ] {
            let dir = cam.direction(300, 200, raster);
            let back = cam.raster_of(300, 200, cam.position + dir * 7.0).unwrap();
            assert!((back - raster).length() < 1e-3, "{raster} -> {back}");
        }
        let center = cam.direction(300, 200, Vec2::new(150.0, 100.0));
        assert!((center - -Vec3::Z).length() < 1e-6);
        assert!(cam.raster_of(300, 200, Vec3::new(0.0, 1.0, 9.0)).is_none());
    }

    #[test]
    fn directions_in_lanes_are_those_of_one_ray_at_a_time_bit_for_bit() {
        let transform =
            Mat4::from_rotation_y(0.3) * Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0));
        let cam = Camera::from_transform(transform, 0.7, Some(1.3)).unwrap();
        let projection = cam.projection(301, 199);
        // Corners, the centre, and positions that are not round numbers.
        let rasters = [
            Vec2::new(0.0, 0.0),
            Vec2::new(301.0, 199.0),
            Vec2::new(150.5, 99.5),
            Vec2::new(0.123, 198.999),
            Vec2::new(300.7, 0.001),
            Vec2::new(17.25, 61.875),
            Vec2::new(255.9, 3.3),
            Vec2::new(1e-6, 100.0),
        ];
        let lanes = projection.directions([rasters.map(|r| r.x), rasters.map(|r| r.y)]);
        for (lane, &raster) in rasters.iter().enumerate() {
            let one = projection.direction(raster);
            let bits = |v: [f32; 3]| v.map(f32::to_bits);
            let in_lanes = [lanes[0][lane], lanes[1][lane], lanes[2][lane]];
            assert_eq!(bits(in_lanes), bits(one.to_array()), "{raster}");
        }
    }

    #[test]
    fn vertical_field_of_view_spans_the_image_height() {
        let cam = Camera::from_transform(Mat4::IDENTITY, 1.0, None).unwrap();
        let top = cam.direction(100, 100, Vec2::new(50.0, 0.0));
        let angle = top.angle_between(-Vec3::Z);
        assert!((angle - 0.5).abs() < 1e-5);
    }

    #[test]
    fn framing_sees_the_whole_box() {
        let bounds = Bounds {
            min: Vec3::splat(-2.0),
            max: Vec3::splat(2.0),
        };
        let cam = Camera::framing(&bounds);
        for corner in [bounds.min, bounds.max, Vec3::new(2.0, -2.0, 2.0)] {
            assert!(cam.raster_of(64, 64, corner).is_some(), "{corner}");
        }
    }
}
