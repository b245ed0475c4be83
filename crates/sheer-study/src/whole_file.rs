//! Files the study writes appear whole or not at all: each is written under a hidden name beside its
//! target and renamed into place when complete (a rename within one folder is atomic on POSIX file
//! systems), so Ctrl-C or a killed run never leaves a truncated CSV, Markdown page or chart under a
//! published name.

use std::path::{Path, PathBuf};

use crate::StudyError;

/// A hidden name beside `path` for its partial contents: `.NAME.part-PID.EXT`, ending in the target's
/// extension, from which plotters picks the image format.
pub(crate) fn partial_path(path: &Path) -> PathBuf {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let extension = path
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!(".{name}.part-{}{extension}", std::process::id()))
}

/// Renames the complete `partial` to `path`; on failure the partial file is removed.
pub(crate) fn rename_into_place(partial: &Path, path: &Path) -> Result<(), StudyError> {
    std::fs::rename(partial, path).map_err(|source| {
        let _ = std::fs::remove_file(partial);
        StudyError::Io {
            path: path.display().to_string(),
            source,
        }
    })
}

/// Writes `text` to `path` whole or not at all.
pub(crate) fn write(path: &Path, text: &str) -> Result<(), StudyError> {
    let partial = partial_path(path);
    std::fs::write(&partial, text).map_err(|source| {
        let _ = std::fs::remove_file(&partial);
        StudyError::Io {
            path: path.display().to_string(),
            source,
        }
    })?;
    rename_into_place(&partial, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_written_file_replaces_the_old_one_and_leaves_nothing_else() {
        let dir = std::env::temp_dir().join(format!("sheer-study-whole-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("table.csv");
        std::fs::write(&path, "old").unwrap();
        write(&path, "new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        assert!(partial_path(&path).to_string_lossy().ends_with(".csv"));
        let error = write(&dir.join("absent/table.csv"), "x")
            .unwrap_err()
            .to_string();
        assert!(error.contains("absent/table.csv"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
