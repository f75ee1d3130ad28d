//! The scene as the path tracing kernel reads it (bind group 2 of `path_tracer.wgsl`), and
//! which scenes it can shade.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use vcm_scene::Scene;
use vcm_scene::bsdf::{FlatLobes, albedo_tables};
use vcm_scene::light::{Light, LightSampler};

/// `ShadeTriangle`: corners with the material and the area light (or `NO_LIGHT`) as bits in
/// w, then the vertex normals.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuTriangle {
    corners: [[f32; 4]; 3],
    normals: [[f32; 4]; 3],
}

/// `Material` of `bsdf.wgsl`: a material's [`FlatLobes`] and sidedness; α 0 for a smooth
/// lobe, row `NO_ROW` for a mirror's albedo.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuMaterial {
    f0: [f32; 3],
    ior: f32,
    f90: [f32; 3],
    flags: u32,
    diffuse_albedo: [f32; 3],
    dielectric_weight: f32,
    diffuse_scale: [f32; 3],
    thin_weight: f32,
    dielectric_tint: [f32; 3],
    specular_alpha: f32,
    thin_tint: [f32; 3],
    dielectric_alpha: f32,
    layer_f0: [f32; 3],
    thin_alpha: f32,
    layer_f90: [f32; 3],
    specular_row_t: f32,
    selection: [f32; 4],
    specular_row: u32,
    layer_row: u32,
    layer_row_t: f32,
    unused: u32,
}

/// `Light` of `path_tracer.wgsl`: three points or directions with a number each, a normal
/// with the kind, and the emission (see there).
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuLight {
    corners: [[f32; 4]; 3],
    normal: [f32; 4],
    emission: [f32; 4],
}

/// The light kinds of `path_tracer.wgsl`.
const AREA_LIGHT: u32 = 0;
const POINT_LIGHT: u32 = 1;
const SPOT_LIGHT: u32 = 2;
const DIRECTIONAL_LIGHT: u32 = 3;
const ENVIRONMENT_LIGHT: u32 = 4;

/// `Material::flags` bits (`bsdf.wgsl`).
const HAS_SPECULAR: u32 = 1;
const HAS_DIFFUSE: u32 = 2;
const HAS_DIELECTRIC: u32 = 4;
const HAS_THIN: u32 = 8;
const DOUBLE_SIDED: u32 = 16;
const CONSTANT_SELECTION: u32 = 32;
const HAS_LAYER: u32 = 64;
/// `NO_ROW` of `bsdf.wgsl`.
const NO_ROW: u32 = u32::MAX;

/// `NO_LIGHT` of `path_tracer.wgsl`.
const NO_LIGHT: u32 = u32::MAX;

/// The scene's shading data, ready to upload.
pub(crate) struct SceneData {
    pub triangles: Vec<GpuTriangle>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
    /// Per light: the smallest number that picks it or a later one, and its probability.
    pub light_pick: Vec<[f32; 2]>,
    /// Lights the light sampler picks from (0 when it has none to pick).
    pub light_count: u32,
    /// The environment light, or `NO_LIGHT`.
    pub environment: u32,
    /// The albedo tables A then B, each row by row.
    pub albedo_tables: Vec<f32>,
}

fn vec4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// Whether the GPU path tracer can shade `scene`: `Err` names the first thing it cannot
/// shade yet (a texture, a rough lobe, a point light, …).
pub fn check_scene(scene: &Scene) -> Result<(), String> {
    let features = &scene.features;
    let unsupported = [
        (features.textures, "textures"),
        (features.normal_maps, "normal maps"),
        (features.vertex_colors, "vertex colours"),
        (features.alpha_masks, "alpha masks"),
        (features.absorbing_volumes, "absorbing volumes"),
        (features.triangles == 0, "a scene without triangles"),
    ];
    if let Some((_, what)) = unsupported.iter().find(|(present, _)| *present) {
        return Err((*what).to_owned());
    }
    for light in &scene.lights {
        match light {
            Light::Area(area) if area.texture.is_some() || area.cut_out.is_some() => {
                return Err("textured or cut-out emitters".into());
            }
            Light::Environment(environment) if environment.map.is_some() => {
                return Err("environment maps".into());
            }
            _ => {}
        }
    }
    let mut used = vec![false; scene.materials.len()];
    for &material in &scene.mesh.material_ids {
        used[material as usize] = true;
    }
    let materials = scene.materials.iter().zip(&scene.material_lobes);
    for ((material, lobes), _) in materials.zip(used).filter(|(_, used)| *used) {
        if lobes.is_none() {
            let name = &material.name;
            return Err(format!("material '{name}' varies over its surface"));
        }
    }
    Ok(())
}

