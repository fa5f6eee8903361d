//! Scratch files of the commands that write a scene (`bsa new`, `bsa plant`): they work
//! in dot-files beside the scene until it is complete, so that an error or a Ctrl-C
//! leaves the folder's `scene.json` and `target.png` as they were. [`Scratch`] removes
//! the dot-files however the command ends.

use std::path::{Path, PathBuf};

/// The scratch files of one command, removed when it ends, whether it wrote its scene,
/// failed or was interrupted; and the chess pieces it wrote beside the scene
/// (`pieces/`), removed unless the scene was written.
pub(super) struct Scratch {
    files: Vec<PathBuf>,
    pieces: PathBuf,
    /// The files `pieces/` held before, or `None` when it did not exist.
    pieces_before: Option<Vec<PathBuf>>,
    /// Set by [`Scratch::written`]: the pieces beside the scene stay.
    written: bool,
    /// The scene's folder, when this command created it: removed again if it is left
    /// empty without a scene (a refused `bsa new` leaves no empty folder behind).
    created: Option<PathBuf>,
}

impl Scratch {
    /// Scratch `files` in the scene's folder `dir`, which this command `created`.
    pub(super) fn new(files: Vec<PathBuf>, dir: &Path, created: bool) -> Scratch {
        let pieces = dir.join("pieces");
        let pieces_before = list(&pieces);
        Scratch {
            files,
            pieces,
            pieces_before,
            written: false,
            created: created.then(|| dir.to_path_buf()),
        }
    }

    /// The scene is written: remove the scratch files now and keep the pieces beside it.
    pub(super) fn written(mut self) {
        self.written = true;
    }
}

/// The entries of a folder, or `None` when it cannot be read.
fn list(dir: &Path) -> Option<Vec<PathBuf>> {
    let entries = std::fs::read_dir(dir).ok()?;
    Some(entries.filter_map(|e| e.ok().map(|e| e.path())).collect())
}

impl Drop for Scratch {
    fn drop(&mut self) {
        for file in &self.files {
            let _ = std::fs::remove_file(file);
        }
        if self.written {
            return;
        }
        let before = self.pieces_before.clone().unwrap_or_default();
        for piece in list(&self.pieces).unwrap_or_default() {
            if !before.contains(&piece) {
                let _ = std::fs::remove_file(piece);
            }
        }
        if self.pieces_before.is_none() {
            let _ = std::fs::remove_dir(&self.pieces);
        }
        if let Some(dir) = &self.created {
            // Removes only an empty folder.
            let _ = std::fs::remove_dir(dir);
        }
    }
}
