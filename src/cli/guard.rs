//! The output folder of `bsa solve`, guarded so that a good result is never lost:
//!
//! * a lock file (`.bsa-solve.lock`, holding the process id) stops a second solve into
//!   the same folder while one runs; a lock left by a process that no longer runs is
//!   taken over with a warning;
//! * before any work, the folder must accept a file and hold the free space the solve's
//!   files are estimated to need;
//! * a fresh solve into a folder that holds a complete `solution.json` first moves it
//!   (and its `convergence.csv`) aside to `solution.prev.json` (`convergence.prev.csv`);
//!   if the new solve does not complete (interrupted, or an error such as a full disk),
//!   the previous complete files are put back as `solution.json` and `convergence.csv`,
//!   and the unfinished ones kept as `solution.partial.json` and
//!   `convergence.partial.csv`, which `--resume` picks up. Only a `SIGKILL` leaves the
//!   unfinished solve in `solution.json`, with the previous one still whole in
//!   `solution.prev.json`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};

use crate::output::files;

/// The exit code of a solve that was interrupted before its last stage completed (the
/// shell's code for a process ended by `SIGINT`).
pub const EXIT_INTERRUPTED: i32 = 130;

const LOCK: &str = ".bsa-solve.lock";
const SOLUTION: &str = "solution.json";
const CONVERGENCE: &str = "convergence.csv";
const PREV_SOLUTION: &str = "solution.prev.json";
const PREV_CONVERGENCE: &str = "convergence.prev.csv";
const PARTIAL_SOLUTION: &str = "solution.partial.json";
const PARTIAL_CONVERGENCE: &str = "convergence.partial.csv";

/// A solve that stopped before its last stage: what was saved and how to go on. `main`
/// turns it into [`EXIT_INTERRUPTED`].
#[derive(Debug, thiserror::Error)]
#[error("interrupted after {done} of {total} stages; {saved}; resume with `bsa solve {scene} --out {out} --resume`")]
pub struct Interrupted {
    pub done: usize,
    pub total: usize,
    pub saved: String,
    pub scene: String,
    pub out: String,
}

/// A command that was interrupted before it wrote anything (`bsa new`): the folder holds
/// what it held before. `main` turns it into [`EXIT_INTERRUPTED`].
#[derive(Debug, thiserror::Error)]
#[error("interrupted: no scene written; {dir} holds what it held before")]
pub struct NothingWritten {
    pub dir: String,
}

/// Whether `err` is an interruption ([`Interrupted`] or [`NothingWritten`]), which exits
/// with [`EXIT_INTERRUPTED`].
pub fn is_interruption(err: &anyhow::Error) -> bool {
    err.downcast_ref::<Interrupted>().is_some() || err.downcast_ref::<NothingWritten>().is_some()
}

/// Holds the lock on an output folder for the duration of a solve.
pub struct OutputGuard {
    dir: PathBuf,
    lock: PathBuf,
    /// True when this solve moved a complete solution aside and must put it back unless
    /// it completes.
    moved_previous: bool,
}

impl OutputGuard {
    /// Create the folder, take its lock, check that it is writable and has `needed`
    /// bytes free, and set the previous solution aside (see the module's notes).
    pub fn acquire(dir: &Path, resume: bool, needed: u64) -> Result<OutputGuard> {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create the output folder {}", dir.display()))?;
        let lock = dir.join(LOCK);
        take_lock(&lock)?;
        let mut guard = OutputGuard {
            dir: dir.to_path_buf(),
            lock,
            moved_previous: false,
        };
        preflight(dir, needed)?;
        guard.set_previous_aside(resume)?;
        Ok(guard)
    }

    /// True when a complete solution was set aside and will be put back unless this
    /// solve completes.
    pub fn has_previous(&self) -> bool {
        self.moved_previous
    }

    fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    fn set_previous_aside(&mut self, resume: bool) -> Result<()> {
        let partial = self.path(PARTIAL_SOLUTION);
        if !resume {
            // A fresh solve replaces any unfinished one, so that a later --resume does
            // not pick up a stale file.
            let _ = std::fs::remove_file(&partial);
            let _ = std::fs::remove_file(self.path(PARTIAL_CONVERGENCE));
        }
        if !is_complete(&self.path(SOLUTION)) && is_complete(&self.path(PREV_SOLUTION)) {
            // A solve killed outright (SIGKILL) left the previous complete solution
            // aside: it is still the one to put back unless this solve completes.
            self.moved_previous = true;
            return Ok(());
        }
        if resume && !partial.exists() {
            // Resuming what is in solution.json: nothing to set aside.
            return Ok(());
        }
        if is_complete(&self.path(SOLUTION)) {
            self.rename(SOLUTION, PREV_SOLUTION)?;
            self.rename_if_exists(CONVERGENCE, PREV_CONVERGENCE)?;
            self.moved_previous = true;
        }
        if resume {
            // The unfinished solve becomes the current one again.
            self.rename(PARTIAL_SOLUTION, SOLUTION)?;
            self.rename_if_exists(PARTIAL_CONVERGENCE, CONVERGENCE)?;
        }
        Ok(())
    }

    fn rename(&self, from: &str, to: &str) -> Result<()> {
        std::fs::rename(self.path(from), self.path(to)).with_context(|| {
            format!(
                "cannot rename {} to {}",
                self.path(from).display(),
                self.path(to).display()
            )
        })
    }

