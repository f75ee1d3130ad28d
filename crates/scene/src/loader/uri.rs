//! Resolving glTF URIs: `data:` URIs (base64) and file paths relative to the scene file.

use std::path::Path;

use base64::Engine;

/// Reads the bytes a URI refers to. Errors are plain sentences for the caller to wrap.
pub(crate) fn read_uri(base: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest
            .split_once(',')
            .ok_or_else(|| "malformed data URI (no ',')".to_string())?;
        if !header.ends_with(";base64") {
            return Err("data URI is not base64-encoded".into());
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("invalid base64 in data URI: {e}"));
    }
    if uri.contains("://") {
        return Err(format!("unsupported URI scheme in '{uri}'"));
    }
    let decoded = urlencoding::decode(uri).map_err(|e| format!("invalid URI '{uri}': {e}"))?;
    let file = base.join(decoded.as_ref());
    std::fs::read(&file).map_err(|e| format!("cannot read '{}': {e}", file.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_uris_decode_and_bad_ones_are_errors() {
        let base = Path::new(".");
        assert_eq!(
            read_uri(base, "data:application/octet-stream;base64,AAEC").unwrap(),
            vec![0, 1, 2]
        );
        assert!(read_uri(base, "data:text/plain,hello").is_err());
        assert!(read_uri(base, "data:;base64,***").is_err());
        assert!(read_uri(base, "%FF%FE.bin").is_err());
        assert!(read_uri(base, "http://example.invalid/a.bin").is_err());
        assert!(read_uri(base, "no-such-file.bin").is_err());
    }
}
