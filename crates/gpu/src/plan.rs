//! What the path tracing kernel computes for a scene: the parts it needs, set as the
//! kernel's override constants so that the shader compiler drops the code of the others,
//! and each part's reason for `--explain`.

use vcm_scene::light::Light;
use vcm_scene::{Decision, Scene};

/// The parts of the kernel a scene needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct KernelPlan {
    /// Texture coordinates at hits (textures or normal maps).
    pub texture_coordinates: bool,
    /// Normal maps with interpolated tangents.
    pub normal_maps: bool,
    /// Vertex colours.
    pub vertex_colors: bool,
    /// Lobes built per hit, for materials a texture or vertex colour changes.
    pub varying_materials: bool,
    /// Absorption inside volume boundaries.
    pub absorbing_volumes: bool,
    /// The kinds of light the scene has, bit k for `path_tracer.wgsl`'s kind k.
    pub light_kinds: u32,
    /// An environment map (else a constant environment, if any).
    pub environment_map: bool,
}

/// Light kinds of `path_tracer.wgsl`, and the parts they name.
const LIGHT_KIND_PARTS: [&str; 5] = [
    "area light sampling in the kernel",
    "point light sampling in the kernel",
    "spot light sampling in the kernel",
    "directional light sampling in the kernel",
    "environment light in the kernel",
];

impl KernelPlan {
    /// The parts `scene` needs (as the CPU's shading plan sees it).
    pub fn for_scene(scene: &Scene) -> KernelPlan {
        let plan = &scene.shading;
        let light_kinds = scene
            .lights
            .iter()
            .map(|light| match light {
                Light::Area(_) => 1,
                Light::Point(_) => 2,
                Light::Spot(_) => 4,
                Light::Directional(_) => 8,
                Light::Environment(_) => 16,
            })
            .fold(0, |kinds, kind| kinds | kind);
        let mut used = vec![false; scene.materials.len()];
        for &material in &scene.mesh.material_ids {
            used[material as usize] = true;
        }
        let varying_materials = scene
            .material_lobes
            .iter()
            .zip(used)
            .any(|(lobes, used)| used && lobes.is_none());
        KernelPlan {
            texture_coordinates: plan.texture_coordinates || plan.normal_maps,
            normal_maps: plan.normal_maps,
            vertex_colors: !scene.mesh.colors.is_empty(),
            varying_materials,
            absorbing_volumes: scene.features.absorbing_volumes,
            light_kinds,
            environment_map: scene
                .lights
                .iter()
                .any(|light| matches!(light, Light::Environment(e) if e.map.is_some())),
        }
    }

    /// The kernel's override constants.
    pub fn constants(&self) -> Vec<(&'static str, f64)> {
        let flag = |on: bool| f64::from(u8::from(on));
        vec![
            ("TEXTURE_COORDINATES", flag(self.texture_coordinates)),
            ("NORMAL_MAPS", flag(self.normal_maps)),
            ("VERTEX_COLORS", flag(self.vertex_colors)),
            ("VARYING_MATERIALS", flag(self.varying_materials)),
            ("ABSORBING_VOLUMES", flag(self.absorbing_volumes)),
            ("LIGHT_KINDS", f64::from(self.light_kinds)),
            ("ENVIRONMENT_MAP", flag(self.environment_map)),
        ]
    }

    /// Each part, whether the kernel has it, and why.
    pub fn decisions(&self) -> Vec<Decision> {
        let decide = |part: &'static str, on: bool, yes: &str, no: &str| {
            if on {
                Decision::runs(part, yes)
            } else {
                Decision::left_out(part, no)
            }
        };
        let mut decisions = vec![
            decide(
                "texture coordinates in the kernel",
                self.texture_coordinates,
                "a material samples a texture or has a normal map",
                "no material samples a texture",
            ),
            decide(
                "normal maps in the kernel",
                self.normal_maps,
                "a material has a normal map",
                "no material has a normal map",
            ),
            decide(
                "vertex colours in the kernel",
                self.vertex_colors,
                "the mesh has vertex colours",
                "the mesh has no vertex colours",
            ),
            decide(
                "materials built per hit in the kernel",
                self.varying_materials,
                "a texture or vertex colour changes some material's lobes",
                "every material's lobes are built once, on the host",
            ),
            decide(
                "absorbing volumes in the kernel",
                self.absorbing_volumes,
                "a solid absorbs (KHR_materials_volume attenuation)",
                "no solid absorbs",
            ),
        ];
        for (kind, part) in LIGHT_KIND_PARTS.into_iter().enumerate() {
            let on = self.light_kinds & (1 << kind) != 0;
            decisions.push(decide(
                part,
                on,
                "the scene has such a light",
                "the scene has none",
            ));
        }
        decisions.push(decide(
            "environment map in the kernel",
            self.environment_map,
            "the environment has an image (VCM_environment)",
            "the scene has no environment image",
        ));
        decisions
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::SCENE_WGSL;

    #[test]
    fn every_constant_is_an_override_of_the_kernel() {
        let plan = KernelPlan {
            texture_coordinates: true,
            normal_maps: false,
            vertex_colors: false,
            varying_materials: true,
            absorbing_volumes: false,
            light_kinds: 3,
            environment_map: false,
        };
        for (name, _) in plan.constants() {
            assert!(SCENE_WGSL.contains(&format!("override {name}:")), "{name}");
        }
        assert_eq!(plan.decisions().iter().filter(|d| d.runs).count(), 4);
    }
}
