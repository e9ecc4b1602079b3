//! `sawtooth optimize` end to end: outputs, and a run killed mid-way (SIGKILL) or stopped by
//! Ctrl-C (SIGINT) that resumes to the identical front of an uninterrupted run with the same
//! seed.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common;
use common::{fresh_dir, sawtooth};

use sawtooth::optim::runner::{EvaluationRow, GenerationRow};

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
    let o = sawtooth().args(ARGS).args(["--out", out.to_str().unwrap()]).args(extra).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn rows(path: &Path) -> usize {
    std::fs::read_to_string(path).map(|t| t.lines().count().saturating_sub(1)).unwrap_or(0)
}

#[test]
fn optimize_writes_its_outputs_and_resumes_after_a_kill_to_the_same_front() {
    let full = fresh_dir("full");
    let stdout = run_to_end(&full, &[]);
    for f in ["run.toml", "evaluations.csv", "generations.csv", "checkpoint.json", "pareto.csv", "pareto.svg"] {
        assert!(full.join(f).exists(), "missing {f}");
    }
    common::assert_png_beside(&full.join("pareto.svg"));
    assert!(stdout.contains("A ") && stdout.contains("C "), "{stdout}");
    assert_eq!(rows(&full.join("generations.csv")), 14);
    assert_eq!(rows(&full.join("evaluations.csv")), 48 * 15);
    // both logs are typed rows: every column named in the type, with its type
    let evaluations: Vec<EvaluationRow> =
        csv::Reader::from_path(full.join("evaluations.csv")).unwrap().deserialize().collect::<Result<_, _>>().unwrap();
    assert_eq!(evaluations.len(), 48 * 15);
    assert!(evaluations.iter().any(|r| r.w_spec_j_kg.is_some()));
    for r in &evaluations {
        // figures exactly where the design was simulated and accepted, a reason otherwise
        assert_eq!(r.f_stroke_hz.is_some(), r.invalid.is_empty(), "{r:?}");
        assert!(r.generation <= 14 && r.alpha_deg == 35.0 && r.compliant.is_none(), "{r:?}");
    }
    let generations: Vec<GenerationRow> =
        csv::Reader::from_path(full.join("generations.csv")).unwrap().deserialize().collect::<Result<_, _>>().unwrap();
    assert_eq!(generations.iter().map(|g| g.generation).collect::<Vec<_>>(), (1..=14).collect::<Vec<_>>());
    assert!(generations.iter().all(|g| g.hypervolume_hz_j_kg >= 0.0 && g.evaluations > 0));
    let header = std::fs::read_to_string(full.join("pareto.csv")).unwrap();
    assert!(header.starts_with("l_c_mm,l_a_mm,l_b_mm,r_mm,omega_deg,delta_deg,v0_m_s,a_m_s2,f_stroke_hz,w_spec_j_kg,m_dot_kg_s,stroke_m,n_wire,d_avg_m"));
    assert!(rows(&full.join("pareto.csv")) >= 1);

    // the same run, killed once it has logged a few generations
    let cut = fresh_dir("cut");
    let mut child = sawtooth()
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
    let o = sawtooth().args(ARGS).args(["--out", cut.to_str().unwrap()]).output().unwrap();
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

    // Ctrl-C: the run stops after the generation it is in, with a checkpoint of it (saved
    // at the stop: the periodic ones come every 5 generations here), exit 130
    let int = fresh_dir("int");
    let child = sawtooth()
        .args(ARGS)
        .args(["--out", int.to_str().unwrap(), "--checkpoint-every", "5"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let t = Instant::now();
    while rows(&int.join("generations.csv")) < 3 && t.elapsed() < Duration::from_secs(60) {
        std::thread::sleep(Duration::from_millis(2));
    }
    let sent = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(sent.success());
    let o = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{stderr}");
    let logged = rows(&int.join("generations.csv")) as u64;
    assert!(logged < 14, "the run finished before Ctrl-C ({logged} generations)");
    let checkpoint: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(int.join("checkpoint.json")).unwrap()).unwrap();
    assert_eq!(checkpoint["generation"].as_u64(), Some(logged), "the checkpoint holds the last logged generation");
    assert!(stderr.contains(&format!("interrupted: checkpoint saved at generation {logged}")), "{stderr}");
    assert!(stderr.contains("continue with the same command and --resume"), "{stderr}");
    assert!(!int.join("pareto.csv").exists(), "an interrupted run writes no front");
    run_to_end(&int, &["--resume"]);
    for f in ["pareto.csv", "evaluations.csv"] {
        let a = std::fs::read_to_string(full.join(f)).unwrap();
        assert_eq!(a, std::fs::read_to_string(int.join(f)).unwrap(), "{f} differs after Ctrl-C + resume");
    }
    let _ = std::fs::remove_dir_all(&full);
    let _ = std::fs::remove_dir_all(&cut);
    let _ = std::fs::remove_dir_all(&int);
}

#[test]
fn optimize_rejects_bad_settings() {
    let out = fresh_dir("bad");
    let o = sawtooth().args(["optimize", "--pop", "2", "--out", out.to_str().unwrap(), "--quiet"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--pop"));
    // sizes that are typos are refused before any allocation or work, naming the flag
    for (flag, value) in [
        ("--pop", "1000000000"),
        ("--final-particles", "100000000"),
        ("--replicates", "5000"),
        ("--generations", "9999999999"),
    ] {
        let o = sawtooth().args(["optimize", flag, value, "--out", out.to_str().unwrap(), "--quiet"]).output().unwrap();
        assert_eq!(o.status.code(), Some(2), "{flag} {value}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(flag) && err.contains("must lie in"), "{flag}: {err}");
    }
    let o = sawtooth().args(["optimize", "--resume", "--out", out.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("run.toml"));
}

const SMALL: &[&str] = &[
    "optimize",
    "--env",
    "earth",
    "--pop",
    "8",
    "--algorithm",
    "nsga2",
    "--particles",
    "30",
    "--final-particles",
    "20",
    "--replicates",
    "1",
    "--seed",
    "5",
    "--quiet",
];

fn small(out: &Path, extra: &[&str]) -> std::process::Output {
    sawtooth().args(SMALL).args(["--out", out.to_str().unwrap()]).args(extra).output().unwrap()
}

fn ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn refused(o: &std::process::Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

/// generations.csv without the elapsed-time column
fn generations(dir: &Path) -> Vec<String> {
    let t = std::fs::read_to_string(dir.join("generations.csv")).unwrap();
    t.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string()).collect()
}

#[test]
fn resume_checks_the_stored_run_and_the_flags_given_with_it() {
    let dir = fresh_dir("resume-rules");
    ok(&small(&dir, &["--generations", "3"]));
    let manifest = dir.join("run.toml");
    let original = std::fs::read_to_string(&manifest).unwrap();
    // a run.toml edited to values the CLI refuses is refused on resume, naming the key
    for (from, to, key) in [
        ("k_drag = 5.439", "k_drag = nan", "environment.k_drag"),
        ("pop = 8", "pop = 2", "config.pop"),
        ("alpha_deg = 35.0", "alpha_deg = 95.0", "environment.alpha_deg"),
    ] {
        assert!(original.contains(from), "{from}");
        std::fs::write(&manifest, original.replacen(from, to, 1)).unwrap();
        refused(&small(&dir, &["--generations", "3", "--resume"]), &[key, "run.toml"]);
    }
    std::fs::write(&manifest, &original).unwrap();
    // the run's own command with --resume is fine; flags that describe another run are not
    ok(&small(&dir, &["--generations", "3", "--resume"]));
    refused(
        &small(&dir, &["--generations", "3", "--resume", "--selection", "permutation"]),
        &["--selection permutation", "deb"],
    );
    refused(&small(&dir, &["--generations", "3", "--resume", "--tol", "1e-3"]), &["--tol 0.001", "none"]);
    refused(
        &small(&dir, &["--generations", "3", "--resume", "--k-elastic", "0.5"]),
        &["collision.k_elastic", "0.5", "0.872"],
    );
    refused(&small(&dir, &["--generations", "2", "--resume"]), &["can only be extended"]);
    // a larger --generations extends the finished run to what a longer run gives
    ok(&small(&dir, &["--generations", "5", "--resume"]));
    let longer = fresh_dir("resume-longer");
    ok(&small(&longer, &["--generations", "5"]));
    assert_eq!(generations(&dir), generations(&longer));
    for f in ["pareto.csv", "evaluations.csv"] {
        assert_eq!(std::fs::read(dir.join(f)).unwrap(), std::fs::read(longer.join(f)).unwrap(), "{f}");
    }
    assert!(std::fs::read_to_string(&manifest).unwrap().contains("max_generations = 5"));

    // killed before its first checkpoint: only run.toml exists; --resume starts it again
    let early = fresh_dir("resume-early");
    std::fs::create_dir_all(&early).unwrap();
    // (the marker is written before run.toml: a folder is the project's by its marker only)
    std::fs::copy(longer.join(".sawtooth-run"), early.join(".sawtooth-run")).unwrap();
    std::fs::copy(longer.join("run.toml"), early.join("run.toml")).unwrap();
    let o = small(&early, &["--generations", "5", "--resume"]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("no checkpoint"), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read(early.join("pareto.csv")).unwrap(), std::fs::read(longer.join("pareto.csv")).unwrap());

    // run.toml is a config: its scenario, flags on top
    let o = sawtooth()
        .args(["simulate", "--config", manifest.to_str().unwrap(), "--particles", "20", "--json"])
        .args(["--design", "47.376,45.884,34.375,36.916,62.853,17.552,1.299,58.595"])
        .output()
        .unwrap();
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["scenario"]["environment"]["g"], 9.81);
    assert_eq!(v["scenario"]["sim"]["particles"], 20);
    assert_eq!(v["scenario"]["sim"]["seed"], 5);
    for d in [dir, longer, early] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn progress_goes_to_a_log_as_lines_and_quiet_is_silent() {
    let (loud, quiet) = (fresh_dir("progress-loud"), fresh_dir("progress-quiet"));
    let args = ["optimize", "--env", "lunar", "--pop", "8", "--generations", "4", "--algorithm", "nsga2"];
    let small = ["--particles", "20", "--final-particles", "10", "--replicates", "1"];
    // stderr is a pipe here, not a terminal: periodic lines with the generation and an ETA
    let o = sawtooth().args(args).args(small).args(["--out", loud.to_str().unwrap()]).output().unwrap();
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("generation 1/4:") && err.contains("generation 4/4:") && err.contains("elapsed"), "{err}");
    let o = sawtooth().args(args).args(small).args(["--quiet", "--out", quiet.to_str().unwrap()]).output().unwrap();
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("generation"), "--quiet printed: {err}");
    let _ = std::fs::remove_dir_all(&loud);
    let _ = std::fs::remove_dir_all(&quiet);
}
