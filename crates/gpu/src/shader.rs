//! Composing the kernels from the WGSL sources in this crate's `shaders/` and the traversal
//! functions of vcm-traversal-wgpu (WGSL has no includes).

use vcm::hash_grid::HashGrid;
use vcm::ray_offset::gamma;
use vcm_scene::bsdf::{ALBEDO_TABLE_SIZE, MIN_ALPHA};

/// The CPU's numbers: keyed hashes and Owen-scrambled Sobol pairs.
pub const SAMPLER_WGSL: &str = include_str!("../shaders/sampler.wgsl");
/// The surface scattering model.
pub const BSDF_WGSL: &str = include_str!("../shaders/bsdf.wgsl");
/// Textures, and materials that vary over their surface.
pub const MATERIAL_WGSL: &str = include_str!("../shaders/material.wgsl");
/// The dispatch's parameters, the scene's shading data and what every kernel does with it.
pub const SCENE_WGSL: &str = include_str!("../shaders/scene.wgsl");
/// The frame's film on the device: exact sums with atomic additions.
pub const FILM_WGSL: &str = include_str!("../shaders/film.wgsl");
/// The path tracing kernel.
pub const PATH_TRACER_WGSL: &str = include_str!("../shaders/path_tracer.wgsl");
/// The light vertex cache's and the hash grids' layouts, and the grid's bucket hash.
pub const CACHE_WGSL: &str = include_str!("../shaders/cache.wgsl");
/// The light vertex index built on the device.
pub const INDEX_WGSL: &str = include_str!("../shaders/index.wgsl");
/// The hash grids built on the device.
pub const GRID_WGSL: &str = include_str!("../shaders/grid.wgsl");
/// What the bidirectional kernels share: MIS quantities and weights, the light vertex cache.
pub const BIDIR_WGSL: &str = include_str!("../shaders/bidir.wgsl");
/// The light pass: light tracing, or the bidirectional algorithms' light vertices.
pub const LIGHT_TRACER_WGSL: &str = include_str!("../shaders/light_tracer.wgsl");
/// The camera pass of bidirectional path tracing.
pub const BIDIR_CAMERA_WGSL: &str = include_str!("../shaders/bidir_camera.wgsl");

/// Invocations per workgroup (`WORKGROUP` in `scene.wgsl`): the traversal backend's, whose
/// [`dispatch_shape`](vcm_traversal_wgpu::dispatch_shape) sizes the dispatches.
pub const WORKGROUP_SIZE: u32 = vcm_traversal_wgpu::shader::WORKGROUP_SIZE;

/// A kernel of this crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// The path tracer's wavefront (`path_tracer.wgsl`): paths started at the camera, then
    /// taken one vertex further and their shadow rays traced round by round.
    PathTracer,
    /// Each invocation follows one light path to its end, and for light tracing alone takes
    /// one camera sample's first hit (`light_tracer.wgsl`).
    LightTracer,
    /// Each invocation follows one camera path of bidirectional path tracing to its end
    /// (`bidir_camera.wgsl`).
    BidirCamera,
}

impl Kernel {
    /// Every kernel.
    pub const ALL: [Kernel; 3] = [Kernel::PathTracer, Kernel::LightTracer, Kernel::BidirCamera];

    /// Its main entry point, whose pipeline its bind groups are made for (the stages of a
    /// kernel of several share one layout).
    pub fn entry(self) -> &'static str {
        match self {
            Kernel::PathTracer => "extend_paths",
            Kernel::LightTracer => "trace_light_paths",
            Kernel::BidirCamera => "connect_camera_paths",
        }
    }

    /// Its entry points, the first dispatched over the frame's invocations; for the path
    /// tracer then, round by round, the paths taken one vertex further, their shadow rays
    /// and the queues advanced (indirect dispatches), and the last paths taken to their end.
    pub fn stages(self) -> &'static [&'static str] {
        match self {
            Kernel::PathTracer => &[
                "start_paths",
                "extend_paths",
                "trace_shadows",
                "advance_paths",
                "finish_paths",
            ],
            Kernel::LightTracer => &["trace_light_paths"],
            Kernel::BidirCamera => &["connect_camera_paths"],
        }
    }

    /// The bindings of its bind group 0: 0 the parameters, 1–4 the film (sums, dropped
    /// samples), 5 the ray counts; for the light pass 6 the cache's index; for both
    /// bidirectional passes 7 the cache and 8 the iterations; for the camera pass 9 and 10
    /// the hash grids' bucket starts and entries; for the path tracer 11 the paths' states,
    /// 12 the queues and 13 their counts; for the light pass 14 the light paths' first
    /// vertices.
    pub fn dispatch_bindings(self) -> &'static [u32] {
        match self {
            Kernel::PathTracer => &[0, 1, 2, 3, 4, 5, 11, 12, 13],
            Kernel::LightTracer => &[0, 1, 2, 3, 4, 5, 6, 7, 8, 14],
            Kernel::BidirCamera => &[0, 1, 2, 3, 4, 5, 7, 8, 9, 10],
        }
    }

    /// Its own sources, which follow [`SCENE_WGSL`] and [`FILM_WGSL`].
    fn sources(self) -> &'static [&'static str] {
        match self {
            Kernel::PathTracer => &[PATH_TRACER_WGSL],
            Kernel::LightTracer => &[CACHE_WGSL, BIDIR_WGSL, LIGHT_TRACER_WGSL],
            Kernel::BidirCamera => &[CACHE_WGSL, BIDIR_WGSL, BIDIR_CAMERA_WGSL],
        }
    }
}

