//! Reading one glTF mesh primitive into world space.

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::{Mode, Semantic};

use super::accessors::check_accessor;
use crate::loader::builder::Primitive;

/// Triangle vertex indices for a primitive's topology, from its index list.
fn assemble_triangles(mode: Mode, indices: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (2..indices.len())
            .map(|i| {
                let (a, b, c) = (indices[i - 2], indices[i - 1], indices[i]);
                // Every other strip triangle is wound the other way round.
                if i % 2 == 0 { [a, b, c] } else { [b, a, c] }
            })
            .collect(),
        Mode::TriangleFan => (2..indices.len())
            .map(|i| [indices[0], indices[i - 1], indices[i]])
            .collect(),
        _ => indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect(),
    }
}

/// Reads `primitive` with the node's world transform. `Ok(None)` for non-triangle topologies.
pub(super) fn read_primitive(
    primitive: &gltf::Primitive,
    name: String,
    world: Mat4,
    buffers: &[Vec<u8>],
    (material, texture_coordinates): (u32, u32),
) -> Result<Option<Primitive>, String> {
    if !matches!(
        primitive.mode(),
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    ) {
        return Ok(None);
    }
    let float = [DataType::F32];
    let positions = primitive
        .get(&Semantic::Positions)
        .ok_or("primitive has no POSITION attribute")?;
    check_accessor(&positions, buffers, Dimensions::Vec3, &float)?;
    let attributes = [
        (Semantic::Normals, Dimensions::Vec3, &float[..]),
        (Semantic::Tangents, Dimensions::Vec4, &float[..]),
        (
            Semantic::TexCoords(texture_coordinates),
            Dimensions::Vec2,
            &[DataType::F32, DataType::U8, DataType::U16][..],
        ),
    ];
    for (semantic, dimensions, types) in attributes {
        if let Some(accessor) = primitive.get(&semantic) {
            check_accessor(&accessor, buffers, dimensions, types)?;
        }
    }
    if let Some(colors) = primitive.get(&Semantic::Colors(0)) {
        let dimensions = match colors.dimensions() {
            Dimensions::Vec4 => Dimensions::Vec4,
            _ => Dimensions::Vec3,
        };
        let types = [DataType::F32, DataType::U8, DataType::U16];
        check_accessor(&colors, buffers, dimensions, &types)?;
        if colors.data_type() != DataType::F32 && !colors.normalized() {
            let index = colors.index();
            return Err(format!(
                "COLOR_0 accessor {index} is an integer type but not normalized"
            ));
        }
    }
    if let Some(indices) = primitive.indices() {
        let types = [DataType::U8, DataType::U16, DataType::U32];
        check_accessor(&indices, buffers, Dimensions::Scalar, &types)?;
    }
    // Every attribute has one element per vertex; checked before reading, since a sparse
    // accessor without a buffer view may declare any count.
    let per_vertex = [
        Semantic::Normals,
        Semantic::Tangents,
        Semantic::TexCoords(texture_coordinates),
        Semantic::Colors(0),
    ];
    for semantic in per_vertex {
        if let Some(accessor) = primitive.get(&semantic)
            && accessor.count() != positions.count()
        {
            return Err(format!(
                "accessor {} has {} elements for {} positions",
                accessor.index(),
                accessor.count(),
                positions.count()
            ));
        }
    }

    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let unreadable = || "an accessor's data cannot be read".to_string();
    let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
    let flips_winding = Mat3::from_mat4(world).determinant() < 0.0;
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or_else(unreadable)?
        .map(|p| world.transform_point3(Vec3::from(p)))
        .collect();
    let normals = reader.read_normals().map(|it| {
        it.map(|n| (normal_matrix * Vec3::from(n)).normalize_or_zero())
            .collect()
    });
    let tangents = reader.read_tangents().map(|it| {
        it.map(|t| {
            let xyz = (Mat3::from_mat4(world) * Vec4::from(t).truncate()).normalize_or_zero();
            let w = if flips_winding { -t[3] } else { t[3] };
            xyz.extend(w)
        })
        .collect()
    });
    let uvs = reader
        .read_tex_coords(texture_coordinates)
        .map(|it| it.into_f32().map(Vec2::from).collect());
    let colors = reader
        .read_colors(0)
        .map(|it| it.into_rgba_f32().map(Vec4::from).collect());
    let indices: Vec<u32> = match reader.read_indices() {
        Some(it) => it.into_u32().collect(),
        None => (0..positions.len() as u32).collect(),
    };
    let mut triangles = assemble_triangles(primitive.mode(), &indices);
    if flips_winding {
        // A mirroring transform turns counter-clockwise into clockwise (glTF 2.0 §3.7.4).
        triangles.iter_mut().for_each(|t| t.swap(1, 2));
    }
    Ok(Some(Primitive {
        name,
        positions,
        normals,
        uvs,
        tangents,
        colors,
        triangles,
        material,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_a_consistent_winding() {
        assert_eq!(
            assemble_triangles(Mode::TriangleStrip, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [2, 1, 3]]
        );
        assert_eq!(
            assemble_triangles(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(
            assemble_triangles(Mode::Triangles, &[0, 1, 2, 3]),
            vec![[0, 1, 2]]
        );
    }
}
