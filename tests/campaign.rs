//! Campaigns without a scheduler: a plan written by `gpu-sweep --plan` / `study … --plan`,
//! its members run one process each (`campaign run --task I`, as Slurm array tasks do),
//! gives the same bytes as the one-process command; gather refuses partial campaigns; owned
//! folders refuse a second writer; SIGTERM (Slurm's cancel) saves a checkpoint that the
//! next task resumes from. The real-Slurm test is tests/campaign_slurm.rs.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common;
use common::{fresh_dir, run, sawtooth};

const GA: &[&str] = &[
    "--pop",
    "16",
    "--generations",
    "6",
    "--algorithm",
    "nsga2",
    "--particles",
    "40",
    "--final-particles",
    "60",
    "--replicates",
    "2",
    "--quiet",
];

fn with_ga<'a>(args: &[&'a str]) -> Vec<&'a str> {
    let mut v = args.to_vec();
    v.extend_from_slice(GA);
    v
}

fn same_file(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ", a.display(), b.display());
}

/// Plan into `arr`, run every task alone, gather; compare with the one-process `local`.
fn plan_tasks_gather_matches_local(cmd: &[&str], n: usize, members: &[&str], summaries: &[&str], name: &str) {
    let (local, arr) = (fresh_dir(&format!("{name}-local")), fresh_dir(&format!("{name}-arr")));
    let mut a = with_ga(cmd);
    a.extend(["--out", local.to_str().unwrap()]);
    let (code, local_out, err) = run(&a);
    assert_eq!(code, 0, "{err}");

    let mut a = with_ga(cmd);
    a.extend(["--out", arr.to_str().unwrap(), "--plan"]);
    let (code, out, err) = run(&a);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains(&format!("({n} members)")), "{out}");
    assert!(arr.join("plan.json").exists());
    let d = arr.to_str().unwrap();
    // last task first: the order does not matter
    for i in (0..n).rev() {
        let (code, out, err) = run(&["campaign", "run", d, "--task", &i.to_string()]);
        assert_eq!(code, 0, "task {i}: {err}");
        assert!(out.contains("finished"), "{out}");
    }
    let (code, status, _) = run(&["campaign", "status", d]);
    assert_eq!(code, 0);
    assert!(status.contains(&format!("finished {n}, running 0, stopped 0, not started 0")), "{status}");
    let (code, gathered, err) = run(&["campaign", "gather", d]);
    assert_eq!(code, 0, "{err}");
    // the same table (the last line names the folder)
    let body = |s: &str| s.lines().filter(|l| !l.starts_with("wrote ")).collect::<Vec<_>>().join("\n");
    assert_eq!(body(&local_out), body(&gathered));
    for f in summaries {
        same_file(&local.join(f), &arr.join(f));
    }
    for m in members {
        for f in ["pareto.csv", "evaluations.csv", "checkpoint.json", "run.toml", "pareto.svg"] {
            same_file(&local.join(m).join(f), &arr.join(m).join(f));
        }
    }
    // a finished task is not rerun
    let (code, out, _) = run(&["campaign", "run", d, "--task", "0"]);
    assert_eq!(code, 0);
    assert!(out.contains("already finished"), "{out}");
    let _ = std::fs::remove_dir_all(&local);
    let _ = std::fs::remove_dir_all(&arr);
}

#[test]
fn a_sweep_run_task_by_task_gives_the_one_process_bytes() {
    plan_tasks_gather_matches_local(
        &["gpu-sweep", "--env", "lunar", "--alpha", "10..40", "--step", "10"],
        4,
        &["alpha_010.00", "alpha_020.00", "alpha_030.00", "alpha_040.00"],
        &["summary.csv", "sweep.svg"],
        "sweep",
    );
}

#[test]
fn a_repeatability_study_run_task_by_task_gives_the_one_process_bytes() {
    plan_tasks_gather_matches_local(
        &["study", "repeatability", "--env", "lunar", "--runs", "3"],
        3,
        &["run_000", "run_001", "run_002"],
        &["runs.csv", "summary.csv", "repeatability.svg"],
        "rep",
    );
}

