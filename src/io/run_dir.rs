//! Owned output folders. A command that writes into a folder first takes a lock on
//! `DIR/.sawtooth.lock` (`File::try_lock`: an OS file lock, released when the process exits,
//! however it exits), so two processes started into one `--out` cannot interleave their
//! writes; the second is refused at once with a message naming the folder.
//!
//! Only the project's own marker makes a folder the project's: `DIR/.sawtooth-run`, a small
//! TOML file with the kind of run, the command that made it and a run id. A folder holding
//! anything else (a user's `run.toml`, `pareto.csv`, `fit.json`: names alone prove nothing)
//! is refused rather than written into. Stale temporary files of the project's own killed
//! atomic writes (`io::atomic`) are removed as soon as the folder is owned, before it is
//! judged, so a kill in the first milliseconds (between the marker's temporary file and its
//! rename) never leaves a folder that neither a rerun nor a resume accepts.
//!
//! The lock is advisory and per folder: on a cluster it needs a shared filesystem whose
//! locks reach every node (NFSv4, Lustre, BeeGFS, GPFS do; NFSv3 needs lockd).

use std::fs::{File, OpenOptions, TryLockError};
use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _};

use super::atomic::{clean_stale_temps, is_temp_name, write_atomic};

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

/// What a marker records.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Marker {
    /// The kind of run (`optimize`, `campaign`, `fit`, `diagnose`).
    pub kind: String,
    /// The command line that made the folder (for people).
    #[serde(default)]
    pub command: String,
    /// Unique per folder: when, by which process.
    #[serde(default)]
    pub run_id: String,
}

impl Marker {
    fn new(kind: &str) -> Marker {
        let since_epoch = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        Marker {
            kind: kind.to_string(),
            command: std::env::args().collect::<Vec<_>>().join(" "),
            run_id: format!("{}.{:09}-{}", since_epoch.as_secs(), since_epoch.subsec_nanos(), std::process::id()),
        }
    }
}

/// `dir`'s marker, if it has one that reads as one. Markers written before they held a TOML
/// table hold the kind alone on one line; they are the project's own too.
pub fn marker_of(dir: &Path) -> Option<Marker> {
    let path = dir.join(MARKER_FILE);
    // a marker is a few hundred bytes; anything larger is not one
    const MARKER_MAX: u64 = 64 * 1024;
    if std::fs::metadata(&path).ok()?.len() > MARKER_MAX {
        return None;
    }
    let text = std::fs::read_to_string(&path).ok()?;
    if let Ok(m) = toml::from_str::<Marker>(&text) {
        return Some(m);
    }
    let kind = text.trim();
    let one_word = !kind.is_empty() && kind.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
    one_word.then(|| Marker { kind: kind.to_string(), command: String::new(), run_id: String::new() })
}

/// The kind recorded in `dir`'s marker, if any.
pub fn kind_of(dir: &Path) -> Option<String> {
    marker_of(dir).map(|m| m.kind)
}

