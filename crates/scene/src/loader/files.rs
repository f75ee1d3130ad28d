//! Reading the files a scene refers to (glTF buffers and images, MTL libraries, textures):
//! only regular files, no more bytes than they hold or the scene declares, and by default
//! only inside the scene file's folder.

use std::io::{ErrorKind, Read};
use std::path::{Component, Path, PathBuf};

use crate::loader::options::LoadOptions;

/// Why a file the scene refers to was not read.
#[derive(Debug, PartialEq)]
pub(crate) enum ReadError {
    /// The name leads outside the scene's folder, which the options do not allow. Nothing
    /// was opened or looked up outside: the message can tell nothing about the file.
    Outside,
    /// The file is missing, not a regular file, shorter than declared, or unreadable: a
    /// sentence for the caller to wrap.
    Failed(String),
}

/// How many bytes to read.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Length {
    /// The whole file (images, MTL libraries): as long as it is now, no longer.
    Whole,
    /// Exactly this many bytes from the start (a glTF buffer's `byteLength`): a shorter
    /// file is an error, a longer one is read no further.
    Declared(u64),
}

/// The folder a scene file lies in, and whether files outside it may be read.
pub(crate) struct SceneFolder {
    folder: PathBuf,
    allow_outside: bool,
}

impl SceneFolder {
    /// The folder of `scene_file` (the current one for a bare file name).
    pub fn of(scene_file: &Path, options: &LoadOptions) -> Self {
        let folder = match scene_file.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => parent.to_path_buf(),
            _ => PathBuf::from("."),
        };
        SceneFolder {
            folder,
            allow_outside: options.allow_outside_files,
        }
    }

    /// Reads `length` bytes of the file `name` (relative to the folder, as written in the
    /// scene, already percent-decoded).
    pub fn read(&self, name: &str, length: Length) -> Result<Vec<u8>, ReadError> {
        let file = self.folder.join(name);
        let opened = if self.allow_outside {
            file.clone()
        } else {
            self.confine(Path::new(name), &file)?
        };
        read_regular_file(&opened, &file, length).map_err(ReadError::Failed)
    }

    /// The real path of `file` (the folder joined with `name`) if it lies inside the folder.
    /// The name is checked first without touching the file system (no absolute path, no `..`
    /// above the folder), then the real path, which symbolic links may lead elsewhere.
    fn confine(&self, name: &Path, file: &Path) -> Result<PathBuf, ReadError> {
        let mut depth = 0usize;
        for component in name.components() {
            match component {
                Component::Normal(_) => depth += 1,
                Component::CurDir => {}
                Component::ParentDir => {
                    depth = depth.checked_sub(1).ok_or(ReadError::Outside)?;
                }
                Component::RootDir | Component::Prefix(_) => return Err(ReadError::Outside),
            }
        }
        let unreadable =
            |e: std::io::Error| ReadError::Failed(format!("cannot read '{}': {e}", file.display()));
        let real = file.canonicalize().map_err(unreadable)?;
        let folder = self.folder.canonicalize().map_err(unreadable)?;
        if real.starts_with(&folder) {
            Ok(real)
        } else {
            Err(ReadError::Outside)
        }
    }
}

/// Opens `file` if it is a regular file, with its length.
///
/// Device files (`/dev/zero`), FIFOs and sockets are refused before they are opened: they
/// have no length to bound a read by, and opening a FIFO blocks. The opened file is checked
/// again, in case the name was pointed elsewhere in between.
pub(crate) fn open_regular_file(file: &Path) -> std::io::Result<(std::fs::File, u64)> {
    let not_regular = || std::io::Error::new(ErrorKind::InvalidInput, "not a regular file");
    if !std::fs::metadata(file)?.is_file() {
        return Err(not_regular());
    }
    let opened = std::fs::File::open(file)?;
    let metadata = opened.metadata()?;
    if !metadata.is_file() {
        return Err(not_regular());
    }
    Ok((opened, metadata.len()))
}

