//! Ballistic shadow art: find launch velocities for a set of objects so that, at one
//! instant of their flight, the shadows they cast from a point light onto a plane form
//! a target picture.
//!
//! Pipeline (see `docs/ARCHITECTURE.md`), one folder per stage, each importing only
//! from the ones before it: [`scene`] (validated input, on [`geometry`]'s shapes) ->
//! [`sim`] (exact free flight, first contacts, rapier after `t`, air drag) ->
//! [`shadow`] (exact shadow into a [`shadow::mask::Mask`]) -> [`energy`] (the paper's
//! ten terms) -> [`evaluate`] (one sample) -> [`optimize`] (stages of CMA-ES) ->
//! [`output`] (the result schema and files), [`budget`] (the error budget) and
//! [`compose`] (`bsa new`'s design search, over [`design`]); [`cli`] is the glue of the
//! `bsa` binary.
//!
//! The modules' docs are written for the developers and name private items (a stage's
//! constants, its helpers); `cargo doc --document-private-items` renders those links.

#![allow(rustdoc::private_intra_doc_links)]

pub mod budget;
pub mod cli;
pub mod compose;
pub mod design;
pub mod energy;
pub mod evaluate;
pub mod geometry;
pub mod linalg;
pub mod optimize;
pub mod output;
pub mod scene;
pub mod shadow;
pub mod sim;

/// Temporary files and folders of the unit tests, removed when a test passes and kept
/// when it fails (test code, so any layer may use it). Every test run left ~100 MB
/// in the temporary folder before the tests removed theirs.
#[cfg(test)]
pub(crate) mod test_temp {
    use std::path::{Path, PathBuf};

    /// A test's temporary file or folder, which derefs to its path. Dropped after the
    /// test passed it removes it; dropped while the test panics it keeps it and prints
    /// its path, so that what the failed test left can be looked at. Keep the guard for
    /// as long as the path is used.
    #[must_use = "dropping the guard removes the file or folder"]
    pub(crate) struct TempPath(PathBuf);

    /// `<temporary folder>/<prefix>-<process id>-<name>`: the process id keeps two test
    /// runs side by side apart, `name` the tests of one run.
    fn path_of(prefix: &str, name: &str) -> PathBuf {
        std::env::temp_dir().join(format!("{prefix}-{}-{name}", std::process::id()))
    }

    impl TempPath {
        /// A fresh, empty folder named after `prefix` and `name`.
        pub(crate) fn dir(prefix: &str, name: &str) -> TempPath {
            let d = path_of(prefix, name);
            let _ = std::fs::remove_dir_all(&d);
            std::fs::create_dir_all(&d).unwrap();
            TempPath(d)
        }

        /// A file named after `prefix` and `name`, holding `bytes`.
        pub(crate) fn file(prefix: &str, name: &str, bytes: impl AsRef<[u8]>) -> TempPath {
            let f = path_of(prefix, name);
            std::fs::write(&f, bytes).unwrap();
            TempPath(f)
        }
    }

    impl std::ops::Deref for TempPath {
        type Target = Path;
        fn deref(&self) -> &Path {
            &self.0
        }
    }

    impl AsRef<Path> for TempPath {
        fn as_ref(&self) -> &Path {
            &self.0
        }
    }

    impl Drop for TempPath {
        fn drop(&mut self) {
            if std::thread::panicking() {
                eprintln!("kept {} for the failed test", self.0.display());
            } else if self.0.is_dir() {
                let _ = std::fs::remove_dir_all(&self.0);
            } else {
                let _ = std::fs::remove_file(&self.0);
            }
        }
    }

    #[test]
    fn removed_after_a_pass_and_kept_after_a_failure() {
        let dir = TempPath::dir("bsa-guard", "passed");
        std::fs::write(dir.join("file"), "x").unwrap();
        let file = TempPath::file("bsa-guard", "passed.txt", "x");
        let (dir_path, file_path) = (dir.to_path_buf(), file.to_path_buf());
        drop((dir, file));
        assert!(!dir_path.exists() && !file_path.exists());

        let failed = std::thread::spawn(|| {
            let file = TempPath::file("bsa-guard", "failed.txt", "x");
            panic!("a failing test, on purpose: {}", file.display());
        })
        .join();
        let kept = path_of("bsa-guard", "failed.txt");
        assert!(failed.is_err() && kept.is_file());
        std::fs::remove_file(kept).unwrap();
    }
}
