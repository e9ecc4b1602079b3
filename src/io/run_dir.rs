//! Owned output folders. A command that writes into a folder first takes a lock on
//! `DIR/.sawtooth.lock` (`File::try_lock`: an OS file lock, released when the process exits,
//! however it exits), so two processes started into one `--out` cannot interleave their
//! writes; the second is refused at once with a message naming the folder. The folder is
//! marked with `DIR/.sawtooth-run` (the kind of run it holds); a folder that holds files but
//! no run of this kind is refused rather than written into. Once owned, stale temporary
//! files of killed atomic writes are removed.
//!
//! The lock is advisory and per folder: on a cluster it needs a shared filesystem whose
//! locks reach every node (NFSv4, Lustre, BeeGFS, GPFS do; NFSv3 needs lockd).

use std::fs::{File, OpenOptions, TryLockError};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use super::atomic::{clean_stale_temps, write_atomic};

pub const LOCK_FILE: &str = ".sawtooth.lock";
pub const MARKER_FILE: &str = ".sawtooth-run";

/// How a folder is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Access {
    /// The only writer: creates and marks the folder, cleans stale temporaries.
    Exclusive,
    /// One of several readers (e.g. the tasks of a campaign under its root): the folder
    /// must already be marked; excludes exclusive holders only.
    Shared,
}

/// A held folder; the lock is released on drop (or when the process ends).
#[derive(Debug)]
pub struct RunDir {
    pub path: PathBuf,
    _lock: File,
}

/// Open the lock file of `dir` and try to take it; `Ok(None)` when another process holds it.
fn try_lock(dir: &Path, access: Access) -> anyhow::Result<Option<File>> {
    let path = dir.join(LOCK_FILE);
    let f = OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .with_context(|| format!("opening lock file {}", path.display()))?;
    let r = match access {
        Access::Exclusive => f.try_lock(),
        Access::Shared => f.try_lock_shared(),
    };
    match r {
        Ok(()) => Ok(Some(f)),
        Err(TryLockError::WouldBlock) => Ok(None),
        Err(TryLockError::Error(e)) => Err(e).with_context(|| format!("locking {}", path.display())),
    }
}

/// True when a process holds `dir`'s lock right now (a running task, say). Only looks.
pub fn is_held(dir: &Path) -> bool {
    if !dir.join(LOCK_FILE).exists() {
        return false;
    }
    matches!(try_lock(dir, Access::Exclusive), Ok(None))
}

/// The kind recorded in `dir`'s marker, if any.
pub fn kind_of(dir: &Path) -> Option<String> {
    std::fs::read_to_string(dir.join(MARKER_FILE)).ok().map(|s| s.trim().to_string())
}

impl RunDir {
    /// Own `dir` for a run of `kind` (created if missing). `legacy` says whether an
    /// unmarked, non-empty folder holds a run of this kind written before markers existed.
    pub fn acquire(dir: &Path, kind: &str, access: Access, legacy: impl Fn(&Path) -> bool) -> anyhow::Result<RunDir> {
        if access == Access::Exclusive {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        } else if !dir.is_dir() {
            bail!("{} does not exist", dir.display());
        }
        let Some(lock) = try_lock(dir, access)? else {
            bail!(
                "{} is in use by another sawtooth process (it holds {}); wait for it to finish or choose another folder",
                dir.display(),
                dir.join(LOCK_FILE).display()
            );
        };
        match kind_of(dir) {
            Some(k) if k == kind => {}
            Some(k) => bail!("{} holds a `{k}` run, not a `{kind}` one; choose another folder", dir.display()),
            None => {
                let others = std::fs::read_dir(dir)
                    .with_context(|| format!("listing {}", dir.display()))?
                    .filter_map(|e| e.ok())
                    .filter(|e| e.file_name() != LOCK_FILE)
                    .count();
                if others > 0 && !legacy(dir) {
                    bail!(
                        "{} holds files but no `{kind}` run of sawtooth (no {MARKER_FILE}); refusing to write into it: choose an empty or new folder",
                        dir.display()
                    );
                }
                if access == Access::Shared {
                    bail!("{} is not a `{kind}` folder (no {MARKER_FILE})", dir.display());
                }
                write_atomic(&dir.join(MARKER_FILE), format!("{kind}\n").as_bytes())?;
            }
        }
        if access == Access::Exclusive {
            clean_stale_temps(dir)?;
        }
        Ok(RunDir { path: dir.to_path_buf(), _lock: lock })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_owner_is_refused_until_the_first_lets_go() {
        let d = tempfile::tempdir().unwrap();
        let dir = d.path().join("run");
        let first = RunDir::acquire(&dir, "optimize", Access::Exclusive, |_| false).unwrap();
        assert!(is_held(&dir));
        let e = RunDir::acquire(&dir, "optimize", Access::Exclusive, |_| false).unwrap_err().to_string();
        assert!(e.contains("in use by another sawtooth process"), "{e}");
        assert!(RunDir::acquire(&dir, "optimize", Access::Shared, |_| false).is_err());
        drop(first);
        assert!(!is_held(&dir));
        let _a = RunDir::acquire(&dir, "optimize", Access::Shared, |_| false).unwrap();
        let _b = RunDir::acquire(&dir, "optimize", Access::Shared, |_| false).unwrap();
        assert!(RunDir::acquire(&dir, "optimize", Access::Exclusive, |_| false).is_err());
    }

    #[test]
    fn foreign_and_other_kinds_of_folders_are_refused() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("thesis.pdf"), b"x").unwrap();
        let e = RunDir::acquire(d.path(), "optimize", Access::Exclusive, |_| false).unwrap_err().to_string();
        assert!(e.contains("holds files but no `optimize` run"), "{e}");
        assert!(RunDir::acquire(d.path(), "optimize", Access::Exclusive, |p| p.join("thesis.pdf").exists()).is_ok());
        let e = RunDir::acquire(d.path(), "campaign", Access::Exclusive, |_| true).unwrap_err().to_string();
        assert!(e.contains("holds a `optimize` run"), "{e}");
    }

    #[test]
    fn owning_a_folder_removes_stale_temporaries() {
        let d = tempfile::tempdir().unwrap();
        let _r = RunDir::acquire(d.path(), "optimize", Access::Exclusive, |_| false).unwrap();
        drop(_r);
        std::fs::write(d.path().join(".checkpoint.json.abc123.sawtooth-tmp"), b"torn").unwrap();
        let _r = RunDir::acquire(d.path(), "optimize", Access::Exclusive, |_| false).unwrap();
        assert!(!d.path().join(".checkpoint.json.abc123.sawtooth-tmp").exists());
    }
}
