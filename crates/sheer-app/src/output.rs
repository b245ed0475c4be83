//! Everything the command line writes goes through here: files appear whole or not at all, sequences
//! do not mix with an earlier run's frames, and Ctrl-C ends a run between two frames, saying how far it
//! got.
//!
//! * [`write_file`]: written under a hidden temporary name beside the target and renamed into place
//!   when complete ([`sheer_slab::render::write_file_atomically`]), so an interrupted or killed run
//!   never leaves a truncated file under a frame's name.
//! * [`FrameNames`] and [`prepare_sequence_folder`]: `frame_0000.obj` …, padded to the width of the
//!   last frame's number (at least four digits), so that names sort in frame order; a folder that
//!   already holds frames is refused unless the user passes `--overwrite`, which removes them first.
//! * [`interrupt`]: the first Ctrl-C asks the running sequence to stop after the frame it is writing;
//!   a second one ends the process at once (a partial file can then remain only under its hidden
//!   temporary name).

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, LazyLock};

use crate::CliError;

/// Writes `bytes` to `path` whole or not at all; the error names the file.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    sheer_slab::render::write_file_atomically(path, bytes)
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))
}

/// Creates the output folder `dir` (and its parents) and checks that a file can be written in it,
/// before any work (a render of an hour of flag found out only at its first frame). A file already
/// there is named as such: the system's own message for it, "File exists", reads as if the folder were
/// the problem.
pub fn create_output_dir(dir: &Path) -> Result<(), CliError> {
    if dir.exists() && !dir.is_dir() {
        return Err(CliError::new(format!(
            "cannot use {} as the output folder: it is a file",
            dir.display()
        )));
    }
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::new(format!("cannot create {}: {e}", dir.display())))?;
    let probe = dir.join(format!(".sheer-write-check-{}", std::process::id()));
    std::fs::write(&probe, b"")
        .and_then(|()| std::fs::remove_file(&probe))
        .map_err(|e| CliError::new(format!("cannot write into {}: {e}", dir.display())))
}

/// Checks, before any work, that the file `path` can be written: a file there opens for writing (and
/// is left as it is), or one can be created there (and is removed again); a folder there is refused.
pub fn check_output_file(path: &Path) -> Result<(), CliError> {
    let refused =
        |e: std::io::Error| CliError::new(format!("cannot write {}: {e}", path.display()));
    if path.is_dir() {
        return Err(CliError::new(format!(
            "cannot write {}: it is a folder",
            path.display()
        )));
    }
    if path.exists() {
        // Not truncated: `/dev/stdout` or a file that a failed run should not empty.
        return std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .map(drop)
            .map_err(refused);
    }
    let folder = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    if !folder.is_dir() {
        return Err(CliError::new(format!(
            "cannot write {}: there is no folder {}",
            path.display(),
            folder.display()
        )));
    }
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .and_then(|_| std::fs::remove_file(path))
        .map_err(refused)
}

/// The file names of a sequence of frames: `frame_` and the frame number, zero-padded to the width of
/// the last frame's number (at least four digits), then one of the sequence's extensions.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FrameNames {
    width: usize,
    extensions: Vec<&'static str>,
}

/// The prefix of every frame's file name.
const FRAME_PREFIX: &str = "frame_";

impl FrameNames {
    /// Names for frames `0..frames`, each written with every extension in `extensions` (no dot).
    pub fn new(frames: u32, extensions: &[&'static str]) -> FrameNames {
        let last = frames.saturating_sub(1);
        FrameNames {
            width: last.to_string().len().max(4),
            extensions: extensions.to_vec(),
        }
    }

    /// `frame_0012.png` for frame 12 and extension `png`.
    pub fn name(&self, frame: u32, extension: &str) -> String {
        format!(
            "{FRAME_PREFIX}{frame:0width$}.{extension}",
            width = self.width
        )
    }

    /// Whether `name` is a frame of this kind (`frame_`, digits, one of the extensions), whatever its
    /// padding: an earlier run's frames of any length.
    fn matches(&self, name: &str) -> bool {
        let Some((stem, extension)) = name.rsplit_once('.') else {
            return false;
        };
        let Some(digits) = stem.strip_prefix(FRAME_PREFIX) else {
            return false;
        };
        !digits.is_empty()
            && digits.bytes().all(|b| b.is_ascii_digit())
            && self.extensions.contains(&extension)
    }

    /// Whether `name` is a partial file of a frame left by a killed run (`.frame_0001.obj.part-PID`).
    fn matches_partial(&self, name: &str) -> bool {
        name.strip_prefix('.')
            .and_then(|rest| rest.rsplit_once(".part-"))
            .is_some_and(|(frame, pid)| {
                self.matches(frame) && pid.bytes().all(|b| b.is_ascii_digit())
            })
    }
}

/// Prepares `dir` for a sequence named by `names`: creates it and checks it can be written; refuses it
/// when it already holds frames of that kind (an earlier run's frames would sit beside the new ones,
/// indistinguishable), unless `overwrite`, which removes those frames, and partial files a killed run
/// left, first. Files of any other name are never touched.
pub fn prepare_sequence_folder(
    dir: &Path,
    names: &FrameNames,
    overwrite: bool,
) -> Result<(), CliError> {
    create_output_dir(dir)?;
    let entries = std::fs::read_dir(dir)
        .map_err(|e| CliError::new(format!("cannot read {}: {e}", dir.display())))?;
    let mut frames: Vec<PathBuf> = Vec::new();
    for entry in entries {
        let entry =
            entry.map_err(|e| CliError::new(format!("cannot read {}: {e}", dir.display())))?;
        let name = entry.file_name();
        let Some(name) = name.to_str() else { continue };
        if names.matches(name) || (overwrite && names.matches_partial(name)) {
            frames.push(entry.path());
        }
    }
    if frames.is_empty() {
        return Ok(());
    }
    if !overwrite {
        frames.sort();
        let first = frames[0].file_name().unwrap_or_default().to_string_lossy();
        return Err(CliError::new(format!(
            "{} already holds {} frame file(s) ({first} …): they would mix with this run's; choose \
             another folder, or pass --overwrite to remove them first",
            dir.display(),
            frames.len()
        )));
    }
    for frame in &frames {
        std::fs::remove_file(frame)
            .map_err(|e| CliError::new(format!("cannot remove {}: {e}", frame.display())))?;
    }
    Ok(())
}

/// Ctrl-C (SIGINT) during a run: a flag that the first press sets; a second press ends the process
/// with status 130 at once.
pub mod interrupt {
    use super::*;

