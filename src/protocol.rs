//! The campaign protocol (issue 44): a campaign is a folder holding a plan of members, each
//! member run alone by one process (`campaign run DIR --task I`, a Slurm array task) or every
//! member here by one (`campaign run DIR`), then gathered into one summary (`campaign
//! gather`), with a status of its members (`campaign status`) and Slurm scripts of its
//! unfinished ones (`campaigns::slurm`). An optimisation campaign (`campaigns::plan`: members
//! are `optimize` runs) and a DEM check (`dem::check`: members are DEM runs) are two kinds of
//! one [`Campaign`]; a kind says what its members are and how they run, gather and report,
//! and the functions here do what every kind shares: the task's range and folder, the locks
//! (a task holds the campaign's folder shared, beside the other tasks; running every member
//! here or gathering holds it exclusively), the already-finished member, the status table.
//! Resuming is each kind's own: a member picks up from what its folder holds (a
//! checkpoint, a run's result), so the same command after a kill finishes it.
//!
//! A third kind (a DEM design of experiments) implements [`Campaign`] for its plan and adds
//! one arm where a folder's kind is told (`campaigns::open`).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::bail;

use crate::io::run_dir::{Access, RunDir};

/// Where a member stands.
#[derive(Debug, Clone, PartialEq)]
pub enum MemberState {
    Finished,
    /// A process holds its folder now.
    Running,
    /// Stopped (or pre-empted) with a checkpoint at this generation.
    Checkpoint(u64),
    /// Its folder exists but it has no result: running, or stopped (a kind that cannot tell).
    Started,
    NotStarted,
}

impl std::fmt::Display for MemberState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            MemberState::Finished => write!(f, "finished"),
            MemberState::Running => write!(f, "running"),
            MemberState::Checkpoint(g) => write!(f, "stopped at generation {g} (checkpoint)"),
            MemberState::Started => write!(f, "started (running, or stopped: run it again)"),
            MemberState::NotStarted => write!(f, "not started"),
        }
    }
}

/// How a run of members ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Ran {
    /// Finished now; what to say of it (`40 generations (stall), 12 front points`).
    Finished(String),
    /// Finished before: nothing was run.
    AlreadyFinished,
    /// Stopped by Ctrl-C or SIGTERM, its state saved: the same command continues it.
    Interrupted,
}

