//! The scene as the path tracing kernel reads it (bind group 2 of `path_tracer.wgsl`), and
//! which scenes it can shade.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3, Vec4};
use vcm_scene::Material;

use crate::plan::KernelPlan;
use vcm_scene::Scene;
use vcm_scene::bsdf::{ALBEDO_TABLE_SIZE, FlatLobes, albedo_tables};
use vcm_scene::light::{EnvironmentMap, Light};
use vcm_scene::mesh::Mesh;
use vcm_scene::sampling::Distribution1D;
use vcm_scene::texture::{
    ColorEncoding, Filter, Texture, TextureRef, UvTransform, WrapMode, srgb_to_linear_table,
};

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
/// with the kind, the emission, and an area light's texture coordinates and texture
/// reference (see there).
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuLight {
    corners: [[f32; 4]; 3],
    normal: [f32; 4],
    emission: [f32; 4],
    uv01: [f32; 4],
    uv2: [f32; 4],
}

/// `TextureInfo` of `material.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuTexture {
    offset: u32,
    width: u32,
    height: u32,
    flags: u32,
}

/// `TextureRef` of `material.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuTextureRef {
    linear: [f32; 4],
    offset: [f32; 2],
    texture: u32,
    identity: u32,
}

/// `MaterialInputs` of `material.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuMaterialInputs {
    base_color: [f32; 4],
    specular_color: [f32; 3],
    metallic: f32,
    absorption: [f32; 3],
    roughness: f32,
    specular: f32,
    transmission: f32,
    normal_scale: f32,
    ior: f32,
    flags: u32,
    refs: [u32; 7],
}

/// `TriangleAttributes` of `path_tracer.wgsl`.
#[derive(Clone, Copy, Pod, Zeroable)]
#[repr(C)]
pub(crate) struct GpuAttributes {
    uv01: [f32; 4],
    uv2: [f32; 4],
    colors: [[f32; 4]; 3],
    tangents: [[f32; 4]; 3],
}

/// The light kinds of `path_tracer.wgsl`.
const AREA_LIGHT: u32 = 0;
const POINT_LIGHT: u32 = 1;
const SPOT_LIGHT: u32 = 2;
const DIRECTIONAL_LIGHT: u32 = 3;
const ENVIRONMENT_LIGHT: u32 = 4;
/// Set beside the kind of an area light that an alpha mask cuts out.
const CUT_OUT: u32 = 0x100;

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
/// `TextureInfo::flags` and `MaterialInputs::flags` bits, `NO_TEXTURE` (`material.wgsl`).
const SRGB_TEXTURE: u32 = 1;
const NEAREST_TEXTURE: u32 = 2;
const THIN_WALLED: u32 = 1;
const UNIFORM_LOBES: u32 = 2;
const BOUNDS_VOLUME: u32 = 4;
const NO_TEXTURE: u32 = u32::MAX;

/// The scene's shading data, ready to upload.
pub(crate) struct SceneData {
    pub triangles: Vec<GpuTriangle>,
    pub materials: Vec<GpuMaterial>,
    pub lights: Vec<GpuLight>,
    /// Discrete distributions, per entry the smallest number that picks it or a later one
    /// and its probability: the lights' (`light_count` of them), then the environment map's
    /// rows and each row's texels, from `environment_offsets`.
    pub picks: Vec<[f32; 2]>,
    /// Lights the light sampler picks from (0 when it has none to pick).
    pub light_count: u32,
    /// Where the environment map's rows and its rows' texels start in `picks`.
    pub environment_offsets: [u32; 2],
    /// The environment light, or `NO_LIGHT`.
    pub environment: u32,
    /// The albedo tables A then B, each row by row, their row averages, the sRGB table.
    pub tables: Vec<f32>,
    /// The environment map's texels (empty without one).
    pub environment_texels: Vec<[f32; 4]>,
    /// Per triangle, its texture coordinates, colours and tangents (empty where `plan`
    /// needs none of them).
    pub attributes: Vec<GpuAttributes>,
    pub textures: Vec<GpuTexture>,
    /// Every texture's texels, RGBA8 packed into a word.
    pub texels: Vec<u32>,
    pub texture_refs: Vec<GpuTextureRef>,
    pub material_inputs: Vec<GpuMaterialInputs>,
}

