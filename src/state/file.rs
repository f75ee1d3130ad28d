//! The render state file: a [safetensors](https://huggingface.co/docs/safetensors) file, so
//! that any safetensors reader (Python's `safetensors.numpy.load_file`, for one) opens it.
//! `docs/render-state.md` documents the fields.
//!
//! Tensors (little-endian, row by row from the top-left pixel):
//! - `sum` F64 [height, width, 3]: each pixel's sum of samples and splats per channel,
//!   rounded to f64 (the image is `sum / samples`);
//! - `sum_exact` U64 [height, width, 3, 5]: the same sums exactly, as 320-bit two's
//!   complement integers in units of 2⁻¹⁴⁹, least significant word first
//!   ([`vcm::exact_sum`]); the state is read back from these;
//! - `samples` U64 [height, width]: samples taken per pixel (non-finite ones included).
//!
//! Text metadata: `format`, `format_version`, the scene's content hash and path, every
//! estimator setting ([`super::SETTING_KEYS`]), the global `samples` ranges held, the
//! `dropped` non-finite samples, an optional `target_spp`, and an xxh3 `checksum` over all
//! of it and the tensors.

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};

use safetensors::tensor::TensorView;
use safetensors::{Dtype, SafeTensors};
use vcm::atomic_write::write_atomically;
use vcm::exact_sum::{ExactSum, WORDS};
use vcm::{Film, PixelSum, rounded_sum};
use xxhash_rust::xxh3::Xxh3;

use super::{RenderSettings, RenderState, SampleRanges, StateError};

/// The `format` entry of every render state file.
pub const FORMAT_NAME: &str = "vcm-rs render state";
/// The format version this build writes; it reads this one and older ones.
pub const FORMAT_VERSION: u32 = 1;

/// The tensors, in the order the checksum covers them.
const TENSORS: [&str; 3] = ["sum", "sum_exact", "samples"];

/// What a state file holds: a state's settings and provenance with a film and the samples
/// it holds, which need not be the state's own (a render writes its film in progress).
#[derive(Clone, Copy)]
pub struct Contents<'a> {
    pub state: &'a RenderState,
    pub film: &'a Film,
    pub samples: &'a SampleRanges,
}

