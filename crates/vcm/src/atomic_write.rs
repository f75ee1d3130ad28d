//! Writing a file through a temporary file in the same folder that is then renamed over the
//! target, so an interrupted or failed write never leaves a broken file behind.

use std::path::{Path, PathBuf};

/// A temporary name beside `path` (same folder, so the rename is atomic) that keeps the
/// extension, for writers that choose the format from it: `out.png` → `.out.png.<pid>.tmp.png`.
pub fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let extension = path
        .extension()
        .map_or_else(String::new, |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!(".{name}.{}.tmp{extension}", std::process::id()))
}

/// Writes with `write` to a temporary file, then renames it over `path`; the temporary file is
/// removed when either step fails, and a failed rename is reported through `rename_failed`.
///
/// Only regular files are replaced: a `path` that names a device, a FIFO, a socket or a
/// folder is refused (through `rename_failed`, before anything is written), since a rename
/// would put a regular file in its place. A symbolic link is followed: the file it points to
/// is replaced, and the link stays.
pub fn write_atomically<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    rename_failed: impl FnOnce(std::io::Error) -> E,
) -> Result<(), E> {
    let target = match writable_target(path) {
        Ok(target) => target,
        Err(e) => return Err(rename_failed(e)),
    };
    let temporary = temporary_path(&target);
    if let Err(e) = write(&temporary) {
        let _ = std::fs::remove_file(&temporary);
        return Err(e);
    }
    std::fs::rename(&temporary, &target).map_err(|source| {
        let _ = std::fs::remove_file(&temporary);
        rename_failed(source)
    })
}

/// The file a write to `path` replaces: `path` itself, or the end of the links it leads
/// through; an error when that exists and is not a regular file.
pub fn writable_target(path: &Path) -> std::io::Result<PathBuf> {
    let target = match std::fs::symlink_metadata(path) {
        Ok(meta) if meta.file_type().is_symlink() => resolve_links(path)?,
        _ => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(meta) if !meta.is_file() => Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "it exists and is not a regular file (a device, FIFO, socket or folder); \
             outputs replace regular files only",
        )),
        _ => Ok(target),
    }
}

/// Follows the symbolic links from `path` to the path they end at (which need not exist).
fn resolve_links(path: &Path) -> std::io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    // As many links as the kernel follows before giving up (ELOOP).
    for _ in 0..40 {
        match std::fs::read_link(&current) {
            Ok(next) => {
                current = match current.parent() {
                    Some(folder) => folder.join(next),
                    None => next,
                };
            }
            Err(e) if e.kind() == std::io::ErrorKind::InvalidInput => return Ok(current),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(current),
            Err(e) => return Err(e),
        }
    }
    Err(std::io::Error::other("too many levels of symbolic links"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn failed_writes_leave_nothing_and_successful_ones_replace_the_target() {
        let dir = tempfile::tempdir().unwrap();
        let target = dir.path().join("report.csv");
        assert_eq!(
            temporary_path(&target).extension().unwrap(),
            "csv",
            "writers that pick the format from the extension still see it"
        );
        let failed = write_atomically(
            &target,
            |tmp| {
                std::fs::write(tmp, "partial").unwrap();
                Err("disk full")
            },
            |_| "rename",
        );
        assert_eq!(failed, Err("disk full"));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        write_atomically(&target, |tmp| std::fs::write(tmp, "done"), |e| e).unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "done");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn fifos_and_folders_are_refused_and_links_are_followed() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe.exr");
        let name = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: `name` is a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o600) }, 0);
        let write = |tmp: &Path| std::fs::write(tmp, "image");
        for target in [&fifo, &dir.path().to_path_buf()] {
            let error = write_atomically(target, write, |e| e).unwrap_err();
            assert!(error.to_string().contains("not a regular file"), "{error}");
        }
        let meta = std::fs::symlink_metadata(&fifo).unwrap();
        assert!(std::os::unix::fs::FileTypeExt::is_fifo(&meta.file_type()));
        // A link to a file: the file is replaced, the link stays a link.
        let real = dir.path().join("real.exr");
        std::fs::write(&real, "old").unwrap();
        let link = dir.path().join("link.exr");
        std::os::unix::fs::symlink("real.exr", &link).unwrap();
        write_atomically(&link, write, |e| e).unwrap();
        assert_eq!(std::fs::read_to_string(&real).unwrap(), "image");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        // A link to a FIFO is refused like the FIFO.
        let to_fifo = dir.path().join("to-fifo.exr");
        std::os::unix::fs::symlink(&fifo, &to_fifo).unwrap();
        assert!(write_atomically(&to_fifo, write, |e| e).is_err());
        let names = std::fs::read_dir(dir.path()).unwrap().count();
        assert_eq!(names, 4, "no temporary file is left");
    }
}