fn vec4(v: Vec3, w: f32) -> [f32; 4] {
    [v.x, v.y, v.z, w]
}

/// Whether the GPU path tracer can shade `scene`: `Err` says what it cannot shade. The
/// kernel has the whole scene model; it needs a hierarchy to trace, which a scene without
/// triangles does not have.
pub fn check_scene(scene: &Scene) -> Result<(), String> {
    if scene.features.triangles == 0 {
        return Err("a scene without triangles".into());
    }
    Ok(())
}

impl SceneData {
    /// Packs `scene`, which [`check_scene`] accepts, for a kernel with `plan`.
    pub fn new(scene: &Scene, plan: &KernelPlan) -> SceneData {
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
        let mut refs = Vec::new();
        let lights = scene
            .lights
            .iter()
            .map(|light| pack_light(light, &mut refs))
            .collect();
        let material_inputs = scene
            .materials
            .iter()
            .zip(&scene.material_lobes)
            .map(|(material, lobes)| pack_inputs(material, lobes.is_some(), &mut refs))
            .collect();
        let attributes = if !(plan.texture_coordinates || plan.vertex_colors) {
            Vec::new()
        } else {
            (0..mesh.triangle_count())
                .map(|t| pack_attributes(mesh, t))
                .collect()
        };
        let (textures, texels) = pack_textures(&scene.textures);
        let map = scene.lights.iter().find_map(|light| match light {
            Light::Environment(environment) => environment.map.as_deref(),
            _ => None,
        });
        let environment_map = map.map_or_else(PackedEnvironment::default, pack_environment_map);
        let mut picks: Vec<[f32; 2]> = (sampler.first_numbers().into_iter().enumerate())
            .map(|(i, first)| [first, sampler.pmf(i)])
            .collect();
        let light_count = picks.len() as u32;
        let rows = environment_map.rows.len() as u32;
        let environment_offsets = [light_count, light_count + rows];
        picks.extend(environment_map.rows);
        picks.extend(environment_map.columns);
        let environment = sampler.environment().map_or(NO_LIGHT, |l| l as u32);
        SceneData {
            triangles,
            materials,
            lights,
            picks,
            light_count,
            environment_offsets,
            environment,
            tables: lookup_tables(),
            attributes,
            textures,
            texels,
            texture_refs: refs,
            material_inputs,
            environment_texels: environment_map.texels,
        }
    }
}

/// The albedo tables A and B row by row, their row averages, then the sRGB decoding table:
/// `tables` of `path_tracer.wgsl` (offsets in [`crate::shader`]).
pub(crate) fn lookup_tables() -> Vec<f32> {
    let albedo = albedo_tables();
    let rows = |table: &[[f32; ALBEDO_TABLE_SIZE.0]; ALBEDO_TABLE_SIZE.1]| {
        table.iter().flatten().copied().collect::<Vec<_>>()
    };
    [
        rows(albedo.a),
        rows(albedo.b),
        albedo.a_average.to_vec(),
        albedo.b_average.to_vec(),
        srgb_to_linear_table().to_vec(),
    ]
    .concat()
}

/// An environment map as the kernel reads it.
#[derive(Default)]
struct PackedEnvironment {
    texels: Vec<[f32; 4]>,
    /// Per row, then per texel of each row: the first number that picks it and its
    /// probability (empty where the map is black and has no distribution).
    rows: Vec<[f32; 2]>,
    columns: Vec<[f32; 2]>,
}

