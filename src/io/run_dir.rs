//! Owned output folders. A command that writes into a folder first takes a lock on
//! `DIR/.sawtooth.lock` (`File::try_lock`: an OS file lock, released when the process exits,
//! however it exits), so two processes started into one `--out` cannot interleave their
//! writes; the second is refused at once with a message naming the folder.
//!
//! Only the project's own marker makes a folder the project's: `DIR/.sawtooth-run`, a TOML
//! file with its format, the kind of run, the command that made it, a run id and `wrote`,
//! the files the run wrote at the top of the folder. The run records a file there before it
//! writes it ([`RunDir`] registers the folder; `io::atomic` asks before every write), so a
//! kill between the two leaves a name without a file, never a file without its name. A
//! folder the run made inside its own carries a marker of its own ([`mark_subfolder`]). A
//! folder is the project's when everything in it is accounted for: the lock, the marker,
//! stale temporary files, files its marker lists, and folders that are marked or hold
//! nothing but such bookkeeping. Anything else (a user's `pareto.csv` beside a marker
//! written by hand or by an older sawtooth, a link to a folder elsewhere) makes the folder
//! someone else's: it is refused and nothing in it is touched, not even by a lock file,
//! as the folder is judged before the lock is taken (and judged again under it).
//!
//! Stale temporary files of the project's own killed atomic writes (`io::atomic`) are
//! removed as soon as the folder is owned, before it is judged, in its marked subfolders
//! too, so a kill in the first milliseconds (between the marker's temporary file and its
//! rename) never leaves a folder that neither a rerun nor a resume accepts.
//!
//! The lock is advisory and per folder: on a cluster it needs a shared filesystem whose
//! locks reach every node (NFSv4, Lustre, BeeGFS, GPFS do; NFSv3 needs lockd).

use std::fs::{File, OpenOptions, TryLockError};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{bail, Context as _};

use super::atomic::{clean_stale_temps, is_temp_name, set_before_write, write_atomic};

pub const LOCK_FILE: &str = ".sawtooth.lock";
pub const MARKER_FILE: &str = ".sawtooth-run";
/// The marker's format: 2 records what the run wrote. Older markers (the kind alone on a
/// line, or a table without `format`) record nothing and no longer make a folder the project's.
pub const MARKER_FORMAT: u32 = 2;
/// How deep owning a folder looks for stale temporary files in its marked subfolders (a
/// DEM check: its root, a design's campaign, a run).
const CLEAN_DEPTH: usize = 3;

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
    /// Where this process records the files it writes (exclusive holders only).
    registered: Option<PathBuf>,
}

impl Drop for RunDir {
    fn drop(&mut self) {
        if let Some(dir) = &self.registered {
            held().retain(|h| &h.dir != dir);
        }
    }
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
#[serde(deny_unknown_fields)]
pub struct Marker {
    /// [`MARKER_FORMAT`].
    pub format: u32,
    /// The kind of run (`optimize`, `campaign`, `fit`, `diagnose`, `dem`, ...).
    pub kind: String,
    /// The command line that made the folder (for people).
    #[serde(default)]
    pub command: String,
    /// Unique per folder: when, by which process.
    pub run_id: String,
    /// The files the run wrote at the top of its folder, sorted.
    #[serde(default)]
    pub wrote: Vec<String>,
}

impl Marker {
    fn new(kind: &str) -> Marker {
        let since_epoch = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        Marker {
            format: MARKER_FORMAT,
            kind: kind.to_string(),
            command: std::env::args().collect::<Vec<_>>().join(" "),
            run_id: format!("{}.{:09}-{}", since_epoch.as_secs(), since_epoch.subsec_nanos(), std::process::id()),
            wrote: Vec::new(),
        }
    }
}

/// What `DIR/.sawtooth-run` holds.
enum MarkerFile {
    Absent,
    /// A marker of this format.
    Current(Marker),
    /// Something else: an older sawtooth's marker, or not a marker at all.
    Other,
}

fn read_marker(dir: &Path) -> MarkerFile {
    let path = dir.join(MARKER_FILE);
    if std::fs::symlink_metadata(&path).is_err() {
        return MarkerFile::Absent;
    }
    // a link, a pipe or a huge file in the marker's place is not a marker
    if !std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file()) {
        return MarkerFile::Other;
    }
    match crate::io::bounded::read_text(&path, &crate::schema::MARKER_FILE_LIMIT) {
        Ok(text) => match toml::from_str::<Marker>(&text) {
            Ok(m) if m.format == MARKER_FORMAT && !m.kind.is_empty() && !m.run_id.is_empty() => MarkerFile::Current(m),
            _ => MarkerFile::Other,
        },
        Err(_) => MarkerFile::Other,
    }
}