impl<'a> Contents<'a> {
    /// `state` as it is.
    pub fn of(state: &'a RenderState) -> Contents<'a> {
        Contents {
            state,
            film: &state.film,
            samples: &state.samples,
        }
    }

    /// The text metadata, but the checksum.
    fn metadata(&self) -> BTreeMap<String, String> {
        let state = self.state;
        let mut metadata = state.settings.to_metadata();
        let mut put = |key: &str, value: String| metadata.insert(key.to_string(), value);
        put("format", FORMAT_NAME.into());
        put("format_version", FORMAT_VERSION.to_string());
        put("scene", state.scene_path.display().to_string());
        put("scene_hash", format!("xxh3:{:016x}", state.scene_hash));
        put("samples", self.samples.to_string());
        put("dropped", self.film.dropped().to_string());
        if let Some(output) = &state.output {
            put("output", output.display().to_string());
        }
        if let Some(spp) = state.target_spp {
            put("target_spp", spp.to_string());
        }
        metadata
    }
}

/// Writes `contents` to `path` through a temporary file in the same folder, renamed over
/// `path` once complete.
pub fn write(path: &Path, contents: Contents) -> Result<(), StateError> {
    let failed = |reason: String| StateError::Write {
        path: path.to_path_buf(),
        reason,
    };
    let bytes = encode(contents).map_err(failed)?;
    // A plain write, so the file gets the permissions the umask gives new files.
    write_atomically(
        path,
        |temporary| std::fs::write(temporary, &bytes).map_err(|e| failed(e.to_string())),
        |e| failed(e.to_string()),
    )
}

/// The bytes of the state file of `contents`; the error says why it cannot be encoded.
pub fn encode(contents: Contents) -> Result<Vec<u8>, String> {
    let film = contents.film;
    let (width, height) = (film.width() as usize, film.height() as usize);
    let rounded: Vec<u8> = film
        .sums()
        .iter()
        .flat_map(|sum| rounded_sum(sum).to_array())
        .flat_map(f64::to_le_bytes)
        .collect();
    let exact: Vec<u8> = film
        .sums()
        .iter()
        .flatten()
        .flat_map(ExactSum::words)
        .flat_map(u64::to_le_bytes)
        .collect();
    let samples: Vec<u8> = film
        .sample_counts()
        .iter()
        .flat_map(|n| n.to_le_bytes())
        .collect();
    let view = |dtype, shape, data| TensorView::new(dtype, shape, data).map_err(|e| e.to_string());
    let tensors = [
        ("sum", view(Dtype::F64, vec![height, width, 3], &rounded)?),
        (
            "sum_exact",
            view(Dtype::U64, vec![height, width, 3, WORDS], &exact)?,
        ),
        ("samples", view(Dtype::U64, vec![height, width], &samples)?),
    ];
    let mut metadata = contents.metadata();
    let checksum = checksum(&metadata, tensors.iter().map(|(_, t)| t));
    metadata.insert("checksum".into(), checksum);
    let metadata: HashMap<String, String> = metadata.into_iter().collect();
    safetensors::serialize(tensors.iter().cloned(), Some(metadata)).map_err(|e| e.to_string())
}

/// Reads the render state at `path`, checking everything: that it is a regular file and a
/// safetensors file, that it is a render state of a version this build reads, that its
/// checksum matches, and that its tensors and metadata agree with one another.
pub fn read(path: &Path) -> Result<RenderState, StateError> {
    let io = |source| StateError::Read {
        path: path.to_path_buf(),
        source,
    };
    let kind = std::fs::metadata(path).map_err(io)?.file_type();
    if !kind.is_file() {
        return Err(not_a_state(path, "it is not a regular file"));
    }
    let bytes = std::fs::read(path).map_err(io)?;
    decode(&bytes, path)
}

/// Reads a render state from the bytes of a state file, checking everything as [`read`]
/// does; errors name `path` as where the bytes came from.
pub fn decode(bytes: &[u8], path: &Path) -> Result<RenderState, StateError> {
    let file = SafeTensors::deserialize(bytes).map_err(|e| {
        not_a_state(
            path,
            &format!("not a complete safetensors file ({e}); it may be truncated"),
        )
    })?;
    let (_, header) = SafeTensors::read_metadata(bytes)
        .map_err(|e| not_a_state(path, &format!("unreadable header ({e})")))?;
    let metadata: BTreeMap<String, String> = header
        .metadata()
        .clone()
        .unwrap_or_default()
        .into_iter()
        .collect();
    if metadata.get("format").map(String::as_str) != Some(FORMAT_NAME) {
        return Err(not_a_state(
            path,
            "a safetensors file, but its `format` is not a vcm-rs render state",
        ));
    }
    let damaged = |reason: String| StateError::Damaged {
        path: path.to_path_buf(),
        reason,
    };
    let version: u32 = metadata
        .get("format_version")
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| damaged("its `format_version` is missing or unreadable".into()))?;
    if version > FORMAT_VERSION {
        return Err(StateError::NewerFormat {
            path: path.to_path_buf(),
            version,
        });
    }
    let tensor = |name: &str| {
        file.tensor(name)
            .map_err(|_| damaged(format!("the tensor `{name}` is missing")))
    };
    let (rounded, exact, samples) = (tensor("sum")?, tensor("sum_exact")?, tensor("samples")?);
    let mut unsigned = metadata.clone();
    let stored = unsigned.remove("checksum").unwrap_or_default();
    if checksum(&unsigned, [&rounded, &exact, &samples].into_iter()) != stored {
        return Err(damaged(
            "its checksum does not match its contents (the file was changed or corrupted)".into(),
        ));
    }
    let entry = |key: &str| {
        metadata
            .get(key)
            .ok_or_else(|| damaged(format!("the entry `{key}` is missing")))
    };
    let settings = RenderSettings::from_metadata(&metadata).map_err(damaged)?;
    let (width, height) = (settings.width as usize, settings.height as usize);
    check_tensor(&rounded, Dtype::F64, &[height, width, 3]).map_err(damaged)?;
    check_tensor(&exact, Dtype::U64, &[height, width, 3, WORDS]).map_err(damaged)?;
    check_tensor(&samples, Dtype::U64, &[height, width]).map_err(damaged)?;
    let words = little_endian_words(exact.data());
    let sums: Vec<PixelSum> = words
        .chunks_exact(3 * WORDS)
        .map(|pixel| {
            std::array::from_fn(|c| {
                ExactSum::from_words(std::array::from_fn(|w| pixel[c * WORDS + w]))
            })
        })
        .collect();
    let counts = little_endian_words(samples.data());
    let dropped: u64 = entry("dropped")?
        .parse()
        .map_err(|_| damaged("the entry `dropped` is not a count".into()))?;
    let size = (settings.width, settings.height);
    let film = Film::from_parts(size, sums, counts, dropped)
        .ok_or_else(|| damaged("the tensors do not have the image's size".into()))?;
    let ranges: SampleRanges = entry("samples")?
        .parse()
        .map_err(|e| damaged(format!("the entry `samples`: {e}")))?;
    let scene_hash = entry("scene_hash")?
        .strip_prefix("xxh3:")
        .and_then(|h| u64::from_str_radix(h, 16).ok())
        .ok_or_else(|| damaged("the entry `scene_hash` is unreadable".into()))?;
    let target_spp = match metadata.get("target_spp") {
        Some(n) => Some(
            n.parse()
                .map_err(|_| damaged("the entry `target_spp` is not a count".into()))?,
        ),
        None => None,
    };
    Ok(RenderState {
        settings,
        scene_hash,
        scene_path: PathBuf::from(entry("scene")?),
        output: metadata.get("output").map(PathBuf::from),
        samples: ranges,
        target_spp,
        film,
    })
}