/// The bind group of the scene's shading data: 2, or 3 where the traversal functions test
/// alpha masks, whose buffers are their group 2.
pub fn shading_group(alpha_masks: bool) -> u32 {
    if alpha_masks { 3 } else { 2 }
}

/// The module of `kernel` over `traversal` (the traversal functions of the scene's
/// hierarchy, [`vcm_traversal_wgpu::GpuBvh::traversal_functions`], with or without
/// `alpha_masks`).
pub fn kernel_module(kernel: Kernel, traversal: &str, alpha_masks: bool) -> String {
    let constants = host_constants();
    // The shading data's bindings are written as group 2 in scene.wgsl.
    let group = shading_group(alpha_masks);
    let scene = SCENE_WGSL.replace("@group(2)", &format!("@group({group})"));
    let kernel = kernel.sources().join("\n");
    format!(
        "{constants}{traversal}\n{SAMPLER_WGSL}\n{BSDF_WGSL}\n{MATERIAL_WGSL}\n{scene}\n\
         {FILM_WGSL}\n{kernel}"
    )
}

/// The constants the host defines for the shaders: the CPU's rounding-error factors, GGX
/// width floor and hash grid reach, written so that they parse to the same f32, and the
/// layout of the lookup tables.
pub fn host_constants() -> String {
    let (columns, rows) = ALBEDO_TABLE_SIZE;
    // Where each table starts in `tables`: A and B (rows × columns each), their row
    // averages, the sRGB table.
    let a_average = 2 * rows * columns;
    let (b_average, srgb) = (a_average + rows, a_average + 2 * rows);
    format!(
        "const GAMMA_7: f32 = {:?}f;\nconst GAMMA_16: f32 = {:?}f;\n\
         const MIN_ALPHA: f32 = {:?}f;\nconst R_MIN: f32 = {:?}f;\n\
         const ALBEDO_COLUMNS: u32 = {columns}u;\nconst ALBEDO_ROWS: u32 = {rows}u;\n\
         const TABLE_A_AVG: u32 = {a_average}u;\nconst TABLE_B_AVG: u32 = {b_average}u;\n\
         const TABLE_SRGB: u32 = {srgb}u;\nconst GRID_REACH_SQ: f32 = {:?}f;\n\
         const GRID_SCALED_ERROR: f32 = {:?}f;\n",
        gamma(7),
        gamma(16),
        MIN_ALPHA,
        MIN_ALPHA.sqrt(),
        HashGrid::REACH_SQ,
        HashGrid::SCALED_ERROR,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use vcm_traversal_wgpu::NodeLayout;
    use vcm_traversal_wgpu::shader::{traversal_functions, validate_module};

    #[test]
    fn every_kernel_validates_over_both_node_layouts_with_and_without_alpha_masks() {
        for kernel in Kernel::ALL {
            for layout in [NodeLayout::Binary, NodeLayout::Wide] {
                for masks in [false, true] {
                    let traversal = traversal_functions(layout, 32, masks);
                    let module = kernel_module(kernel, &traversal, masks);
                    if let Err(error) = validate_module(&module, kernel.stages()) {
                        panic!("{kernel:?}: {error}");
                    }
                }
            }
        }
    }

    #[test]
    fn workgroup_size_matches_the_shader() {
        let line = format!("const WORKGROUP: u32 = {WORKGROUP_SIZE}u;");
        assert!(SCENE_WGSL.contains(&line));
    }

    #[test]
    fn host_constants_parse_back_to_the_same_floats() {
        for x in [
            gamma(7),
            gamma(16),
            MIN_ALPHA,
            MIN_ALPHA.sqrt(),
            HashGrid::REACH_SQ,
            HashGrid::SCALED_ERROR,
        ] {
            let written = format!("{x:?}");
            assert_eq!(written.parse::<f32>().unwrap().to_bits(), x.to_bits());
        }
    }
}