    fn rename_if_exists(&self, from: &str, to: &str) -> Result<()> {
        if self.path(from).exists() {
            self.rename(from, to)
        } else {
            // A stale file of the other name would pair the wrong table with the
            // solution.
            let _ = std::fs::remove_file(self.path(to));
            Ok(())
        }
    }

    /// The solve did not complete: put the previous complete solution back (if this solve
    /// set one aside) and keep the unfinished one beside it. Returns a sentence saying
    /// where each is.
    pub fn keep_previous(&self) -> String {
        if !self.moved_previous {
            // A solve that failed before its first stage wrote nothing to point at.
            if !self.path(SOLUTION).is_file() {
                return "no solution was written".to_string();
            }
            return format!("the best so far is in {}", self.path(SOLUTION).display());
        }
        let moved = self
            .rename_if_exists(SOLUTION, PARTIAL_SOLUTION)
            .and_then(|_| self.rename_if_exists(CONVERGENCE, PARTIAL_CONVERGENCE))
            .and_then(|_| self.rename(PREV_SOLUTION, SOLUTION))
            .and_then(|_| self.rename_if_exists(PREV_CONVERGENCE, CONVERGENCE));
        match moved {
            Ok(()) => format!(
                "the previous complete solution is kept in {}, the unfinished one in {}",
                self.path(SOLUTION).display(),
                self.path(PARTIAL_SOLUTION).display()
            ),
            Err(e) => format!(
                "the previous complete solution is in {} ({e:#})",
                self.path(PREV_SOLUTION).display()
            ),
        }
    }
}

impl Drop for OutputGuard {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.lock);
    }
}

/// A solution file that parses and has run all its stages.
fn is_complete(path: &Path) -> bool {
    path.exists() && files::read_solution(path).is_ok_and(|s| s.stages_completed >= s.stages_total)
}

/// Create the lock file, or explain who holds it.
fn take_lock(lock: &Path) -> Result<()> {
    use std::io::Write;
    for _ in 0..2 {
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(lock)
        {
            Ok(mut f) => {
                let _ = writeln!(f, "{}", std::process::id());
                return Ok(());
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                let pid = std::fs::read_to_string(lock)
                    .ok()
                    .and_then(|s| s.trim().parse::<u32>().ok());
                match pid {
                    Some(pid) if process_alive(pid) => bail!(
                        "another `bsa solve` (process {pid}) is writing to {}; wait for it to end, or delete {} if it is not running",
                        lock.parent().unwrap_or(lock).display(),
                        lock.display()
                    ),
                    _ => {
                        eprintln!(
                            "warning: taking over the lock {} left by a solve that no longer runs",
                            lock.display()
                        );
                        let _ = std::fs::remove_file(lock);
                    }
                }
            }
            Err(e) => {
                return Err(e).with_context(|| {
                    format!(
                        "the output folder {} is not writable",
                        lock.parent().unwrap_or(lock).display()
                    )
                })
            }
        }
    }
    bail!("cannot take the lock {}", lock.display())
}

/// Whether a process with this id runs (Linux's `/proc`; elsewhere a lock is assumed
/// held).
fn process_alive(pid: u32) -> bool {
    if cfg!(target_os = "linux") {
        Path::new(&format!("/proc/{pid}")).exists()
    } else {
        true
    }
}

/// The folder takes a file, and has room for `needed` bytes.
fn preflight(dir: &Path, needed: u64) -> Result<()> {
    let probe = dir.join(format!(".bsa-write-test{}", std::process::id()));
    let written = std::fs::write(&probe, b"bsa");
    let _ = std::fs::remove_file(&probe);
    written.with_context(|| format!("the output folder {} is not writable", dir.display()))?;
    if let Some(free) = free_bytes(dir) {
        if free < needed {
            bail!(
                "the output folder {} has {} free, and this solve needs about {}; free some space or choose another --out",
                dir.display(),
                human(free),
                human(needed)
            );
        }
    }
    Ok(())
}

/// Bytes available to this user on the file system of `dir` (`statvfs`).
fn free_bytes(dir: &Path) -> Option<u64> {
    use std::os::unix::ffi::OsStrExt;
    let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).ok()?;
    let mut st: libc::statvfs = unsafe { std::mem::zeroed() };
    // SAFETY: `c` is a valid NUL-terminated path and `st` a writable statvfs.
    let rc = unsafe { libc::statvfs(c.as_ptr(), &mut st) };
    (rc == 0).then(|| st.f_bavail as u64 * st.f_frsize as u64)
}

fn human(bytes: u64) -> String {
    format!("{:.1} MB", bytes as f64 / 1e6)
}

/// The bytes a solve's files are expected to take: solution, convergence table and
/// plot, pictures (four RGBA images of the target's size, before compression), and the
/// exports (a pose per key and body, twice: glTF and CSV), with room to spare for the
/// temporary copies. The convergence table grows with the samples and is not foreseen;
/// a disk that fills during the solve is handled by putting the previous solution back.
pub fn estimated_bytes(keys: f64, bodies: usize, pixels: usize) -> u64 {
    let exports = keys * bodies as f64 * 400.0;
    let pictures = pixels as f64 * 4.0 * 4.0;
    (4e6 + 2.0 * exports + pictures) as u64
}
