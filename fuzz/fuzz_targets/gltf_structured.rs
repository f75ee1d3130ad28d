//! Structure-aware fuzzing of the glTF loader: the input bytes choose a document's shape rather
//! than its characters, so that every run gets past JSON parsing and most past validation, to
//! where issue 56's hostile files did their damage. The shapes: node graphs whose children
//! repeat and loop (exponential instancing, cycles, long chains); accessors, buffer views and
//! sparse accessors whose counts, offsets and strides disagree with their data; buffers that
//! declare more or less than they hold; URIs that lead out of the folder or to device files;
//! factors and camera values out of range. Files are resolved in a folder that does not exist
//! and only inside it (the default), so nothing outside the input is read. The limits are
//! small so that a run is fast; findings are panics, hangs, aborts and runs that allocate past
//! libFuzzer's `-rss_limit_mb`.
#![no_main]

use libfuzzer_sys::arbitrary::{Result, Unstructured};
use libfuzzer_sys::fuzz_target;
use vcm_scene::LoadOptions;
use vcm_scene::loader::load_gltf_from_bytes_with;

fuzz_target!(|data: &[u8]| {
    let Ok(json) = document(&mut Unstructured::new(data)) else {
        return;
    };
    let path = std::path::Path::new("/nonexistent-fuzz-dir/input.gltf");
    let options = LoadOptions {
        max_triangles: 100_000,
        max_texels: 1 << 20,
        ..LoadOptions::default()
    };
    let _ = load_gltf_from_bytes_with(path, json.as_bytes(), &options);
});

/// Numbers where loaders go wrong: zero, the unit range's ends, negatives, tiny and huge
/// values (1e39 is infinite once read as f32).
const NUMBERS: &[&str] = &[
    "0", "1", "-1", "0.5", "2", "100", "-5", "1e-6", "1e-45", "1e18", "1e38", "1e39", "-1e39",
];

/// Counts, offsets and lengths: small ones that fit a few bytes and large ones that do not.
const COUNTS: &[u64] = &[
    0,
    1,
    2,
    3,
    4,
    6,
    12,
    36,
    255,
    4096,
    65536,
    1 << 24,
    1 << 31,
    4294967295,
];

/// URIs for buffers and images: data, names in and out of the folder, device files.
const URIS: &[&str] = &[
    "x.bin",
    "../x.bin",
    "%2e%2e/%2e%2e/etc/passwd",
    "/dev/zero",
    "/dev/urandom",
    "sub/../../x.bin",
    "http://example.invalid/x.bin",
    "data:application/octet-stream;base64,AAAAAAAAgD8AAAAA",
    "data:text/plain,hello",
    // A 2 × 2 RGBA PNG.
    "data:image/png;base64,iVBORw0KGgoAAAANSUhEUgAAAAIAAAACCAYAAABytg0kAAAAFElEQVR4nGP4z8DwHwgbGMA0EAAAP9cIeY8TiooAAAAASUVORK5CYII=",
];

fn number(u: &mut Unstructured) -> Result<String> {
    if u.ratio(1, 2)? {
        return Ok(u.choose(NUMBERS)?.to_string());
    }
    let value: f32 = u.arbitrary()?;
    Ok(if value.is_finite() {
        format!("{value:e}")
    } else {
        "0".into()
    })
}

fn numbers(u: &mut Unstructured, n: usize) -> Result<String> {
    let values: Result<Vec<String>> = (0..n).map(|_| number(u)).collect();
    Ok(format!("[{}]", values?.join(", ")))
}

fn count(u: &mut Unstructured) -> Result<u64> {
    if u.ratio(3, 4)? {
        Ok(*u.choose(COUNTS)?)
    } else {
        Ok(u64::from(u.arbitrary::<u32>()?))
    }
}

/// True for about one input byte in sixteen, and never once the input is used up (where
/// `Unstructured` answers zeros): the unusual case, so that short inputs make valid files.
fn rarely(u: &mut Unstructured) -> Result<bool> {
    Ok(u.arbitrary::<u8>()? >= 240)
}

/// An index below `n`, or now and then one past the end.
fn index(u: &mut Unstructured, n: usize) -> Result<usize> {
    if n == 0 || rarely(u)? {
        Ok(n)
    } else {
        u.choose_index(n)
    }
}

/// A count for elements of `size` bytes: mostly one that fits `bytes`, rarely any.
fn count_within(u: &mut Unstructured, bytes: usize, size: usize) -> Result<u64> {
    if rarely(u)? {
        count(u)
    } else {
        Ok(u.int_in_range(0..=bytes / size.max(1))? as u64)
    }
}

