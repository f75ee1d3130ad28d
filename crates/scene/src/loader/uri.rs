//! Resolving glTF URIs: `data:` URIs (base64) and file paths relative to the scene file.

use base64::Engine;

use crate::loader::files::{Length, ReadError, SceneFolder};

/// Reads the bytes a URI refers to: `length` of them from a file (a data URI holds what it
/// holds). Errors are plain sentences for the caller to wrap.
pub(crate) fn read_uri(
    folder: &SceneFolder,
    uri: &str,
    length: Length,
) -> Result<Vec<u8>, ReadError> {
    let failed = |reason: String| ReadError::Failed(reason);
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest
            .split_once(',')
            .ok_or_else(|| failed("malformed data URI (no ',')".into()))?;
        if !header.ends_with(";base64") {
            return Err(failed("data URI is not base64-encoded".into()));
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| failed(format!("invalid base64 in data URI: {e}")));
    }
    if uri.contains("://") {
        return Err(failed(format!("unsupported URI scheme in '{uri}'")));
    }
    let decoded =
        urlencoding::decode(uri).map_err(|e| failed(format!("invalid URI '{uri}': {e}")))?;
    folder.read(&decoded, length)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loader::options::LoadOptions;

    #[test]
    fn data_uris_decode_and_bad_ones_are_errors() {
        let folder = SceneFolder::of(std::path::Path::new("scene.gltf"), &LoadOptions::default());
        let read = |uri| read_uri(&folder, uri, Length::Whole);
        assert_eq!(
            read("data:application/octet-stream;base64,AAEC").unwrap(),
            vec![0, 1, 2]
        );
        assert!(read("data:text/plain,hello").is_err());
        assert!(read("data:;base64,***").is_err());
        assert!(read("%FF%FE.bin").is_err());
        assert!(read("http://example.invalid/a.bin").is_err());
        assert!(read("no-such-file.bin").is_err());
        // Percent-encoding does not hide a way out of the folder.
        assert_eq!(read("%2E%2E/%2E%2E/etc/passwd"), Err(ReadError::Outside));
    }
}