impl SceneData {
    /// Packs `scene`, which [`check_scene`] accepts.
    pub fn new(scene: &Scene) -> SceneData {
        let mesh = &scene.mesh;
        let sampler = &scene.light_sampler;
        let triangles = (0..mesh.triangle_count())
            .map(|t| {
                let corners = mesh.corners(t);
                let indices = mesh.triangles[t].map(|i| i as usize);
                let light = if scene.shading.emitter_lookups {
                    scene.light_sampler.light_of_triangle(t as u32)
                } else {
                    None
                };
                let light = light.map_or(NO_LIGHT, |l| l as u32);
                let bits = [mesh.material_ids[t], light, 0].map(f32::from_bits);
                let normal = |k: usize| mesh.normals.get(indices[k]).copied().unwrap_or(Vec3::ZERO);
                GpuTriangle {
                    corners: [0, 1, 2].map(|k| vec4(corners[k], bits[k])),
                    normals: [0, 1, 2].map(|k| vec4(normal(k), 0.0)),
                }
            })
            .collect();
        let materials = scene
            .materials
            .iter()
            .zip(&scene.material_lobes)
            .map(|(material, lobes)| {
                let flat = lobes.as_ref().map(|l| l.flat());
                pack_material(flat.as_ref(), material.double_sided)
            })
            .collect();
        let lights = scene.lights.iter().map(pack_light).collect();
        let environment = sampler.environment().map_or(NO_LIGHT, |l| l as u32);
        let light_count = if sampler.sample(0.0).is_some() {
            scene.lights.len() as u32
        } else {
            0
        };
        let light_pick = (0..light_count as usize)
            .map(|i| [first_number_picking(sampler, i), sampler.pmf(i)])
            .collect();
        SceneData {
            triangles,
            materials,
            lights,
            light_pick,
            light_count,
            environment,
            albedo_tables: albedo_tables()
                .iter()
                .flat_map(|t| t.iter().flatten())
                .copied()
                .collect(),
        }
    }
}

/// A light as `path_tracer.wgsl` reads it (textured emitters and environment maps, which
/// [`check_scene`] refuses, without their textures).
fn pack_light(light: &Light) -> GpuLight {
    let kind =
        |kind: u32, emission: Vec3| (vec4(Vec3::ZERO, f32::from_bits(kind)), vec4(emission, 0.0));
    let point = |p: Vec3, w: f32| vec4(p, w);
    let zero = [0.0; 4];
    match light {
        Light::Area(area) => {
            let (mut normal, emission) = kind(AREA_LIGHT, area.emission);
            normal[..3].copy_from_slice(&area.normal.to_array());
            GpuLight {
                corners: [
                    point(area.corners[0], area.area),
                    point(area.corners[1], 0.0),
                    point(area.corners[2], 0.0),
                ],
                normal,
                emission,
            }
        }
        Light::Point(l) => {
            let (normal, emission) = kind(POINT_LIGHT, l.intensity);
            GpuLight {
                corners: [point(l.position, 0.0), zero, zero],
                normal,
                emission,
            }
        }
        Light::Spot(l) => {
            let (normal, emission) = kind(SPOT_LIGHT, l.intensity);
            GpuLight {
                corners: [
                    point(l.position, l.cos_inner),
                    point(l.direction, l.cos_outer),
                    zero,
                ],
                normal,
                emission,
            }
        }
        Light::Directional(l) => {
            let (normal, emission) = kind(DIRECTIONAL_LIGHT, l.irradiance);
            GpuLight {
                corners: [point(l.direction, 0.0), zero, zero],
                normal,
                emission,
            }
        }
        Light::Environment(l) => {
            let (normal, emission) = kind(ENVIRONMENT_LIGHT, l.radiance);
            GpuLight {
                corners: [zero; 3],
                normal,
                emission,
            }
        }
    }
}