/// The little-endian 64-bit words of `bytes` (a trailing partial word is ignored; the
/// tensors' shapes were checked before).
fn little_endian_words(bytes: &[u8]) -> Vec<u64> {
    bytes
        .chunks_exact(8)
        .map(|b| u64::from_le_bytes(b.try_into().expect("chunks of 8 bytes")))
        .collect()
}

/// Checks a tensor's type and shape; the error says what differs.
fn check_tensor(tensor: &TensorView<'_>, dtype: Dtype, shape: &[usize]) -> Result<(), String> {
    if tensor.dtype() != dtype || tensor.shape() != shape {
        return Err(format!(
            "a tensor is {:?} {:?}, not {dtype:?} {shape:?} as the image size says",
            tensor.dtype(),
            tensor.shape()
        ));
    }
    Ok(())
}

/// `path` is not a render state, for `reason`.
fn not_a_state(path: &Path, reason: &str) -> StateError {
    StateError::NotAState {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// `xxh3:` and the hexadecimal xxh3 hash of the metadata (sorted by key) and the tensors
/// (their names, types, shapes and bytes, in [`TENSORS`] order).
fn checksum<'a>(
    metadata: &BTreeMap<String, String>,
    tensors: impl Iterator<Item = &'a TensorView<'a>>,
) -> String {
    fn text(hasher: &mut Xxh3, s: &str) {
        hasher.update(&(s.len() as u64).to_le_bytes());
        hasher.update(s.as_bytes());
    }
    let mut hasher = Xxh3::new();
    for (key, value) in metadata {
        text(&mut hasher, key);
        text(&mut hasher, value);
    }
    for (name, tensor) in TENSORS.iter().zip(tensors) {
        text(&mut hasher, name);
        text(
            &mut hasher,
            &format!("{:?} {:?}", tensor.dtype(), tensor.shape()),
        );
        hasher.update(tensor.data());
    }
    format!("xxh3:{:016x}", hasher.digest())
}