#[test]
fn gather_refuses_a_partial_campaign_and_names_what_is_missing() {
    let arr = fresh_dir("partial");
    let d = arr.to_str().unwrap();
    let (code, _, err) =
        run(&with_ga(&["gpu-sweep", "--env", "lunar", "--alpha", "20..30", "--step", "10", "--out", d, "--plan"]));
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&["campaign", "run", d, "--task", "1"]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&["campaign", "gather", d]);
    assert_eq!(code, 2);
    assert!(err.contains("1 of 2 members") && err.contains("alpha  20.0  not started"), "{err}");
    assert!(!arr.join("summary.csv").exists());
    // a member whose run stopped half-way (a checkpoint, no final front) is partial too
    let (code, status, _) = run(&["campaign", "status", d]);
    assert_eq!(code, 0);
    assert!(status.contains("finished 1, running 0, stopped 0, not started 1"), "{status}");
    // the same folder cannot be planned with other settings
    let (code, _, err) =
        run(&with_ga(&["gpu-sweep", "--env", "lunar", "--alpha", "20..40", "--step", "10", "--out", d, "--plan"]));
    assert_eq!(code, 2);
    assert!(err.contains("different plan"), "{err}");
    let _ = std::fs::remove_dir_all(&arr);
}

#[test]
fn bad_campaign_input_is_named() {
    let arr = fresh_dir("bad");
    let d = arr.to_str().unwrap();
    let (code, _, err) =
        run(&with_ga(&["gpu-sweep", "--env", "lunar", "--alpha", "20..30", "--step", "10", "--out", d, "--plan"]));
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = run(&["campaign", "run", d, "--task", "2"]);
    assert_eq!(code, 2);
    assert!(err.contains("--task 2") && err.contains("2 members"), "{err}");
    let o = sawtooth().args(["campaign", "run", d]).env("SLURM_ARRAY_TASK_ID", "x1").output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("SLURM_ARRAY_TASK_ID"));
    for (flag, v) in [("--time", "1 hour"), ("--partition", "a b"), ("--cpus-per-task", "0"), ("--max-parallel", "0")] {
        let (code, _, err) = run(&["campaign", "slurm", d, flag, v]);
        assert_eq!(code, 2, "{flag} {v}");
        assert!(err.contains(flag), "{flag}: {err}");
    }
    let (code, out, err) =
        run(&["campaign", "slurm", d, "--time", "0-01:00:00", "--max-parallel", "1", "--cpus-per-task", "2"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("--dependency=afterok:"), "{out}");
    let script = std::fs::read_to_string(arr.join("slurm/array.sbatch")).unwrap();
    for line in [
        "#SBATCH --array=0-1%1",
        "#SBATCH --time=0-01:00:00",
        "#SBATCH --cpus-per-task=2",
        "/logs/%A_%a.out",
        "--task \"$SLURM_ARRAY_TASK_ID\"",
    ] {
        assert!(script.contains(line), "{line} in\n{script}");
    }
    // not a campaign
    let plain = fresh_dir("plain");
    std::fs::create_dir_all(&plain).unwrap();
    let (code, _, err) = run(&["campaign", "gather", plain.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("not a campaign folder"), "{err}");
    // a folder with someone else's files is not written into
    std::fs::write(plain.join("notes.txt"), "mine").unwrap();
    let (code, _, err) = run(&with_ga(&[
        "gpu-sweep",
        "--env",
        "lunar",
        "--alpha",
        "20..30",
        "--step",
        "10",
        "--out",
        plain.to_str().unwrap(),
        "--plan",
    ]));
    assert_eq!(code, 2);
    assert!(err.contains("is not a folder of sawtooth's"), "{err}");
    let _ = std::fs::remove_dir_all(&arr);
    let _ = std::fs::remove_dir_all(&plain);
}

#[test]
fn a_member_owned_by_another_process_is_refused() {
    let arr = fresh_dir("locked");
    let d = arr.to_str().unwrap();
    let (code, _, err) =
        run(&with_ga(&["gpu-sweep", "--env", "lunar", "--alpha", "20..30", "--step", "10", "--out", d, "--plan"]));
    assert_eq!(code, 0, "{err}");
    // this test process plays the other task: it holds member 0's lock
    let member = arr.join("alpha_020.00");
    std::fs::create_dir_all(&member).unwrap();
    let lock = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(member.join(".sawtooth.lock"))
        .unwrap();
    lock.try_lock().unwrap();
    let (code, _, err) = run(&["campaign", "run", d, "--task", "0"]);
    assert_eq!(code, 2);
    assert!(err.contains("in use by another sawtooth process"), "{err}");
    let (_, status, _) = run(&["campaign", "status", d]);
    assert!(status.contains("alpha  20.0  running"), "{status}");
    // the whole campaign run here needs every member: refused too, nothing interleaved
    let (code, _, err) = run(&["campaign", "run", d]);
    assert_eq!(code, 2);
    assert!(err.contains("in use"), "{err}");
    drop(lock);
    let (code, _, err) = run(&["campaign", "run", d]);
    assert_eq!(code, 0, "{err}");
    assert!(arr.join("summary.csv").exists());
    let _ = std::fs::remove_dir_all(&arr);
}

#[test]
fn sigterm_saves_a_checkpoint_and_the_next_task_resumes_to_the_same_bytes() {
    let (whole, cut) = (fresh_dir("whole"), fresh_dir("cut"));
    let ga = [
        "--pop",
        "16",
        "--generations",
        "200",
        "--algorithm",
        "nsga2",
        "--particles",
        "40",
        "--final-particles",
        "60",
        "--replicates",
        "2",
        "--quiet",
    ];
    for dir in [&whole, &cut] {
        let mut a =
            vec!["study", "repeatability", "--env", "lunar", "--runs", "2", "--out", dir.to_str().unwrap(), "--plan"];
        a.extend_from_slice(&ga);
        let (code, _, err) = run(&a);
        assert_eq!(code, 0, "{err}");
    }
    let (code, _, err) = run(&["campaign", "run", whole.to_str().unwrap(), "--task", "1"]);
    assert_eq!(code, 0, "{err}");

    let mut child = sawtooth()
        .args(["campaign", "run", cut.to_str().unwrap(), "--task", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let gens = cut.join("run_001/generations.csv");
    let t = Instant::now();
    while std::fs::read_to_string(&gens).map_or(0, |s| s.lines().count()) < 6 && t.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(5));
    }
    let st = Command::new("kill").args(["-TERM", &child.id().to_string()]).status().unwrap();
    assert!(st.success());
    let code = child.wait().unwrap().code();
    assert_eq!(code, Some(130), "SIGTERM: checkpoint saved, exit 130");
    let (_, status, _) = run(&["campaign", "status", cut.to_str().unwrap()]);
    assert!(status.contains("stopped at generation"), "{status}");
    let (code, _, err) = run(&["campaign", "run", cut.to_str().unwrap(), "--task", "1"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("resuming from the checkpoint at generation"), "{err}");
    for f in ["pareto.csv", "evaluations.csv", "checkpoint.json"] {
        same_file(&whole.join("run_001").join(f), &cut.join("run_001").join(f));
    }
    let _ = std::fs::remove_dir_all(&whole);
    let _ = std::fs::remove_dir_all(&cut);
}

#[test]
fn a_sensitivity_plan_holds_the_grid_and_the_repeatability_interval() {
    let (rep, sens) = (fresh_dir("rep-summary"), fresh_dir("sens-plan"));
    std::fs::create_dir_all(&rep).unwrap();
    // the w_spec row of a gathered repeatability study: mean 400, half width 12.5
    std::fs::write(
        rep.join("summary.csv"),
        "metric,mean,sd,cv,ci95_half_width,n\nw_spec_j_kg,4.0e2,1.0e1,2.5e-2,1.25e1,3\n",
    )
    .unwrap();
    let (code, out, err) = run(&with_ga(&[
        "study",
        "sensitivity",
        "--env",
        "lunar",
        "--repeatability",
        rep.to_str().unwrap(),
        "--out",
        sens.to_str().unwrap(),
        "--plan",
    ]));
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("(25 members)"), "{out}");
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sens.join("plan.json")).unwrap()).unwrap();
    assert_eq!(plan["study"]["kind"], "sensitivity");
    assert_eq!(plan["study"]["repeatability_ci"], serde_json::json!([400.0, 12.5]));
    assert_eq!(plan["members"].as_array().unwrap().len(), 25);
    assert_eq!(plan["members"][24]["dir"], "grid_24");
    let _ = std::fs::remove_dir_all(&rep);
    let _ = std::fs::remove_dir_all(&sens);
}