/// The files of `dir` that are not the project's own bookkeeping (its lock, and temporary
/// files of its atomic writes): what makes an unmarked folder someone else's.
fn foreign_entries(dir: &Path) -> anyhow::Result<Vec<String>> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let name = e.with_context(|| format!("listing {}", dir.display()))?.file_name().to_string_lossy().into_owned();
        if name != LOCK_FILE && !is_temp_name(&name) {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

impl RunDir {
    /// Own `dir` for a run of `kind` (created if missing). A folder is the project's only by
    /// its marker; an unmarked folder must hold nothing but the project's own bookkeeping.
    pub fn acquire(dir: &Path, kind: &str, access: Access) -> anyhow::Result<RunDir> {
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
        if access == Access::Exclusive {
            // owned now: what a killed writer left half-written is stale (the marker's own
            // temporary file among them)
            clean_stale_temps(dir)?;
        }
        match marker_of(dir) {
            Some(m) if m.kind == kind => {}
            Some(m) => bail!("{} holds a `{}` run, not a `{kind}` one; choose another folder", dir.display(), m.kind),
            None => {
                let foreign = foreign_entries(dir)?;
                if !foreign.is_empty() {
                    let mut shown = foreign.iter().take(3).map(String::as_str).collect::<Vec<_>>().join(", ");
                    if foreign.len() > 3 {
                        shown.push_str(", …");
                    }
                    bail!(
                        "{} holds files ({shown}) but is not a folder of sawtooth's (no {MARKER_FILE}); refusing to write into it: choose an empty or new folder",
                        dir.display()
                    );
                }
                if access == Access::Shared {
                    bail!("{} is not a `{kind}` folder (no {MARKER_FILE})", dir.display());
                }
                let marker = toml::to_string(&Marker::new(kind))?;
                write_atomic(&dir.join(MARKER_FILE), marker.as_bytes())?;
            }
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
        let first = RunDir::acquire(&dir, "optimize", Access::Exclusive).unwrap();
        assert!(is_held(&dir));
        let e = RunDir::acquire(&dir, "optimize", Access::Exclusive).unwrap_err().to_string();
        assert!(e.contains("in use by another sawtooth process"), "{e}");
        assert!(RunDir::acquire(&dir, "optimize", Access::Shared).is_err());
        drop(first);
        assert!(!is_held(&dir));
        let _a = RunDir::acquire(&dir, "optimize", Access::Shared).unwrap();
        let _b = RunDir::acquire(&dir, "optimize", Access::Shared).unwrap();
        assert!(RunDir::acquire(&dir, "optimize", Access::Exclusive).is_err());
    }

    #[test]
    fn foreign_and_other_kinds_of_folders_are_refused() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join("thesis.pdf"), b"x").unwrap();
        let e = RunDir::acquire(d.path(), "optimize", Access::Exclusive).unwrap_err().to_string();
        assert!(e.contains("holds files (thesis.pdf) but is not a folder of sawtooth's"), "{e}");
        std::fs::remove_file(d.path().join("thesis.pdf")).unwrap();
        drop(RunDir::acquire(d.path(), "optimize", Access::Exclusive).unwrap());
        let e = RunDir::acquire(d.path(), "campaign", Access::Exclusive).unwrap_err().to_string();
        assert!(e.contains("holds a `optimize` run"), "{e}");
    }

    /// Finding 1 of issue 34: a file's name is no proof of whose it is.
    #[test]
    fn a_users_files_named_like_a_runs_never_make_the_folder_the_projects() {
        for (kind, names) in [
            ("optimize", &["run.toml", "pareto.csv"][..]),
            ("fit", &["fit.json"][..]),
            ("diagnose", &["diagnosis.json"][..]),
            ("campaign", &["plan.json"][..]),
        ] {
            let d = tempfile::tempdir().unwrap();
            for n in names {
                std::fs::write(d.path().join(n), b"mine").unwrap();
            }
            let e = RunDir::acquire(d.path(), kind, Access::Exclusive).unwrap_err().to_string();
            assert!(e.contains("is not a folder of sawtooth's"), "{kind}: {e}");
            for n in names {
                assert_eq!(std::fs::read(d.path().join(n)).unwrap(), b"mine");
            }
        }
    }

    #[test]
    fn the_marker_names_the_kind_the_command_and_a_run_id_and_old_markers_still_count() {
        let d = tempfile::tempdir().unwrap();
        drop(RunDir::acquire(d.path(), "fit", Access::Exclusive).unwrap());
        let m = marker_of(d.path()).unwrap();
        assert_eq!(m.kind, "fit");
        assert!(!m.command.is_empty() && !m.run_id.is_empty(), "{m:?}");
        // the marker of an older sawtooth: the kind alone
        std::fs::write(d.path().join(MARKER_FILE), "optimize\n").unwrap();
        assert_eq!(kind_of(d.path()).as_deref(), Some("optimize"));
        std::fs::write(d.path().join(MARKER_FILE), "mine, not a marker\n").unwrap();
        assert_eq!(kind_of(d.path()), None);
    }

    /// Finding 2: killed between the marker's temporary file and its rename, the folder
    /// holds only the project's bookkeeping; a rerun owns it.
    #[test]
    fn a_folder_left_by_a_kill_before_its_marker_was_renamed_is_accepted() {
        let d = tempfile::tempdir().unwrap();
        std::fs::write(d.path().join(LOCK_FILE), b"").unwrap();
        std::fs::write(d.path().join("..sawtooth-run.Ab12Cd.sawtooth-tmp"), b"optim").unwrap();
        let _r = RunDir::acquire(d.path(), "optimize", Access::Exclusive).unwrap();
        assert!(!d.path().join("..sawtooth-run.Ab12Cd.sawtooth-tmp").exists());
        assert_eq!(kind_of(d.path()).as_deref(), Some("optimize"));
    }

    #[test]
    fn owning_a_folder_removes_stale_temporaries() {
        let d = tempfile::tempdir().unwrap();
        let _r = RunDir::acquire(d.path(), "optimize", Access::Exclusive).unwrap();
        drop(_r);
        std::fs::write(d.path().join(".checkpoint.json.abc123.sawtooth-tmp"), b"torn").unwrap();
        let _r = RunDir::acquire(d.path(), "optimize", Access::Exclusive).unwrap();
        assert!(!d.path().join(".checkpoint.json.abc123.sawtooth-tmp").exists());
    }
}
