//! Pieces of glTF files for loader tests: one triangle's buffer, data URIs, GLB containers and
//! node graphs that are hostile by their shape (exponential instancing, deep chains).

use std::fmt::Write;

use base64::Engine;

/// One triangle in the z = 0 plane, counter-clockwise seen from +Z: its three positions as
/// 36 bytes of little-endian `f32`.
pub fn triangle_positions() -> Vec<u8> {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    positions.iter().flat_map(|f| f.to_le_bytes()).collect()
}

/// `bytes` as a base64 `data:` URI.
pub fn data_uri(bytes: &[u8]) -> String {
    let data = base64::engine::general_purpose::STANDARD.encode(bytes);
    format!("data:application/octet-stream;base64,{data}")
}

/// `json` and `binary` as a GLB container (each chunk padded to 4 bytes).
pub fn glb(json: &str, binary: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    json.resize(json.len().next_multiple_of(4), b' ');
    let mut binary = binary.to_vec();
    binary.resize(binary.len().next_multiple_of(4), 0);
    // Header (12 bytes), then each chunk's length and kind (8 bytes) before its data.
    let length = 12 + 8 + json.len() + 8 + binary.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(length as u32).to_le_bytes());
    for (kind, chunk) in [(b"JSON", &json), (b"BIN\0", &binary)] {
        out.extend_from_slice(&(chunk.len() as u32).to_le_bytes());
        out.extend_from_slice(kind);
        out.extend_from_slice(chunk);
    }
    out
}

/// A `nodes` array of `levels` nodes, each listing the next one twice, the last drawing mesh
/// 0: 2^(levels−1) instances of it.
pub fn doubling_chain(levels: usize) -> String {
    let mut nodes: Vec<String> = (1..levels)
        .map(|next| format!(r#"{{"children": [{next}, {next}]}}"#))
        .collect();
    nodes.push(r#"{"mesh": 0}"#.into());
    format!("[{}]", nodes.join(", "))
}

/// A `nodes` array of `depth` nodes, each the only child of the one before, the last drawing
/// mesh 0.
pub fn deep_chain(depth: usize) -> String {
    let mut nodes = String::from("[");
    for next in 1..depth {
        write!(nodes, r#"{{"children": [{next}]}}, "#).expect("writing to a String");
    }
    nodes.push_str(r#"{"mesh": 0}]"#);
    nodes
}