    /// Set by the first Ctrl-C; shared as an `Arc` with libraries that poll a flag of their own
    /// (`sheer_study::Monitor`).
    static REQUESTED: LazyLock<Arc<AtomicBool>> =
        LazyLock::new(|| Arc::new(AtomicBool::new(false)));

    /// Installs the handler (once per process; later calls do nothing). Until it is installed, Ctrl-C
    /// keeps its default behaviour, ending the process.
    pub fn install() {
        static INSTALLED: std::sync::Once = std::sync::Once::new();
        INSTALLED.call_once(|| {
            // If another part of the process owns SIGINT already, Ctrl-C keeps ending the process,
            // and the files written so far are still whole.
            let _ = ctrlc::set_handler(|| {
                if REQUESTED.swap(true, Ordering::SeqCst) {
                    // _exit, not exit: no atexit handlers run while the main thread may be inside the
                    // GPU driver; the partial file, if any, is hidden and nothing else needs cleaning.
                    // SAFETY: _exit takes no pointers and never returns.
                    #[allow(unsafe_code)]
                    unsafe {
                        libc::_exit(130)
                    };
                }
            });
        });
    }

    /// Whether Ctrl-C was pressed since the handler was installed.
    pub fn requested() -> bool {
        REQUESTED.load(Ordering::SeqCst)
    }

    /// The flag the first Ctrl-C sets.
    pub fn flag() -> Arc<AtomicBool> {
        Arc::clone(&REQUESTED)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("sheer-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn frame_names_are_padded_to_the_last_frames_width() {
        let names = FrameNames::new(60, &["obj"]);
        assert_eq!(names.name(7, "obj"), "frame_0007.obj");
        let long = FrameNames::new(12_001, &["png"]);
        assert_eq!(long.name(7, "png"), "frame_00007.png");
        assert_eq!(long.name(12_000, "png"), "frame_12000.png");
        // Names sort in frame order.
        let mut sorted: Vec<String> = [9_999, 10_000, 2].map(|f| long.name(f, "png")).to_vec();
        sorted.sort();
        assert_eq!(
            sorted,
            ["frame_00002.png", "frame_09999.png", "frame_10000.png"]
        );
        assert_eq!(
            FrameNames::new(1, &["obj"]).name(0, "obj"),
            "frame_0000.obj"
        );
    }

    #[test]
    fn a_folder_with_frames_is_refused_unless_overwritten() {
        let dir = scratch("refuse");
        let names = FrameNames::new(5, &["obj"]);
        prepare_sequence_folder(&dir, &names, false).unwrap();
        for frame in 0..20 {
            std::fs::write(
                dir.join(FrameNames::new(20, &["obj"]).name(frame, "obj")),
                "v",
            )
            .unwrap();
        }
        std::fs::write(dir.join(".frame_0003.obj.part-77"), "v 1").unwrap();
        std::fs::write(dir.join("notes.txt"), "mine").unwrap();
        std::fs::write(dir.join("frame_0001.png"), "another kind").unwrap();
        let error = prepare_sequence_folder(&dir, &names, false)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("already holds 20 frame file(s)") && error.contains("--overwrite"),
            "{error}"
        );
        assert!(
            dir.join("frame_0019.obj").exists(),
            "a refusal removes nothing"
        );
        prepare_sequence_folder(&dir, &names, true).unwrap();
        let mut left: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().into_string().unwrap())
            .collect();
        left.sort();
        assert_eq!(left, ["frame_0001.png", "notes.txt"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_written_file_replaces_the_old_one_whole_and_leaves_no_partial_file() {
        let dir = scratch("atomic");
        let path = dir.join("frame_0000.obj");
        std::fs::write(&path, "old").unwrap();
        write_file(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert_eq!(names.len(), 1);
        // Through a link, the file it names is replaced and the link stays a link.
        let link = dir.join("link.obj");
        std::os::unix::fs::symlink(&path, &link).unwrap();
        write_file(&link, b"newer").unwrap();
        assert!(link.is_symlink());
        assert_eq!(std::fs::read(&path).unwrap(), b"newer");
        // A folder that cannot take the file: an error naming it, and nothing left behind.
        let error = write_file(&dir.join("missing/frame.obj"), b"x")
            .unwrap_err()
            .to_string();
        assert!(error.contains("missing/frame.obj"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
