//! Composing the traversal kernels from the WGSL sources in this crate's `shaders/`.
//!
//! WGSL has no includes: a module is the host-defined constants followed by `ray.wgsl`
//! (rays, hits, the triangle test), the alpha test, the traversal file and `kernels.wgsl`
//! (the entry points over batches of rays). Kernels that trace rays of their own (the GPU
//! path tracer) take everything but the entry points ([`traversal_functions`]) and call
//! `trace(ray, any_hit)`. The stack size is
//! a host constant because private arrays cannot be sized by pipeline overrides. Scenes
//! without alpha masks get `alpha_none.wgsl`, so their kernels carry no mask code and bind no
//! mask buffers; scenes with masks get `alpha_masks.wgsl` (bind group 2).

use crate::layout::NodeLayout;

/// The shared ray and triangle code (bind group 1: the hierarchy).
pub const RAY_WGSL: &str = include_str!("../shaders/ray.wgsl");
/// The alpha test of scenes without masks: always opaque.
pub const ALPHA_NONE_WGSL: &str = include_str!("../shaders/alpha_none.wgsl");
/// The alpha test of scenes with masks.
pub const ALPHA_MASKS_WGSL: &str = include_str!("../shaders/alpha_masks.wgsl");
/// Traversal of the binary layout.
pub const TRAVERSE_BVH2_WGSL: &str = include_str!("../shaders/traverse_bvh2.wgsl");
/// Traversal of the wide layout.
pub const TRAVERSE_CWBVH_WGSL: &str = include_str!("../shaders/traverse_cwbvh.wgsl");

/// The entry points over batches of rays (bind group 0: rays, hits, flags).
pub const KERNELS_WGSL: &str = include_str!("../shaders/kernels.wgsl");

/// Entry point that writes one [`Hit`](vcm_traversal::HitBatch) per ray.
pub const CLOSEST_HIT_ENTRY: &str = "closest_hit";
/// Entry point that writes one occlusion flag per ray.
pub const ANY_HIT_ENTRY: &str = "any_hit";
/// Invocations per workgroup (`WORKGROUP_SIZE` in `kernels.wgsl`).
pub const WORKGROUP_SIZE: u32 = 64;

/// The complete WGSL module for `layout`, whose traversal needs `stack_size` entries, with
/// or without the alpha-mask test.
pub fn traversal_module(layout: NodeLayout, stack_size: u32, alpha_masks: bool) -> String {
    let functions = traversal_functions(layout, stack_size, alpha_masks);
    format!("{functions}\n{KERNELS_WGSL}")
}

/// The traversal without entry points: `trace(ray, any_hit) -> Hit` over the hierarchy in
/// bind group 1 (and the alpha masks in group 2), for kernels that trace rays of their own.
pub fn traversal_functions(layout: NodeLayout, stack_size: u32, alpha_masks: bool) -> String {
    let alpha = if alpha_masks {
        ALPHA_MASKS_WGSL
    } else {
        ALPHA_NONE_WGSL
    };
    let traverse = match layout {
        NodeLayout::Binary => TRAVERSE_BVH2_WGSL,
        NodeLayout::Wide => TRAVERSE_CWBVH_WGSL,
    };
    format!(
        "const STACK_SIZE: u32 = {}u;\n{RAY_WGSL}\n{alpha}\n{traverse}",
        stack_size.max(1)
    )
}

/// Parses and validates a WGSL module with naga, then resolves its pipeline overrides (at
/// their defaults) for each of `entries` and writes SPIR-V, as wgpu does on Vulkan: a check
/// of kernels that needs no GPU, for tests. The error names the stage
/// that failed, with naga's message.
pub fn validate_module(source: &str, entries: &[&str]) -> Result<(), String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("WGSL parse error:\n{}", e.emit_to_string(source)))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .map_err(|e| format!("WGSL validation error:\n{}", e.emit_to_string(source)))?;
    for &entry in entries {
        let stage = Some((naga::ShaderStage::Compute, entry));
        let constants = naga::back::PipelineConstants::default();
        let (module, info) =
            naga::back::pipeline_constants::process_overrides(&module, &info, stage, &constants)
                .map_err(|e| format!("{entry}: overrides: {e}"))?;
        let options = naga::back::spv::Options::default();
        naga::back::spv::write_vec(&module, &info, &options, None)
            .map_err(|e| format!("{entry}: SPIR-V: {e}"))?;
    }
    Ok(())
}

/// The bind group layout entries of every buffer `source` declares, per group from 0 to the
/// highest it uses: a uniform buffer, or a storage buffer read-only unless declared
/// `read_write`. One pipeline layout made of them serves every entry point of the module, so
/// that its kernels share bind groups (layouts that wgpu derives belong to one pipeline).
pub fn buffer_layouts(source: &str) -> Result<Vec<Vec<wgpu::BindGroupLayoutEntry>>, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("WGSL parse error:\n{}", e.emit_to_string(source)))?;
    let mut groups: Vec<Vec<wgpu::BindGroupLayoutEntry>> = Vec::new();
    for (_, global) in module.global_variables.iter() {
        let Some(binding) = &global.binding else {
            continue;
        };
        let ty = match global.space {
            naga::AddressSpace::Uniform => wgpu::BufferBindingType::Uniform,
            naga::AddressSpace::Storage { access } => wgpu::BufferBindingType::Storage {
                read_only: !access.contains(naga::StorageAccess::STORE),
            },
            other => return Err(format!("a binding in {other:?}, not a buffer")),
        };
        let group = binding.group as usize;
        if groups.len() <= group {
            groups.resize_with(group + 1, Vec::new);
        }
        groups[group].push(buffer_layout(binding.binding, ty));
    }
    Ok(groups)
}

/// The layout entry of a whole buffer of type `ty` at `binding`, for compute shaders.
pub fn buffer_layout(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The size in bytes of struct `name` of the WGSL module `source` (its array stride), for
/// tests that a host's constant matches the shader's layout; `None` where the module does
/// not parse or has no such struct.
pub fn struct_size(source: &str, name: &str) -> Option<u32> {
    let module = naga::front::wgsl::parse_str(source).ok()?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).ok()?;
    let (handle, _) = module
        .types
        .iter()
        .find(|(_, ty)| ty.name.as_deref() == Some(name))?;
    Some(layouter[handle].to_stride())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Validates a composed module (panics with naga's message).
    fn validate(source: &str) {
        if let Err(error) = validate_module(source, &[CLOSEST_HIT_ENTRY, ANY_HIT_ENTRY]) {
            panic!("{error}");
        }
    }

    #[test]
    fn every_shader_validates() {
        for layout in [NodeLayout::Binary, NodeLayout::Wide] {
            for stack_size in [1, 64] {
                for alpha_masks in [false, true] {
                    validate(&traversal_module(layout, stack_size, alpha_masks));
                }
            }
        }
    }

    #[test]
    fn opaque_scenes_carry_no_mask_code() {
        for layout in [NodeLayout::Binary, NodeLayout::Wide] {
            let opaque = traversal_module(layout, 8, false);
            assert!(!opaque.contains("@group(2)") && !opaque.contains("sample_alpha"));
            assert!(traversal_module(layout, 8, true).contains("@group(2)"));
        }
    }

    #[test]
    fn workgroup_size_matches_the_shader() {
        assert!(KERNELS_WGSL.contains(&format!("const WORKGROUP_SIZE: u32 = {WORKGROUP_SIZE}u;")));
    }
}