/// `"key": value` if the input says so.
fn optional(
    u: &mut Unstructured,
    key: &str,
    value: impl FnOnce(&mut Unstructured) -> Result<String>,
) -> Result<Option<String>> {
    Ok(if u.arbitrary()? {
        Some(format!(r#""{key}": {}"#, value(u)?))
    } else {
        None
    })
}

fn object(fields: impl IntoIterator<Item = Option<String>>) -> String {
    let fields: Vec<String> = fields.into_iter().flatten().collect();
    format!("{{{}}}", fields.join(", "))
}

fn list(items: Vec<String>) -> String {
    format!("[{}]", items.join(", "))
}

fn base64(bytes: &[u8]) -> String {
    const DIGITS: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut text = String::new();
    for chunk in bytes.chunks(3) {
        let word = chunk
            .iter()
            .enumerate()
            .fold(0u32, |w, (i, &b)| w | u32::from(b) << (16 - 8 * i));
        for i in 0..4 {
            if i <= chunk.len() {
                text.push(char::from(DIGITS[(word >> (18 - 6 * i) & 63) as usize]));
            } else {
                text.push('=');
            }
        }
    }
    text
}

/// The document: one embedded buffer of input bytes (and perhaps a second by URI), views and
/// accessors over it, meshes, materials, textures, cameras and a node graph.
fn document(u: &mut Unstructured) -> Result<String> {
    // Words that read as small floats (positions, normals) or small integers (indices).
    let mut data = Vec::new();
    for _ in 0..u.int_in_range(0..=128)? {
        let byte: u8 = u.arbitrary()?;
        let word = if byte & 1 == 0 {
            (f32::from(byte as i8) / 16.0).to_bits()
        } else {
            u32::from(byte >> 1) % 8
        };
        data.extend(word.to_le_bytes());
    }
    let declared = if rarely(u)? {
        count(u)?
    } else {
        data.len() as u64
    };
    let mut buffers = vec![format!(
        r#"{{"byteLength": {declared}, "uri": "data:application/octet-stream;base64,{}"}}"#,
        base64(&data)
    )];
    if rarely(u)? {
        let uri = u.choose(URIS)?;
        buffers.push(format!(
            r#"{{"byteLength": {}, "uri": "{uri}"}}"#,
            count(u)?
        ));
    }

    let views: Result<Vec<String>> = (0..u.int_in_range(1..=4)?)
        .map(|_| {
            let offset = count_within(u, data.len(), 4)? * 4;
            let length = if rarely(u)? {
                count(u)?
            } else {
                (data.len() as u64).saturating_sub(offset)
            };
            let stride = |u: &mut Unstructured| Ok((u.int_in_range(1..=16u32)? * 4).to_string());
            Ok(object([
                Some(format!(r#""buffer": {}"#, index(u, buffers.len())?)),
                Some(format!(r#""byteLength": {length}"#)),
                Some(format!(r#""byteOffset": {offset}"#)),
                optional(u, "byteStride", stride)?,
            ]))
        })
        .collect();
    let views = views?;

    let accessor_count = u.int_in_range(1..=6)?;
    let accessors: Result<Vec<String>> = (0..accessor_count)
        .map(|_| {
            let kind = if rarely(u)? {
                *u.choose(&["SCALAR", "VEC2", "VEC3", "VEC4"])?
            } else {
                "VEC3"
            };
            let components = match kind {
                "SCALAR" => 1,
                "VEC2" => 2,
                "VEC3" => 3,
                _ => 4,
            };
            let component_type = if u.arbitrary()? {
                *u.choose(&[5121u32, 5123, 5125, 5120, 5122])?
            } else {
                5126
            };
            let sparse = |u: &mut Unstructured| {
                Ok(format!(
                    r#"{{"count": {}, "indices": {{"bufferView": {}, "componentType": {}}},
                        "values": {{"bufferView": {}}}}}"#,
                    count(u)?,
                    index(u, views.len())?,
                    u.choose(&[5121u32, 5123, 5125])?,
                    index(u, views.len())?
                ))
            };
            let view = if rarely(u)? {
                None
            } else {
                Some(format!(r#""bufferView": {}"#, index(u, views.len())?))
            };
            Ok(object([
                view,
                optional(u, "byteOffset", |u| {
                    Ok((count_within(u, 64, 4)? * 4).to_string())
                })?,
                Some(format!(r#""componentType": {component_type}"#)),
                optional(u, "normalized", |u| Ok(u.arbitrary::<bool>()?.to_string()))?,
                Some(format!(
                    r#""count": {}"#,
                    count_within(u, data.len(), 4 * components)?
                )),
                Some(format!(r#""type": "{kind}""#)),
                Some(format!(r#""min": {}"#, numbers(u, components)?)),
                Some(format!(r#""max": {}"#, numbers(u, components)?)),
                optional(u, "sparse", sparse)?,
            ]))
        })
        .collect();
    let accessors = accessors?;

    let material_count = u.int_in_range(0..=2)?;
    let texture_count = u.int_in_range(0..=2)?;
    let texture =
        |u: &mut Unstructured| Ok(format!(r#"{{"index": {}}}"#, index(u, texture_count)?));
    let materials: Result<Vec<String>> = (0..material_count)
        .map(|_| {
            let pbr = object([
                optional(u, "baseColorFactor", |u| numbers(u, 4))?,
                optional(u, "metallicFactor", number)?,
                optional(u, "roughnessFactor", number)?,
                optional(u, "baseColorTexture", texture)?,
            ]);
            let extensions = object([
                optional(u, "KHR_materials_transmission", |u| {
                    Ok(format!(r#"{{"transmissionFactor": {}}}"#, number(u)?))
                })?,
                optional(u, "KHR_materials_ior", |u| {
                    Ok(format!(r#"{{"ior": {}}}"#, number(u)?))
                })?,
                optional(u, "KHR_materials_specular", |u| {
                    Ok(format!(
                        r#"{{"specularFactor": {}, "specularColorFactor": {}}}"#,
                        number(u)?,
                        numbers(u, 3)?
                    ))
                })?,
                optional(u, "KHR_materials_emissive_strength", |u| {
                    Ok(format!(r#"{{"emissiveStrength": {}}}"#, number(u)?))
                })?,
                optional(u, "KHR_materials_volume", |u| {
                    Ok(format!(
                        r#"{{"thicknessFactor": {}, "attenuationDistance": {},
                            "attenuationColor": {}}}"#,
                        number(u)?,
                        number(u)?,
                        numbers(u, 3)?
                    ))
                })?,
            ]);
            Ok(object([
                Some(format!(r#""pbrMetallicRoughness": {pbr}"#)),
                Some(format!(r#""extensions": {extensions}"#)),
                optional(u, "emissiveFactor", |u| numbers(u, 3))?,
                optional(u, "alphaMode", |_| Ok(r#""MASK""#.into()))?,
                optional(u, "alphaCutoff", number)?,
            ]))
        })
        .collect();
    let materials = materials?;

    let image_count = u.int_in_range(0..=2)?;
    let images: Result<Vec<String>> = (0..image_count)
        .map(|_| Ok(format!(r#"{{"uri": "{}"}}"#, u.choose(URIS)?)))
        .collect();
    let textures: Result<Vec<String>> = (0..texture_count)
        .map(|_| Ok(format!(r#"{{"source": {}}}"#, index(u, image_count)?)))
        .collect();

    let mesh_count = u.int_in_range(1..=2)?;
    let meshes: Result<Vec<String>> = (0..mesh_count)
        .map(|_| {
            let primitives: Result<Vec<String>> = (0..u.int_in_range(1..=2)?)
                .map(|_| {
                    let attributes = object([
                        Some(format!(r#""POSITION": {}"#, index(u, accessor_count)?)),
                        optional(u, "NORMAL", |u| Ok(index(u, accessor_count)?.to_string()))?,
                        optional(u, "TEXCOORD_0", |u| {
                            Ok(index(u, accessor_count)?.to_string())
                        })?,
                        optional(u, "COLOR_0", |u| Ok(index(u, accessor_count)?.to_string()))?,
                    ]);
                    Ok(object([
                        Some(format!(r#""attributes": {attributes}"#)),
                        optional(u, "indices", |u| Ok(index(u, accessor_count)?.to_string()))?,
                        optional(u, "mode", |u| Ok(u.int_in_range(0..=6u32)?.to_string()))?,
                        optional(u, "material", |u| Ok(index(u, material_count)?.to_string()))?,
                    ]))
                })
                .collect();
            Ok(format!(r#"{{"primitives": {}}}"#, list(primitives?)))
        })
        .collect();

    let camera_count = u.int_in_range(0..=1)?;
    let cameras: Result<Vec<String>> = (0..camera_count)
        .map(|_| {
            let perspective = object([
                Some(format!(r#""yfov": {}"#, number(u)?)),
                Some(format!(r#""znear": {}"#, number(u)?)),
                optional(u, "aspectRatio", number)?,
            ]);
            Ok(format!(
                r#"{{"type": "perspective", "perspective": {perspective}}}"#
            ))
        })
        .collect();

    // The node graph: children may repeat (instancing), loop back (cycles) or chain deep.
    let node_count = u.int_in_range(1..=40)?;
    let nodes: Result<Vec<String>> = (0..node_count)
        .map(|_| {
            let children = |u: &mut Unstructured| {
                let children: Result<Vec<String>> = (0..u.int_in_range(1..=3)?)
                    .map(|_| Ok(index(u, node_count)?.to_string()))
                    .collect();
                Ok(list(children?))
            };
            Ok(object([
                optional(u, "mesh", |u| Ok(index(u, mesh_count)?.to_string()))?,
                optional(u, "camera", |u| Ok(index(u, camera_count)?.to_string()))?,
                optional(u, "children", children)?,
                optional(u, "translation", |u| numbers(u, 3))?,
                optional(u, "scale", |u| numbers(u, 3))?,
            ]))
        })
        .collect();
    let roots: Result<Vec<String>> = (0..u.int_in_range(1..=3)?)
        .map(|_| Ok(index(u, node_count)?.to_string()))
        .collect();

    Ok(format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": {}}}],
        "nodes": {}, "meshes": {}, "accessors": {}, "bufferViews": {}, "buffers": {},
        "materials": {}, "images": {}, "textures": {}, "cameras": {},
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior",
            "KHR_materials_specular", "KHR_materials_emissive_strength",
            "KHR_materials_volume"]}}"#,
        list(roots?),
        list(nodes?),
        list(meshes?),
        list(accessors),
        list(views),
        list(buffers),
        list(materials),
        list(images?),
        list(textures?),
        list(cameras?)
    ))
}
