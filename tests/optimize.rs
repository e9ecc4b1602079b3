//! `sawtooth optimize` end to end: outputs, and a run killed mid-way (SIGKILL) that resumes
//! to the identical front of an uninterrupted run with the same seed.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

mod common;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_sawtooth")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sawtooth-opt-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

const ARGS: &[&str] = &[
    "optimize",
    "--env",
    "lunar",
    "--pop",
    "48",
    "--generations",
    "14",
    "--algorithm",
    "nsga2",
    "--particles",
    "150",
    "--final-particles",
    "100",
    "--replicates",
    "2",
    "--seed",
    "3",
    "--quiet",
    "--engine",
    "cpu",
];

fn run_to_end(out: &Path, extra: &[&str]) -> String {
    let o = Command::new(bin()).args(ARGS).args(["--out", out.to_str().unwrap()]).args(extra).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn rows(path: &Path) -> usize {
    std::fs::read_to_string(path).map(|t| t.lines().count().saturating_sub(1)).unwrap_or(0)
}

#[test]
fn optimize_writes_its_outputs_and_resumes_after_a_kill_to_the_same_front() {
    let full = tmp("full");
    let stdout = run_to_end(&full, &[]);
    for f in ["run.toml", "evaluations.csv", "generations.csv", "checkpoint.json", "pareto.csv", "pareto.svg"] {
        assert!(full.join(f).exists(), "missing {f}");
    }
    common::assert_png_beside(&full.join("pareto.svg"));
    assert!(stdout.contains("A ") && stdout.contains("C "), "{stdout}");
    assert_eq!(rows(&full.join("generations.csv")), 14);
    assert_eq!(rows(&full.join("evaluations.csv")), 48 * 15);
    let header = std::fs::read_to_string(full.join("pareto.csv")).unwrap();
    assert!(header.starts_with("l_c_mm,l_a_mm,l_b_mm,r_mm,omega_deg,delta_deg,v0_m_s,a_m_s2,f_stroke_hz,w_spec_j_kg,m_dot_kg_s,stroke_m,n_wire,d_avg_m"));
    assert!(rows(&full.join("pareto.csv")) >= 1);

    // the same run, killed once it has logged a few generations
    let cut = tmp("cut");
    let mut child = Command::new(bin())
        .args(ARGS)
        .args(["--out", cut.to_str().unwrap()])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while rows(&cut.join("generations.csv")) < 4 && t.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(2));
    }
    let _ = child.kill(); // SIGKILL: no chance to save anything
    let _ = child.wait();
    let done = rows(&cut.join("generations.csv"));
    assert!(done < 14, "the run finished before it could be killed ({done} generations)");
    // a second start without --resume refuses to overwrite
    let o = Command::new(bin()).args(ARGS).args(["--out", cut.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    run_to_end(&cut, &["--resume"]);
    for f in ["pareto.csv", "generations.csv"] {
        let a = std::fs::read_to_string(full.join(f)).unwrap();
        let b = std::fs::read_to_string(cut.join(f)).unwrap();
        if f == "generations.csv" {
            // elapsed time differs; everything else must match
            let strip = |t: &str| t.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string()).collect::<Vec<_>>();
            assert_eq!(strip(&a), strip(&b), "{f}");
        } else {
            assert_eq!(a, b, "{f} differs after kill + resume");
        }
    }
    assert_eq!(
        std::fs::read_to_string(full.join("evaluations.csv")).unwrap(),
        std::fs::read_to_string(cut.join("evaluations.csv")).unwrap()
    );
    let _ = std::fs::remove_dir_all(&full);
    let _ = std::fs::remove_dir_all(&cut);
}

#[test]
fn optimize_rejects_bad_settings() {
    let out = tmp("bad");
    let o = Command::new(bin())
        .args(["optimize", "--pop", "2", "--out", out.to_str().unwrap(), "--quiet"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--pop"));
    // sizes that are typos are refused before any allocation or work, naming the flag
    for (flag, value) in [
        ("--pop", "1000000000"),
        ("--final-particles", "100000000"),
        ("--replicates", "5000"),
        ("--generations", "9999999999"),
    ] {
        let o = Command::new(bin())
            .args(["optimize", flag, value, "--out", out.to_str().unwrap(), "--quiet"])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(flag) && err.contains("at most"), "{flag}: {err}");
    }
    let o = Command::new(bin()).args(["optimize", "--resume", "--out", out.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("run.toml"));
}