/// The environment map's texels and its sampling distribution.
fn pack_environment_map(map: &EnvironmentMap) -> PackedEnvironment {
    let texels = map
        .texels()
        .iter()
        .map(|t| t.extend(0.0).to_array())
        .collect();
    let Some(distribution) = map.distribution() else {
        return PackedEnvironment {
            texels,
            ..PackedEnvironment::default()
        };
    };
    let picks = |d: &Distribution1D| {
        let numbers = d.first_numbers();
        (0..d.len())
            .map(|i| [numbers[i], d.pmf(i)])
            .collect::<Vec<_>>()
    };
    let width = distribution.size().x as usize;
    let columns = distribution
        .columns()
        .iter()
        .flat_map(|row| match row {
            Some(row) => picks(row),
            // A row without weight, never picked.
            None => vec![[f32::INFINITY, 0.0]; width],
        })
        .collect();
    PackedEnvironment {
        texels,
        rows: picks(distribution.rows()),
        columns,
    }
}

/// Every texture's description and all their texels, one after the other.
fn pack_textures(textures: &[Texture]) -> (Vec<GpuTexture>, Vec<u32>) {
    let mut texels = Vec::new();
    let wrap = |mode: WrapMode| match mode {
        WrapMode::Repeat => 0,
        WrapMode::MirroredRepeat => 1,
        WrapMode::ClampToEdge => 2,
    };
    let infos = textures
        .iter()
        .map(|texture| {
            let offset = texels.len() as u32;
            texels.extend(texture.texels().iter().map(|&t| u32::from_le_bytes(t)));
            let mut flags = (wrap(texture.wrap_u) << 2) | (wrap(texture.wrap_v) << 4);
            if texture.encoding() == ColorEncoding::Srgb {
                flags |= SRGB_TEXTURE;
            }
            if texture.filter == Filter::Nearest {
                flags |= NEAREST_TEXTURE;
            }
            GpuTexture {
                offset,
                width: texture.width(),
                height: texture.height(),
                flags,
            }
        })
        .collect();
    (infos, texels)
}

/// Adds `texture` to `refs` and returns its index there (`NO_TEXTURE` for none).
fn add_ref(refs: &mut Vec<GpuTextureRef>, texture: Option<TextureRef>) -> u32 {
    let Some(texture) = texture else {
        return NO_TEXTURE;
    };
    let [row0, row1] = texture.transform.linear;
    refs.push(GpuTextureRef {
        linear: [row0.x, row0.y, row1.x, row1.y],
        offset: texture.transform.offset.to_array(),
        texture: texture.index as u32,
        identity: u32::from(texture.transform == UvTransform::IDENTITY),
    });
    refs.len() as u32 - 1
}

/// A material's factors and texture references (`uniform`: the host has its lobes).
fn pack_inputs(
    material: &Material,
    uniform: bool,
    refs: &mut Vec<GpuTextureRef>,
) -> GpuMaterialInputs {
    let slots = [
        material.base_color_texture,
        material.metallic_roughness_texture,
        material.normal_texture,
        material.emissive_texture,
        material.specular_texture,
        material.specular_color_texture,
        material.transmission_texture,
    ];
    let mut flags = 0;
    if material.thin_walled {
        flags |= THIN_WALLED;
    }
    if uniform {
        flags |= UNIFORM_LOBES;
    }
    if material.bounds_volume() {
        flags |= BOUNDS_VOLUME;
    }
    GpuMaterialInputs {
        base_color: material.base_color.to_array(),
        specular_color: material.specular_color.to_array(),
        metallic: material.metallic,
        absorption: material.absorption.to_array(),
        roughness: material.roughness,
        specular: material.specular,
        transmission: material.transmission,
        normal_scale: material.normal_scale,
        ior: material.ior,
        flags,
        refs: slots.map(|slot| add_ref(refs, slot)),
    }
}

/// Triangle `t`'s texture coordinates, vertex colours (white without) and tangents.
fn pack_attributes(mesh: &Mesh, t: usize) -> GpuAttributes {
    let corners = mesh.triangles[t].map(|i| i as usize);
    let uv = |k: usize| mesh.uvs.get(corners[k]).copied().unwrap_or(Vec2::ZERO);
    let color = |k: usize| mesh.colors.get(corners[k]).copied().unwrap_or(Vec3::ONE);
    let tangent = |k: usize| mesh.tangents.get(corners[k]).copied().unwrap_or(Vec4::ZERO);
    GpuAttributes {
        uv01: [uv(0).x, uv(0).y, uv(1).x, uv(1).y],
        uv2: [uv(2).x, uv(2).y, 0.0, 0.0],
        colors: [0, 1, 2].map(|k| vec4(color(k), 0.0)),
        tangents: [0, 1, 2].map(|k| tangent(k).to_array()),
    }
}