/// Reads `length` bytes of `file` if it is a regular file (see [`open_regular_file`]), named
/// `shown` in messages. The length is that of the file when it is opened; memory for it is
/// reserved fallibly, so that even a huge real file gives an error rather than an abort.
pub(crate) fn read_regular_file(
    file: &Path,
    shown: &Path,
    length: Length,
) -> Result<Vec<u8>, String> {
    let shown = shown.display();
    let failed = |e: std::io::Error| format!("cannot read '{shown}': {e}");
    let (opened, real_length) = open_regular_file(file).map_err(failed)?;
    let short = |declared: u64| format!("'{shown}' is shorter than the {declared} bytes declared");
    let wanted = match length {
        Length::Whole => real_length,
        Length::Declared(declared) if declared > real_length => return Err(short(declared)),
        Length::Declared(declared) => declared,
    };
    let mut bytes = Vec::new();
    usize::try_from(wanted)
        .ok()
        .and_then(|wanted| bytes.try_reserve_exact(wanted).ok())
        .ok_or_else(|| format!("'{shown}': not enough memory for {wanted} bytes"))?;
    opened
        .take(wanted)
        .read_to_end(&mut bytes)
        .map_err(failed)?;
    match length {
        Length::Declared(declared) if (bytes.len() as u64) < declared => Err(short(declared)),
        _ => Ok(bytes),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(dir: &Path, allow_outside: bool) -> SceneFolder {
        let options = LoadOptions {
            allow_outside_files: allow_outside,
            ..LoadOptions::default()
        };
        SceneFolder::of(&dir.join("scene.gltf"), &options)
    }

    #[test]
    fn names_leading_out_of_the_folder_are_refused_unless_allowed() {
        let root = tempfile::tempdir().unwrap();
        let scene = root.path().join("scene");
        std::fs::create_dir_all(scene.join("textures")).unwrap();
        std::fs::write(root.path().join("secret.txt"), "top secret").unwrap();
        std::fs::write(scene.join("inside.bin"), [1, 2, 3]).unwrap();
        let secret = root.path().join("secret.txt");
        let confined = folder(&scene, false);
        let outside = [
            "../secret.txt".to_string(),
            "textures/../../secret.txt".to_string(),
            secret.display().to_string(),
            // Outside and missing: refused the same way, without looking.
            "../no-such-file".to_string(),
        ];
        for name in &outside {
            assert_eq!(
                confined.read(name, Length::Whole),
                Err(ReadError::Outside),
                "{name}"
            );
        }
        assert_eq!(
            confined.read("textures/../inside.bin", Length::Whole),
            Ok(vec![1, 2, 3])
        );
        let open = folder(&scene, true);
        assert_eq!(
            open.read("../secret.txt", Length::Whole).unwrap(),
            b"top secret"
        );
    }

    #[cfg(unix)]
    #[test]
    fn symbolic_links_out_of_the_folder_are_refused() {
        let root = tempfile::tempdir().unwrap();
        let scene = root.path().join("scene");
        std::fs::create_dir(&scene).unwrap();
        std::fs::write(root.path().join("secret.txt"), "top secret").unwrap();
        std::os::unix::fs::symlink(root.path().join("secret.txt"), scene.join("link.bin")).unwrap();
        std::os::unix::fs::symlink(root.path(), scene.join("up")).unwrap();
        let confined = folder(&scene, false);
        for name in ["link.bin", "up/secret.txt"] {
            assert_eq!(
                confined.read(name, Length::Whole),
                Err(ReadError::Outside),
                "{name}"
            );
        }
        // A link that stays inside is followed.
        std::fs::write(scene.join("data.bin"), [7]).unwrap();
        std::os::unix::fs::symlink(scene.join("data.bin"), scene.join("alias.bin")).unwrap();
        assert_eq!(confined.read("alias.bin", Length::Whole), Ok(vec![7]));
    }

    #[test]
    fn reads_stop_at_the_declared_length_and_shorter_files_are_errors() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("data.bin"), [1, 2, 3, 4, 5]).unwrap();
        let folder = folder(dir.path(), false);
        assert_eq!(
            folder.read("data.bin", Length::Declared(3)),
            Ok(vec![1, 2, 3])
        );
        // A declared length far beyond memory is refused before anything is reserved, and
        // the message does not say how long the file is.
        let Err(ReadError::Failed(message)) = folder.read("data.bin", Length::Declared(1 << 50))
        else {
            panic!("read a 5-byte file as 2^50 bytes");
        };
        assert!(
            message.contains("shorter than the 1125899906842624 bytes declared")
                && !message.contains("5 bytes"),
            "{message}"
        );
        let Err(ReadError::Failed(message)) = folder.read("missing.bin", Length::Whole) else {
            panic!("read a missing file");
        };
        assert!(message.contains("missing.bin"), "{message}");
    }

    #[test]
    fn folders_are_not_regular_files() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("sub.bin")).unwrap();
        let Err(ReadError::Failed(message)) =
            folder(dir.path(), false).read("sub.bin", Length::Whole)
        else {
            panic!("read a folder");
        };
        assert!(message.contains("not a regular file"), "{message}");
    }
}