/// The material's lobes as `bsdf.wgsl` reads them; a material without lobes (one
/// [`check_scene`] refuses) is black.
fn pack_material(lobes: Option<&FlatLobes>, double_sided: bool) -> GpuMaterial {
    let mut m = GpuMaterial::zeroed();
    m.ior = 1.5;
    if double_sided {
        m.flags |= DOUBLE_SIDED;
    }
    let Some(lobes) = lobes else {
        return m;
    };
    m.ior = lobes.ior;
    (m.specular_row, m.layer_row) = (NO_ROW, NO_ROW);
    if let Some(specular) = lobes.specular {
        m.flags |= HAS_SPECULAR;
        (m.f0, m.f90) = (specular.f0.to_array(), specular.f90.to_array());
        m.specular_alpha = specular.alpha.unwrap_or(0.0);
        (m.specular_row, m.specular_row_t) = table_row(specular.albedo.row);
    }
    if let Some(diffuse) = lobes.diffuse {
        m.flags |= HAS_DIFFUSE;
        m.diffuse_albedo = diffuse.albedo.to_array();
        m.diffuse_scale = diffuse.scale.to_array();
        if let Some(layer) = diffuse.layer {
            m.flags |= HAS_LAYER;
            (m.layer_f0, m.layer_f90) = (layer.f0.to_array(), layer.f90.to_array());
            (m.layer_row, m.layer_row_t) = table_row(layer.row);
        }
    }
    if let Some(dielectric) = lobes.dielectric {
        m.flags |= HAS_DIELECTRIC;
        m.dielectric_weight = dielectric.weight;
        m.dielectric_tint = dielectric.tint.to_array();
        m.dielectric_alpha = dielectric.alpha.unwrap_or(0.0);
    }
    if let Some(thin) = lobes.thin {
        m.flags |= HAS_THIN;
        m.thin_weight = thin.weight;
        m.thin_tint = thin.tint.to_array();
        m.thin_alpha = thin.alpha.unwrap_or(0.0);
    }
    if let Some(selection) = lobes.constant_selection {
        m.flags |= CONSTANT_SELECTION;
        m.selection = selection;
    }
    m
}

/// An albedo's table row and fraction as the kernel reads them.
fn table_row(row: Option<(usize, f32)>) -> (u32, f32) {
    row.map_or((NO_ROW, 0.0), |(k, t)| (k as u32, t))
}

/// The smallest number in [0, 1) for which `sampler` picks light `light` or a later one
/// (infinity if none does): the kernel picks the last light whose number is at most its
/// own, which is the light the CPU's f64 search picks for every f32.
fn first_number_picking(sampler: &LightSampler, light: usize) -> f32 {
    let picks_it_or_later = |bits: u32| {
        sampler
            .sample(f32::from_bits(bits))
            .is_some_and(|(i, _)| i >= light)
    };
    // Non-negative floats order as their bits; the numbers lie in [0, 1).
    let (mut lo, mut hi) = (0u32, 1f32.to_bits());
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if picks_it_or_later(mid) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    if lo == 1f32.to_bits() {
        f32::INFINITY
    } else {
        f32::from_bits(lo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_structs_have_the_wgsl_sizes() {
        assert_eq!(size_of::<GpuTriangle>(), 96);
        assert_eq!(size_of::<GpuMaterial>(), 160);
        assert_eq!(size_of::<GpuLight>(), 80);
    }
}