/// `dir`'s marker, if it has one of this format.
pub fn marker_of(dir: &Path) -> Option<Marker> {
    match read_marker(dir) {
        MarkerFile::Current(m) => Some(m),
        _ => None,
    }
}

/// The kind recorded in `dir`'s marker, if any.
pub fn kind_of(dir: &Path) -> Option<String> {
    marker_of(dir).map(|m| m.kind)
}

/// True for the project's bookkeeping in any folder: the lock and stale temporary files.
fn is_bookkeeping(name: &str, entry: &std::fs::DirEntry) -> bool {
    name == LOCK_FILE || (is_temp_name(name) && entry.file_type().is_ok_and(|t| t.is_file()))
}

/// True when `dir` (not a link) holds nothing but the project's bookkeeping.
fn holds_only_bookkeeping(dir: &Path) -> bool {
    let Ok(entries) = std::fs::read_dir(dir) else { return false };
    entries.into_iter().all(|e| {
        e.is_ok_and(|e| {
            let name = e.file_name().to_string_lossy().into_owned();
            is_bookkeeping(&name, &e)
        })
    })
}

/// The entries of `dir` its marker does not account for (all but the bookkeeping where it
/// has none): a file it does not list, a link, a folder neither marked nor empty of all
/// but bookkeeping.
fn foreign_entries(dir: &Path, marker: Option<&Marker>) -> anyhow::Result<Vec<String>> {
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))? {
        let e = e.with_context(|| format!("listing {}", dir.display()))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name == MARKER_FILE || is_bookkeeping(&name, &e) {
            continue;
        }
        let ours = match marker {
            None => false,
            Some(m) => {
                // the entry itself, not what a link points at
                let t = e.file_type().with_context(|| format!("listing {}", dir.display()))?;
                if t.is_file() {
                    m.wrote.contains(&name)
                } else if t.is_dir() {
                    marker_of(&e.path()).is_some() || holds_only_bookkeeping(&e.path())
                } else {
                    false
                }
            }
        };
        if !ours {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

/// A few names for a message: `a, b, c, …`.
fn shown(names: &[String]) -> String {
    let mut s = names.iter().take(3).map(String::as_str).collect::<Vec<_>>().join(", ");
    if names.len() > 3 {
        s.push_str(", …");
    }
    s
}

/// Whether `dir` may be held for a run of `kind`: its marker when it has one, `None` when it
/// holds nothing but bookkeeping (a new folder); an error naming what is not the project's.
fn judge(dir: &Path, kind: &str, access: Access) -> anyhow::Result<Option<Marker>> {
    let marker = match read_marker(dir) {
        MarkerFile::Current(m) => {
            if m.kind != kind {
                bail!("{} holds a `{}` run, not a `{kind}` one; choose another folder", dir.display(), m.kind);
            }
            let foreign = foreign_entries(dir, Some(&m))?;
            if !foreign.is_empty() {
                bail!(
                    "{} is a `{kind}` folder of sawtooth's but holds what its runs did not write ({}); refusing to write into it: move them out, or choose another folder",
                    dir.display(),
                    shown(&foreign)
                );
            }
            Some(m)
        }
        other => {
            let foreign = foreign_entries(dir, None)?;
            if !foreign.is_empty() {
                let why = if matches!(other, MarkerFile::Other) {
                    format!(
                        "its {MARKER_FILE} is not a marker of this sawtooth (an older version's, or not one at all)"
                    )
                } else {
                    format!("no {MARKER_FILE}")
                };
                bail!(
                    "{} holds files ({}) but is not a folder of sawtooth's ({why}); refusing to write into it: choose an empty or new folder",
                    dir.display(),
                    shown(&foreign)
                );
            }
            None
        }
    };
    if marker.is_none() && access == Access::Shared {
        bail!("{} is not a `{kind}` folder (no {MARKER_FILE})", dir.display());
    }
    Ok(marker)
}

/// Folders this process holds exclusively, with their markers: where it records what it writes.
struct Held {
    dir: PathBuf,
    marker: Marker,
}

static HELD: Mutex<Vec<Held>> = Mutex::new(Vec::new());

fn held() -> std::sync::MutexGuard<'static, Vec<Held>> {
    // a panic elsewhere leaves the list as it was: still a list
    HELD.lock().unwrap_or_else(|e| e.into_inner())
}

/// `io::atomic`'s question before every write: a file about to be written at the top of a
/// folder this process holds is recorded in the folder's marker first.
fn record_before_write(path: &Path) -> anyhow::Result<()> {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else { return Ok(()) };
    if name == MARKER_FILE || name == LOCK_FILE || is_temp_name(name) {
        return Ok(());
    }
    let mut held = held();
    if held.is_empty() {
        return Ok(());
    }
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let Ok(parent) = std::fs::canonicalize(parent) else { return Ok(()) };
    let Some(h) = held.iter_mut().find(|h| h.dir == parent) else { return Ok(()) };
    if h.marker.wrote.iter().any(|w| w == name) {
        return Ok(());
    }
    let mut marker = h.marker.clone();
    marker.wrote.push(name.to_string());
    marker.wrote.sort();
    write_marker(&h.dir, &marker)?;
    h.marker = marker;
    Ok(())
}

/// Record an entry written at the top of a folder this process holds by other means than
/// `io::atomic` (a file appended to), before it is written.
pub fn record_write(path: &Path) -> anyhow::Result<()> {
    record_before_write(path)
}

fn write_marker(dir: &Path, marker: &Marker) -> anyhow::Result<()> {
    write_atomic(&dir.join(MARKER_FILE), toml::to_string(marker)?.as_bytes())
}

/// Create `dir` inside a folder the run holds, marked as the run's own (`kind` says what it
/// is), so that the folder above it counts it as the run's. Marking a folder already marked
/// leaves its marker; a folder there that the run did not make is refused.
pub fn mark_subfolder(dir: &Path, kind: &str) -> anyhow::Result<()> {
    if std::fs::symlink_metadata(dir).is_ok_and(|m| m.file_type().is_symlink()) {
        bail!("{} is a link to another folder; a run's folders lie inside its own folder", dir.display());
    }
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    match read_marker(dir) {
        MarkerFile::Current(_) => Ok(()),
        _ if holds_only_bookkeeping(dir) => write_marker(dir, &Marker::new(kind)),
        _ => bail!(
            "{} holds files but is not a folder of sawtooth's (no {MARKER_FILE} of this sawtooth); refusing to write into it",
            dir.display()
        ),
    }
}

/// The only writer of `dir`, a marked subfolder of a folder held shared by several
/// processes (a DEM campaign's run folder, written by one task of a job array): the lock is
/// held until the returned file is dropped, and a second process that would write the same
/// subfolder (a requeued task while the first still runs, two task loops meeting) is refused
/// by name instead of overwriting the first's files as they are written.
pub fn hold_subfolder(dir: &Path) -> anyhow::Result<File> {
    match try_lock(dir, Access::Exclusive)? {
        Some(lock) => Ok(lock),
        None => bail!(
            "{} is being written by another sawtooth process (it holds {}); this one leaves it to that process",
            dir.display(),
            dir.join(LOCK_FILE).display()
        ),
    }
}

/// Record in the marker of `dir` (a run's marked subfolder, [`mark_subfolder`]) the files
/// that the run writes at its top from outside it: a DEM check writes each design's campaign
/// files (plan, dem.csv, setup, law) while it holds the check's folder, not the design's, so
/// without this `dem compare` of a design would find them unaccounted for. Idempotent.
pub fn declare_writes(dir: &Path, names: &[&str]) -> anyhow::Result<()> {
    let MarkerFile::Current(mut marker) = read_marker(dir) else {
        bail!("{} is not a marked folder of sawtooth's (no {MARKER_FILE} of this sawtooth)", dir.display());
    };
    let before = marker.wrote.len();
    for name in names {
        if !marker.wrote.iter().any(|w| w == name) {
            marker.wrote.push(name.to_string());
        }
    }
    if marker.wrote.len() == before {
        return Ok(());
    }
    marker.wrote.sort();
    write_marker(dir, &marker)
}

/// Remove stale temporary files from `dir` and from its marked subfolders that no process
/// holds, `depth` levels down. Only while owning `dir` exclusively.
fn clean_tree(dir: &Path, depth: usize) -> anyhow::Result<()> {
    clean_stale_temps(dir)?;
    if depth == 0 {
        return Ok(());
    }
    for e in std::fs::read_dir(dir).with_context(|| format!("listing {}", dir.display()))?.flatten() {
        if e.file_type().is_ok_and(|t| t.is_dir()) && marker_of(&e.path()).is_some() && !is_held(&e.path()) {
            clean_tree(&e.path(), depth - 1)?;
        }
    }
    Ok(())
}

impl RunDir {
    /// Own `dir` for a run of `kind` (created if missing). A folder is the project's only by
    /// its marker, and only while everything in it is accounted for (module docs); it is
    /// judged before its lock file is created, so a refused folder is left as it was.
    pub fn acquire(dir: &Path, kind: &str, access: Access) -> anyhow::Result<RunDir> {
        let exists = std::fs::metadata(dir).is_ok_and(|m| m.is_dir());
        if exists {
            judge(dir, kind, access)?;
        } else if access == Access::Exclusive {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        } else {
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
            clean_tree(dir, CLEAN_DEPTH)?;
        }
        let marker = match judge(dir, kind, access)? {
            Some(m) => m,
            None => {
                let m = Marker::new(kind);
                write_marker(dir, &m)?;
                m
            }
        };
        let registered = match access {
            Access::Exclusive => {
                let canonical = std::fs::canonicalize(dir).with_context(|| format!("resolving {}", dir.display()))?;
                set_before_write(record_before_write);
                held().push(Held { dir: canonical.clone(), marker });
                Some(canonical)
            }
            Access::Shared => None,
        };
        Ok(RunDir { path: dir.to_path_buf(), _lock: lock, registered })
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

    /// A DEM campaign's run folder under a root that several tasks hold shared: the second
    /// task on the same run is refused while the first writes it (two task loops met on one
    /// member and overwrote each other's LIGGGHTS files before this).
    #[test]
    fn a_subfolder_has_one_writer_at_a_time() {
        let d = tempfile::tempdir().unwrap();
        let root = d.path().join("campaign");
        drop(RunDir::acquire(&root, "dem", Access::Exclusive).unwrap());
        let _tasks = (
            RunDir::acquire(&root, "dem", Access::Shared).unwrap(),
            RunDir::acquire(&root, "dem", Access::Shared).unwrap(),
        );
        let run = root.join("run-001");
        mark_subfolder(&run, "dem-run").unwrap();
        let first = hold_subfolder(&run).unwrap();
        let e = hold_subfolder(&run).unwrap_err().to_string();
        assert!(e.contains("being written by another sawtooth process"), "{e}");
        drop(first);
        drop(hold_subfolder(&run).unwrap());
        // the lock file is bookkeeping: the folder stays the campaign's own
        assert!(kind_of(&run).is_some());
        drop(_tasks);
        drop(RunDir::acquire(&root, "dem", Access::Exclusive).unwrap());
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
    fn the_marker_names_the_kind_the_command_a_run_id_and_what_the_run_wrote() {
        let d = tempfile::tempdir().unwrap();
        let owned = RunDir::acquire(d.path(), "fit", Access::Exclusive).unwrap();
        write_atomic(&d.path().join("fit.json"), b"{}").unwrap();
        write_atomic(&d.path().join("fit.json"), b"{}").unwrap();
        // a file deeper down is its own folder's business, not this marker's
        std::fs::create_dir(d.path().join("sub")).unwrap();
        write_atomic(&d.path().join("sub/x.csv"), b"x").unwrap();
        drop(owned);
        let m = marker_of(d.path()).unwrap();
        assert_eq!((m.format, m.kind.as_str()), (MARKER_FORMAT, "fit"));
        assert!(!m.command.is_empty() && !m.run_id.is_empty(), "{m:?}");
        assert_eq!(m.wrote, ["fit.json"]);
        // written after the folder was let go: not the run's
        write_atomic(&d.path().join("late.csv"), b"x").unwrap();
        assert_eq!(marker_of(d.path()).unwrap().wrote, ["fit.json"]);
        std::fs::remove_dir_all(d.path().join("sub")).unwrap();
        let e = RunDir::acquire(d.path(), "fit", Access::Exclusive).unwrap_err().to_string();
        assert!(e.contains("holds what its runs did not write (late.csv)"), "{e}");
    }

    /// Issue 45: a marker written by hand, or by an older sawtooth (the kind alone, or a table
    /// without `format`), records nothing and makes no folder the project's.
    #[test]
    fn old_and_forged_markers_make_no_folder_the_projects() {
        for forged in ["optimize\n", "kind = \"optimize\"\nrun_id = \"1\"\n", "format = 2\nkind = \"optimize\"\n"] {
            let d = tempfile::tempdir().unwrap();
            std::fs::write(d.path().join(MARKER_FILE), forged).unwrap();
            std::fs::write(d.path().join("pareto.csv"), "mine\n").unwrap();
            assert_eq!(kind_of(d.path()), None, "{forged}");
            let e = RunDir::acquire(d.path(), "optimize", Access::Exclusive).unwrap_err().to_string();
            assert!(e.contains("is not a marker of this sawtooth"), "{e}");
            assert_eq!(std::fs::read_to_string(d.path().join("pareto.csv")).unwrap(), "mine\n");
            assert!(!d.path().join(LOCK_FILE).exists(), "a refused folder got a lock file");
        }
    }

    /// Issue 45: a folder that is not the project's gets no lock file, through a link too.
    #[cfg(unix)]
    #[test]
    fn a_refused_folder_is_left_as_it_was() {
        let d = tempfile::tempdir().unwrap();
        let user = d.path().join("user");
        std::fs::create_dir(&user).unwrap();
        std::fs::write(user.join("notes.txt"), "mine").unwrap();
        let link = d.path().join("out");
        std::os::unix::fs::symlink(&user, &link).unwrap();
        for dir in [&user, &link] {
            assert!(RunDir::acquire(dir, "optimize", Access::Exclusive).is_err());
            assert!(RunDir::acquire(dir, "optimize", Access::Shared).is_err());
        }
        let left: Vec<_> = std::fs::read_dir(&user).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert_eq!(left, ["notes.txt"]);
    }

    /// A folder the run made inside its own counts by its own marker; a link to a folder
    /// elsewhere, or an unmarked folder with files, does not.
    #[cfg(unix)]
    #[test]
    fn subfolders_count_by_their_own_markers() {
        let d = tempfile::tempdir().unwrap();
        let root = d.path().join("root");
        drop(RunDir::acquire(&root, "dem", Access::Exclusive).unwrap());
        mark_subfolder(&root.join("run-001"), "dem-run").unwrap();
        std::fs::write(root.join("run-001/final.dump"), "x").unwrap();
        // killed before its marker: nothing but bookkeeping in it
        std::fs::create_dir(root.join("run-002")).unwrap();
        std::fs::write(root.join("run-002/..sawtooth-run.Ab12Cd.sawtooth-tmp"), "x").unwrap();
        drop(RunDir::acquire(&root, "dem", Access::Exclusive).unwrap());
        // and the run marks it when it comes back to it
        mark_subfolder(&root.join("run-002"), "dem-run").unwrap();
        assert!(marker_of(&root.join("run-002")).is_some());
        let elsewhere = d.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        std::os::unix::fs::symlink(&elsewhere, root.join("run-003")).unwrap();
        let e = RunDir::acquire(&root, "dem", Access::Exclusive).unwrap_err().to_string();
        assert!(e.contains("did not write (run-003)"), "{e}");
        assert!(mark_subfolder(&root.join("run-003"), "dem-run").unwrap_err().to_string().contains("is a link"));
        std::fs::remove_file(root.join("run-003")).unwrap();
        std::fs::create_dir(root.join("mine")).unwrap();
        std::fs::write(root.join("mine/notes.txt"), "x").unwrap();
        assert!(RunDir::acquire(&root, "dem", Access::Shared).unwrap_err().to_string().contains("(mine)"));
        assert!(mark_subfolder(&root.join("mine"), "dem-run").is_err());
    }

    /// Stale temporary files of a killed writer go when the folder is owned again, in the
    /// marked folders inside it too (a killed DEM check's `.sled.stl.*.sawtooth-tmp`).
    #[test]
    fn owning_a_folder_cleans_its_marked_subfolders() {
        let d = tempfile::tempdir().unwrap();
        drop(RunDir::acquire(d.path(), "dem-check", Access::Exclusive).unwrap());
        let run = d.path().join("A+C/run-001");
        mark_subfolder(&d.path().join("A+C"), "dem").unwrap();
        mark_subfolder(&run, "dem-run").unwrap();
        let stale = run.join(".sled.stl.Xy12Ab.sawtooth-tmp");
        std::fs::write(&stale, "torn").unwrap();
        drop(RunDir::acquire(d.path(), "dem-check", Access::Exclusive).unwrap());
        assert!(!stale.exists());
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
