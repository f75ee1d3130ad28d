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
pub fn write_atomically<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    rename_failed: impl FnOnce(std::io::Error) -> E,
) -> Result<(), E> {
    let temporary = temporary_path(path);
    if let Err(e) = write(&temporary) {
        let _ = std::fs::remove_file(&temporary);
        return Err(e);
    }
    std::fs::rename(&temporary, path).map_err(|source| {
        let _ = std::fs::remove_file(&temporary);
        rename_failed(source)
    })
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
}