/// A kind of campaign: its plan, read from its folder or just made.
pub trait Campaign {
    /// The `io::run_dir` kind of the campaign's folder.
    fn kind(&self) -> &'static str;
    /// What the plan is called in messages (`plan`, `DEM check`).
    fn what(&self) -> &'static str;
    /// The command that made the plan (for people).
    fn command(&self) -> &str;
    /// How many members the plan holds.
    fn members(&self) -> usize;
    /// Member `i` as messages name it (`alpha  10.0`, `A+C seed 5`).
    fn label(&self, i: usize) -> String;
    /// Member `i`'s folder under `root`.
    fn member_dir(&self, root: &Path, i: usize) -> PathBuf;
    /// Where member `i` stands.
    fn state(&self, root: &Path, i: usize) -> MemberState;
    /// Run member `i` alone; `root` is held shared (the other members' tasks run beside it).
    fn run_member(&self, root: &Path, i: usize) -> anyhow::Result<Ran>;
    /// Run every unfinished member here and write the summary to `out` (what `gather` prints);
    /// `root` is held exclusively. `Ran::Interrupted` when stopped.
    fn run_all(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<Ran>;
    /// The summary's files from the finished members, and its table to `out`; refused, naming
    /// every unfinished member, while any is. `root` is held exclusively.
    fn gather(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<()>;
    /// The width of the label column of the status table.
    fn label_width(&self) -> usize {
        12
    }
    /// The status table's last line, from every member's state.
    fn tally(&self, states: &[MemberState]) -> String {
        let count = |f: fn(&MemberState) -> bool| states.iter().filter(|s| f(s)).count();
        format!(
            "finished {}, running {}, stopped {}, not started {}",
            count(|s| *s == MemberState::Finished),
            count(|s| *s == MemberState::Running),
            count(|s| matches!(s, MemberState::Checkpoint(_))),
            count(|s| matches!(s, MemberState::NotStarted | MemberState::Started))
        )
    }
}

/// `campaign run DIR --task I`: member `i` alone, `root` held shared; a member whose folder
/// is a link (to anywhere: a member lies inside its campaign) is refused before anything is
/// written.
pub fn run_task(c: &dyn Campaign, root: &Path, i: usize, out: &mut dyn Write) -> anyhow::Result<Ran> {
    let n = c.members();
    if i >= n {
        bail!("--task {i}: the {} in {} has {n} members (tasks 0..={})", c.what(), root.display(), n.saturating_sub(1));
    }
    let label = c.label(i);
    let dir = c.member_dir(root, i);
    if let Ok(target) = std::fs::read_link(&dir) {
        bail!(
            "member {i} ({label}): its folder {} is a link to {}; a member's folder lies inside its campaign: remove the link and run the task again",
            dir.display(),
            target.display()
        );
    }
    let _shared = RunDir::acquire(root, c.kind(), Access::Shared)?;
    let ran = c.run_member(root, i)?;
    match &ran {
        Ran::Finished(what) => writeln!(out, "member {i} ({label}) finished: {what}")?,
        Ran::AlreadyFinished => writeln!(out, "member {i} ({label}) is already finished")?,
        Ran::Interrupted => eprintln!("member {i} ({label}): run the same command again to continue it"),
    }
    Ok(ran)
}

/// `campaign run DIR`: every unfinished member here, `root` held exclusively, then the summary.
pub fn run_here(c: &dyn Campaign, root: &Path, out: &mut dyn Write) -> anyhow::Result<Ran> {
    let _owned = RunDir::acquire(root, c.kind(), Access::Exclusive)?;
    c.run_all(root, out)
}

/// `campaign gather DIR`: the summary from the finished members, `root` held exclusively.
pub fn gather(c: &dyn Campaign, root: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
    let _owned = RunDir::acquire(root, c.kind(), Access::Exclusive)?;
    c.gather(root, out)
}

/// `campaign status DIR`: each member's state and the tally. Takes no lock: it only looks.
pub fn status(c: &dyn Campaign, root: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
    writeln!(out, "{} ({}, {} members)", root.display(), c.command(), c.members())?;
    let width = c.label_width();
    let mut states = Vec::with_capacity(c.members());
    for i in 0..c.members() {
        let s = c.state(root, i);
        writeln!(out, "{i:>5}  {:<width$} {s}", c.label(i))?;
        states.push(s);
    }
    writeln!(out, "{}", c.tally(&states))?;
    Ok(())
}

/// The members not finished: what `campaign slurm --unfinished` submits again.
pub fn unfinished(c: &dyn Campaign, root: &Path) -> Vec<usize> {
    (0..c.members()).filter(|&i| c.state(root, i) != MemberState::Finished).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;

    /// A campaign of three members whose results are files `m-I/done`.
    struct Files {
        ran: RefCell<Vec<usize>>,
    }

    impl Campaign for Files {
        fn kind(&self) -> &'static str {
            "files"
        }
        fn what(&self) -> &'static str {
            "plan"
        }
        fn command(&self) -> &str {
            "test"
        }
        fn members(&self) -> usize {
            3
        }
        fn label(&self, i: usize) -> String {
            format!("m{i}")
        }
        fn member_dir(&self, root: &Path, i: usize) -> PathBuf {
            root.join(format!("m-{i}"))
        }
        fn state(&self, root: &Path, i: usize) -> MemberState {
            if self.member_dir(root, i).join("done").is_file() {
                MemberState::Finished
            } else {
                MemberState::NotStarted
            }
        }
        fn run_member(&self, root: &Path, i: usize) -> anyhow::Result<Ran> {
            if self.state(root, i) == MemberState::Finished {
                return Ok(Ran::AlreadyFinished);
            }
            crate::io::run_dir::mark_subfolder(&self.member_dir(root, i), "m")?;
            std::fs::write(self.member_dir(root, i).join("done"), "")?;
            self.ran.borrow_mut().push(i);
            Ok(Ran::Finished("done".into()))
        }
        fn run_all(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<Ran> {
            for i in 0..3 {
                self.run_member(root, i)?;
            }
            self.gather(root, out)?;
            Ok(Ran::Finished(String::new()))
        }
        fn gather(&self, root: &Path, out: &mut dyn Write) -> anyhow::Result<()> {
            let left = unfinished(self, root);
            anyhow::ensure!(left.is_empty(), "unfinished: {left:?}");
            writeln!(out, "all done")?;
            Ok(())
        }
    }

    #[test]
    fn a_task_runs_its_member_once_and_the_status_and_gather_follow() {
        let d = tempfile::tempdir().unwrap();
        let root = d.path();
        drop(RunDir::acquire(root, "files", Access::Exclusive).unwrap());
        let c = Files { ran: RefCell::new(Vec::new()) };
        let mut out = Vec::new();
        let e = run_task(&c, root, 3, &mut out).unwrap_err().to_string();
        assert!(e.contains("--task 3: the plan in") && e.contains("has 3 members (tasks 0..=2)"), "{e}");
        assert_eq!(run_task(&c, root, 1, &mut out).unwrap(), Ran::Finished("done".into()));
        assert_eq!(run_task(&c, root, 1, &mut out).unwrap(), Ran::AlreadyFinished);
        assert_eq!(*c.ran.borrow(), [1]);
        assert!(gather(&c, root, &mut out).unwrap_err().to_string().contains("unfinished: [0, 2]"));
        let mut table = Vec::new();
        status(&c, root, &mut table).unwrap();
        let table = String::from_utf8(table).unwrap();
        assert!(table.contains("    1  m1           finished\n"), "{table}");
        assert!(table.ends_with("finished 1, running 0, stopped 0, not started 2\n"), "{table}");
        run_here(&c, root, &mut out).unwrap();
        assert_eq!(*c.ran.borrow(), [1, 0, 2]);
        let said = String::from_utf8(out).unwrap();
        assert!(said.starts_with("member 1 (m1) finished: done\nmember 1 (m1) is already finished\n"), "{said}");
        assert!(said.ends_with("all done\n"), "{said}");
    }

    #[cfg(unix)]
    #[test]
    fn a_member_folder_linked_elsewhere_is_refused_before_anything_runs() {
        let d = tempfile::tempdir().unwrap();
        let root = d.path().join("root");
        drop(RunDir::acquire(&root, "files", Access::Exclusive).unwrap());
        let elsewhere = d.path().join("elsewhere");
        std::fs::create_dir(&elsewhere).unwrap();
        std::os::unix::fs::symlink(&elsewhere, root.join("m-0")).unwrap();
        let c = Files { ran: RefCell::new(Vec::new()) };
        let e = run_task(&c, &root, 0, &mut Vec::new()).unwrap_err().to_string();
        assert!(e.contains("member 0 (m0): its folder") && e.contains("is a link to"), "{e}");
        assert!(c.ran.borrow().is_empty() && std::fs::read_dir(&elsewhere).unwrap().next().is_none());
    }
}
