//! Crash and resume (issue 34): `optimize`, `gpu-sweep` and `campaign run` are killed with
//! SIGKILL at random instants, the first milliseconds included (before the folder's marker
//! is renamed into place, between a checkpoint's temporary file and its rename, mid-append
//! of a CSV row), several times in a row, and then finished the way a user would (the same
//! command again; `optimize` with `--resume` once its run.toml exists). The finished
//! folder must hold the same bytes as a run that was never interrupted: every file except
//! the lock, the marker (it carries a run id) and generations.csv's wall-clock column.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common;

const SMALL: &[&str] = &[
    "--pop",
    "8",
    "--generations",
    "3",
    "--particles",
    "30",
    "--final-particles",
    "30",
    "--replicates",
    "1",
    "--quiet",
];

/// The binary with `args`, from the repository root; stdout dropped, stderr kept for errors.
fn sawtooth(args: &[String]) -> Command {
    let mut c = common::sawtooth();
    c.args(args).stdout(Stdio::null()).stderr(Stdio::piped());
    c
}

fn finish(args: &[String]) -> Duration {
    let t = Instant::now();
    let o = sawtooth(args).output().unwrap();
    assert!(o.status.success(), "sawtooth {args:?}: {}", String::from_utf8_lossy(&o.stderr));
    t.elapsed()
}

/// Start `args` and SIGKILL it after `after` (or let it end first).
fn kill_after(args: &[String], after: Duration) {
    let mut child = sawtooth(args).stderr(Stdio::null()).spawn().unwrap();
    std::thread::sleep(after);
    let _ = child.kill();
    let _ = child.wait();
}

/// Every file under `dir` that a finished run must reproduce, by relative path.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                walk(root, &p, out);
                continue;
            }
            if name == ".sawtooth.lock" || name == ".sawtooth-run" {
                continue;
            }
            let mut bytes = std::fs::read(&p).unwrap();
            if name == "generations.csv" {
                // the last column is the wall clock of the process that ran the generation
                let text = String::from_utf8(bytes).unwrap();
                bytes = text
                    .lines()
                    .map(|l| l.rsplit_once(',').map_or(l, |(a, _)| a).to_string() + "\n")
                    .collect::<String>()
                    .into_bytes();
            }
            out.insert(p.strip_prefix(root).unwrap().to_path_buf(), bytes);
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Kill instants for one trial: early ones fixed (the first milliseconds are where the
/// folder is made and marked), the rest spread over the reference run's duration by a
/// seeded generator (the same instants on every run of the test).
fn instants(trial: u64, reference: Duration) -> Vec<Duration> {
    let mut x = 0x9E37_79B9_7F4A_7C15u64.wrapping_mul(trial + 1);
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let early = [0, 1, 2, 4, 8, 15, 25][trial as usize % 7];
    let span = reference.as_millis().max(1) as u64;
    vec![Duration::from_millis(early), Duration::from_millis(next() % span), Duration::from_millis(next() % span)]
}

/// Kill `run(dir)` at each instant of several trials; finish with `resume(dir)` and compare.
fn check(
    name: &str,
    trials: u64,
    prepare: impl Fn(&Path),
    run: impl Fn(&Path) -> Vec<String>,
    resume: impl Fn(&Path) -> Vec<String>,
) {
    let d = tempfile::tempdir().unwrap();
    let reference_dir = d.path().join("reference");
    prepare(&reference_dir);
    let reference_time = finish(&run(&reference_dir));
    let reference = contents(&reference_dir);
    assert!(reference.len() >= 4, "{name}: the reference run wrote {:?}", reference.keys());
    for trial in 0..trials {
        let dir = d.path().join(format!("trial{trial}"));
        prepare(&dir);
        let kills = instants(trial, reference_time);
        for &at in &kills {
            let args = if dir.join("run.toml").exists() { resume(&dir) } else { run(&dir) };
            kill_after(&args, at);
        }
        let args = if dir.join("run.toml").exists() { resume(&dir) } else { run(&dir) };
        finish(&args);
        let got = contents(&dir);
        assert_eq!(
            got.keys().collect::<Vec<_>>(),
            reference.keys().collect::<Vec<_>>(),
            "{name}: trial {trial} (kills at {kills:?}): other files"
        );
        for (path, bytes) in &reference {
            assert!(
                got[path] == *bytes,
                "{name}: trial {trial} (kills at {kills:?}): {} differs from the uninterrupted run's",
                path.display()
            );
        }
    }
    eprintln!("{name}: {trials} trials of 3 kills each (reference run {reference_time:?}) finished byte-identical");
}

fn strings(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

#[test]
fn optimize_killed_at_random_instants_finishes_byte_identical() {
    let run = |dir: &Path| {
        let mut a = strings(&["optimize", "--env", "earth", "--out", dir.to_str().unwrap()]);
        a.extend(strings(SMALL));
        a
    };
    let resume = |dir: &Path| strings(&["optimize", "--out", dir.to_str().unwrap(), "--resume", "--quiet"]);
    check("optimize", 7, |_| {}, run, resume);
}

#[test]
fn gpu_sweep_killed_at_random_instants_finishes_byte_identical() {
    let run = |dir: &Path| {
        let mut a = strings(&[
            "gpu-sweep",
            "--env",
            "lunar",
            "--alpha",
            "10..11",
            "--step",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ]);
        a.extend(strings(SMALL));
        a
    };
    // rerunning the same command resumes every member
    check("gpu-sweep", 5, |_| {}, run, run);
}

#[test]
fn campaign_run_killed_at_random_instants_finishes_byte_identical() {
    let plan = |dir: &Path| {
        let mut a = strings(&[
            "gpu-sweep",
            "--env",
            "lunar",
            "--alpha",
            "10..11",
            "--step",
            "1",
            "--plan",
            "--out",
            dir.to_str().unwrap(),
        ]);
        a.extend(strings(&SMALL[..SMALL.len() - 1]));
        finish(&a);
    };
    let run = |dir: &Path| strings(&["campaign", "run", dir.to_str().unwrap()]);
    // a campaign folder holds plan.json, not run.toml: the same command continues it
    check("campaign run", 5, plan, run, run);
}
