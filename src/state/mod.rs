//! A render's state as a value and a file: everything needed to continue a render or to
//! combine renders of the same image ([`RenderState`]).
//!
//! A render is a pure function of the scene, the settings and the global sample (iteration)
//! indices it covers: sample `s` is the same whatever process, frame or shard renders it, and
//! the film's sums are exact ([`vcm::exact_sum`]), so their order does not matter either.
//! Hence a resumed render equals the uninterrupted one, and shards covering 0..N merged in
//! any order equal one process rendering 0..N, bit for bit.

mod file;
mod ranges;
mod scene_hash;
mod settings;

use std::ops::Range;
use std::path::{Path, PathBuf};

use vcm::Film;
use vcm::image_io::RgbImage;

use file::Contents;
pub use file::{FORMAT_NAME, FORMAT_VERSION};
pub use ranges::{SampleRanges, parse_range};
pub use scene_hash::scene_hash;
pub use settings::{RenderSettings, SETTING_KEYS, SETTING_OPTIONS, SETTINGS};

/// Why a render state could not be read, written, merged or resumed.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    /// The file could not be read.
    #[error("{}: cannot read the render state: {source}", path.display())]
    Read {
        /// The state file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error("{}: cannot write the render state: {reason}", path.display())]
    Write {
        /// The state file.
        path: PathBuf,
        /// What went wrong.
        reason: String,
    },
    /// The file is no render state (or one truncated beyond recognition).
    #[error("{}: not a vcm-rs render state: {reason}", path.display())]
    NotAState {
        /// The file.
        path: PathBuf,
        /// Why not.
        reason: String,
    },
    /// A render state of a format version this build does not know.
    #[error(
        "{}: written by a newer vcm-rs (render state format version {version}; this build \
         reads version {FORMAT_VERSION} and older)",
        path.display()
    )]
    NewerFormat {
        /// The file.
        path: PathBuf,
        /// Its format version.
        version: u32,
    },
    /// A render state whose contents are damaged or inconsistent.
    #[error("{}: the render state is damaged: {reason}", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// Two states (or a state and a render) that cannot be combined.
    #[error("{0}")]
    Incompatible(String),
}

/// A render's state: its film (exact sums and sample counts per pixel), which global samples
/// it holds, and what it was rendered from.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderState {
    /// The estimator's settings.
    pub settings: RenderSettings,
    /// The scene's content hash ([`scene_hash`]).
    pub scene_hash: u64,
    /// The scene file it was rendered from (where a resumed render looks for it first).
    pub scene_path: PathBuf,
    /// The image file the render wrote, if any (where a resumed render writes by default).
    pub output: Option<PathBuf>,
    /// The global samples (iterations) the film holds.
    pub samples: SampleRanges,
    /// The samples per pixel the render was asked for, if it was given a count (a resumed
    /// render continues to it by default).
    pub target_spp: Option<u32>,
    /// The accumulated samples and splats.
    pub film: Film,
}

impl RenderState {
    /// An empty state (no samples yet) for `settings` on the scene with content hash
    /// `scene_hash` loaded from `scene_path`.
    pub fn new(settings: RenderSettings, scene_hash: u64, scene_path: PathBuf) -> RenderState {
        let film = Film::new(settings.width, settings.height);
        RenderState {
            settings,
            scene_hash,
            scene_path,
            output: None,
            samples: SampleRanges::new(),
            target_spp: None,
            film,
        }
    }

    /// Reads a state file, checking it fully (see `docs/render-state.md`).
    pub fn load(path: impl AsRef<Path>) -> Result<RenderState, StateError> {
        file::read(path.as_ref())
    }

    /// Writes the state file atomically: through a temporary file renamed over `path`.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<(), StateError> {
        file::write(path.as_ref(), Contents::of(self))
    }

    /// Writes, as [`RenderState::save`] does, the state this one becomes once it holds
    /// `film`, rendered from it, with the samples `rendered` added: without copying the film
    /// (a render's checkpoints and last save).
    pub fn save_with(
        &self,
        film: &Film,
        rendered: Range<u32>,
        path: impl AsRef<Path>,
    ) -> Result<(), StateError> {
        let mut samples = self.samples.clone();
        samples.insert(rendered);
        let contents = Contents {
            state: self,
            film,
            samples: &samples,
        };
        file::write(path.as_ref(), contents)
    }

    /// The state as the bytes of a state file (what [`RenderState::save`] writes), to send
    /// elsewhere; the error says why it cannot be encoded.
    pub fn to_bytes(&self) -> Result<Vec<u8>, String> {
        file::encode(Contents::of(self))
    }

    /// A state from the bytes of a state file, checked as [`RenderState::load`] checks a
    /// file; errors name `origin` as where the bytes came from.
    pub fn from_bytes(bytes: &[u8], origin: impl AsRef<Path>) -> Result<RenderState, StateError> {
        file::decode(bytes, origin.as_ref())
    }

    /// The mean radiance per pixel.
    pub fn image(&self) -> RgbImage {
        self.film.image()
    }

    /// Why `other` cannot be combined with this state, if it cannot: another scene (by
    /// content) or other settings. `ours` and `theirs` name the two in the message.
    pub fn incompatibility(&self, other: &RenderState, ours: &str, theirs: &str) -> Option<String> {
        if self.scene_hash != other.scene_hash {
            return Some(format!(
                "{theirs} was rendered from another scene than {ours} ({} and {} differ in \
                 content)",
                other.scene_path.display(),
                self.scene_path.display()
            ));
        }
        let differences = self.settings.differences(&other.settings);
        if differences.is_empty() {
            return None;
        }
        let list: Vec<String> = differences
            .iter()
            .map(|(key, a, b)| format!("{key} {b} instead of {a}"))
            .collect();
        Some(format!(
            "{theirs} was rendered with other settings than {ours}: {}",
            list.join(", ")
        ))
    }

    /// Adds the samples of `other`, which must come from the same scene and settings and
    /// hold none of the samples this state holds; `ours` and `theirs` name the two in the
    /// error. The sums are exact, so merging is associative and commutative.
    pub fn merge(
        &mut self,
        other: &RenderState,
        ours: &str,
        theirs: &str,
    ) -> Result<(), StateError> {
        if let Some(reason) = self.incompatibility(other, ours, theirs) {
            return Err(StateError::Incompatible(reason));
        }
        if let Some(shared) = self.samples.overlap_with(&other.samples) {
            return Err(StateError::Incompatible(format!(
                "{theirs} and {ours} both hold samples {}..{}: merging them would count those \
                 twice",
                shared.start, shared.end
            )));
        }
        self.film.merge(&other.film);
        self.samples.insert_all(&other.samples);
        self.target_spp = self.target_spp.max(other.target_spp);
        Ok(())
    }
}

#[cfg(test)]
mod tests;