/// A light as `path_tracer.wgsl` reads it, an area light's emission and mask textures added
/// to `refs` (an environment map's texels and distribution are packed apart:
/// [`pack_environment_map`]).
fn pack_light(light: &Light, refs: &mut Vec<GpuTextureRef>) -> GpuLight {
    // A light without texture coordinates: its kind, its emission and its numbers.
    let unlit = |kind: u32, emission: Vec3, corners: [[f32; 4]; 3]| GpuLight {
        corners,
        normal: vec4(Vec3::ZERO, f32::from_bits(kind)),
        emission: vec4(emission, 0.0),
        uv01: [0.0; 4],
        uv2: [0.0, 0.0, f32::from_bits(NO_TEXTURE), 0.0],
    };
    let zero = [0.0; 4];
    match light {
        Light::Area(area) => {
            // An alpha mask's factor, cutoff and texture; a mask that keeps everything
            // where there is none.
            let (alpha, cutoff, mask_texture, flag) = match area.cut_out {
                Some(mask) => (
                    mask.alpha,
                    mask.cutoff,
                    add_ref(refs, mask.texture),
                    CUT_OUT,
                ),
                None => (1.0, 0.0, NO_TEXTURE, 0),
            };
            GpuLight {
                corners: [
                    vec4(area.corners[0], area.area),
                    vec4(area.corners[1], alpha),
                    vec4(area.corners[2], cutoff),
                ],
                normal: vec4(area.normal, f32::from_bits(AREA_LIGHT | flag)),
                emission: vec4(area.emission, 0.0),
                uv01: [area.uvs[0].x, area.uvs[0].y, area.uvs[1].x, area.uvs[1].y],
                uv2: [
                    area.uvs[2].x,
                    area.uvs[2].y,
                    f32::from_bits(add_ref(refs, area.texture)),
                    f32::from_bits(mask_texture),
                ],
            }
        }
        Light::Point(l) => unlit(
            POINT_LIGHT,
            l.intensity,
            [vec4(l.position, 0.0), zero, zero],
        ),
        Light::Spot(l) => {
            let corners = [
                vec4(l.position, l.cos_inner),
                vec4(l.direction, l.cos_outer),
                zero,
            ];
            unlit(SPOT_LIGHT, l.intensity, corners)
        }
        Light::Directional(l) => unlit(
            DIRECTIONAL_LIGHT,
            l.irradiance,
            [
                vec4(l.direction, 0.0),
                vec4(l.scene_center, l.scene_radius),
                zero,
            ],
        ),
        Light::Environment(l) => {
            // The map's size (as bits), whether there is one, and whether it has a
            // sampling distribution.
            let description = l.map.as_ref().map_or(zero, |map| {
                let size = map.size();
                let sampled = f32::from(u8::from(map.distribution().is_some()));
                [f32::from_bits(size.x), f32::from_bits(size.y), 1.0, sampled]
            });
            let bounds = vec4(l.scene_center, l.scene_radius);
            unlit(ENVIRONMENT_LIGHT, l.radiance, [description, bounds, zero])
        }
    }
}

/// The material's lobes as `bsdf.wgsl` reads them; a material without lobes (one
/// [`check_scene`] refuses) is black.
pub(crate) fn pack_material(lobes: Option<&FlatLobes>, double_sided: bool) -> GpuMaterial {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_structs_have_the_wgsl_sizes() {
        assert_eq!(size_of::<GpuTriangle>(), 96);
        assert_eq!(size_of::<GpuMaterial>(), 160);
        assert_eq!(size_of::<GpuLight>(), 112);
        assert_eq!(size_of::<GpuTexture>(), 16);
        assert_eq!(size_of::<GpuTextureRef>(), 32);
        assert_eq!(size_of::<GpuMaterialInputs>(), 96);
        assert_eq!(size_of::<GpuAttributes>(), 128);
    }
}
