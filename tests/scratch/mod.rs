//! A test's folder of scratch files: removed when the test passes, kept (its path printed) when it
//! fails, so that a failure can be looked at and a passing run leaves nothing behind.

use std::path::{Path, PathBuf};

/// A fresh, empty folder under the system's temporary folder, named for the test and the process;
/// it dereferences to its path.
pub struct Scratch(PathBuf);

impl Scratch {
    /// `sheer-{name}-{process id}`, emptied if an earlier run left it.
    pub fn new(name: &str) -> Scratch {
        let dir = std::env::temp_dir().join(format!("sheer-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if std::thread::panicking() {
            eprintln!("kept {} for the failed test", self.0.display());
        } else {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
