//! Issue 34's findings, each as a user met it: every one ends as a clear error naming the
//! field and its rule (exit 2, no panic, no abort, no hang) or as working behaviour. Each
//! command runs under a memory limit and a time limit, so a regression to "allocate first,
//! check later" fails here instead of bringing the machine down.

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use crate::common;
use common::repo;

/// Address space granted to one probe: far below what any refused input would allocate.
const PROBE_MEMORY_BYTES: u64 = 3 << 30;
/// A refused input is refused at once; a probe that runs this long hangs.
const PROBE_TIMEOUT: Duration = Duration::from_secs(60);

struct Outcome {
    code: i32,
    stdout: String,
    stderr: String,
}

/// The binary run in `dir` under the probe's memory and time limits, its output captured.
fn sawtooth_in(dir: &Path, args: &[&str]) -> Outcome {
    let mut cmd = common::sawtooth();
    cmd.args(args).current_dir(dir).stdout(Stdio::piped()).stderr(Stdio::piped());
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt as _;
        // SAFETY: setrlimit is async-signal-safe and touches only the child.
        unsafe {
            cmd.pre_exec(|| {
                let lim = libc_rlimit(PROBE_MEMORY_BYTES);
                if setrlimit(RLIMIT_AS, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    let started = Instant::now();
    let mut child = cmd.spawn().expect("run binary");
    let (mut out, mut err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut out, &mut s).ok();
        s
    });
    let ereader = std::thread::spawn(move || {
        let mut s = String::new();
        std::io::Read::read_to_string(&mut err, &mut s).ok();
        s
    });
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if started.elapsed() > PROBE_TIMEOUT {
            child.kill().ok();
            panic!("sawtooth {args:?} still ran after {PROBE_TIMEOUT:?}: a hang");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Outcome { code: status.code().unwrap_or(-1), stdout: reader.join().unwrap(), stderr: ereader.join().unwrap() }
}

// the two symbols of libc this needs, declared here rather than adding a dependency
#[cfg(target_os = "linux")]
#[repr(C)]
struct Rlimit {
    cur: u64,
    max: u64,
}
#[cfg(target_os = "linux")]
const RLIMIT_AS: i32 = 9;
#[cfg(target_os = "linux")]
extern "C" {
    fn setrlimit(resource: i32, rlim: *const Rlimit) -> i32;
}
#[cfg(target_os = "linux")]
fn libc_rlimit(bytes: u64) -> Rlimit {
    Rlimit { cur: bytes, max: bytes }
}

/// `args` is refused with exit 2, no panic, and a message holding every one of `names`.
#[track_caller]
fn refused(args: &[&str], names: &[&str]) {
    let o = sawtooth_in(repo(), args);
    assert_eq!(o.code, 2, "sawtooth {args:?}: exit {} (want 2)\n{}", o.code, o.stderr);
    assert!(!o.stderr.contains("panicked"), "sawtooth {args:?} panicked:\n{}", o.stderr);
    for n in names {
        assert!(o.stderr.contains(n), "sawtooth {args:?}: `{n}` missing from:\n{}", o.stderr);
    }
}

const TEST3: [&str; 4] = ["--data", "data/validation/test3.csv", "--setup", "data/validation/test3.toml"];

fn with<'a>(a: &[&'a str], b: &[&'a str]) -> Vec<&'a str> {
    a.iter().chain(b).copied().collect()
}

/// Findings 3-6: counts that size an allocation or a loop are bounded before anything is
/// allocated; endless files are refused by name.
#[test]
fn counts_past_their_bounds_are_refused_by_name_before_anything_is_allocated() {
    refused(
        &["study", "repeatability", "--runs", "4294967295", "--plan", "--out", "/nonexistent/x"],
        &["--runs", "[2, 10000]"],
    );
    refused(&["conformance", "--particles", "0"], &["--particles", "[1, 10000000]"]);
    refused(&["conformance", "--particles", "10000001"], &["--particles"]);
    refused(&["conformance", "--designs", "0"], &["--designs", "[1, 10000]"]);
    refused(&["conformance", "--designs", "1000000000"], &["--designs"]);
    refused(&["bench", "--designs", "1000000"], &["--designs", "[1, 100000]"]);
    refused(&["bench", "--designs", "4294967296"], &["--designs"]);
    refused(&["bench", "--repeats", "4294967295"], &["--repeats", "[1, 1000]"]);
    refused(&with(&["fit"], &with(&TEST3, &["--generations", "4294967295"])), &["--generations", "[0, 100000]"]);
    refused(
        &with(&["diagnose"], &with(&TEST3, &["--generations", "4294967295", "--out", "/nonexistent/d"])),
        &["--generations"],
    );
    refused(
        &["synth", "--setup", "data/validation/test3.toml", "--runs", "100000000", "--out", "/nonexistent/s.csv"],
        &["--runs", "[1, 10000]"],
    );
    refused(
        &["synth", "--setup", "data/validation/test3.toml", "--particles", "10000001", "--out", "/nonexistent/s.csv"],
        &["--particles"],
    );
    refused(&["optimize", "--pop", "1000000000", "--out", "/nonexistent/o"], &["--pop", "[4, 100000]"]);
    refused(&["optimize", "--checkpoint-every", "0", "--out", "/nonexistent/o"], &["--checkpoint-every"]);
    if Path::new("/dev/zero").exists() {
        refused(&["simulate", "--config", "/dev/zero"], &["--config", "/dev/zero", "larger than 4 MiB"]);
        refused(
            &with(&["fit", "--data", "/dev/zero"], &["--setup", "data/validation/test3.toml"]),
            &["--data", "/dev/zero", "larger than 64 MiB"],
        );
    }
}

/// The bounds declared in `sawtooth::schema` after the first round (calibration replicates,
/// slope points, the DEM's counts, the scenario's reals): each refused under the name the
/// user typed, with the schema's rule, and a negative number reaches the rule instead of
/// being taken for a flag.
#[test]
fn every_declared_bound_is_the_one_the_user_meets() {
    let d = |extra: &[&'static str]| with(&["diagnose"], &with(&TEST3, &with(extra, &["--out", "/nonexistent/d"])));
    refused(&d(&["--bootstrap", "1"]), &["--bootstrap", "[2, 100000]"]);
    refused(&d(&["--rescore-streams", "0"]), &["--rescore-streams", "[1, 1000]"]);
    refused(&with(&["fit"], &with(&TEST3, &["--bootstrap", "4294967295"])), &["--bootstrap", "[0, 10000]"]);
    refused(
        &[
            "simulate",
            "--env",
            "lunar",
            "--design",
            "47.376,45.884,34.375,36.916,62.853,17.552,1.299,58.595",
            "--alpha",
            "0..40",
            "--alpha-points",
            "42",
        ],
        &["--alpha-points", "[2, 41]"],
    );
    refused(&["dem", "run", "--runs", "0", "--out", "/nonexistent/r"], &["--runs", "[1, 10000]"]);
    refused(&["optimize", "--tol", "-1", "--out", "/nonexistent/o"], &["--tol must lie in (0, 1]"]);
    refused(
        &["simulate", "--env", "lunar", "--k-elastic", "-0.5"],
        &["`[collision] k_elastic` (--k-elastic)", "[0, 1]"],
    );
    refused(&["simulate", "--env", "lunar", "--aor", "-3"], &["--aor", "[0, 89] degrees"]);
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("heavy.toml");
    std::fs::write(&config, "[environment]\ng_m_s2 = 1e308\n").unwrap();
    refused(&["simulate", "--config", config.to_str().unwrap()], &["g_m_s2", "(0, 100] m/s^2"]);
    // the listing seats at most 2000 launch points (D.5 line 31-32): no design seats 5000,
    // which ends in a rule naming the fill, not in a panic after a million draws
    refused(
        &[
            "bench",
            "--env",
            "earth",
            "--compat-listing",
            "--particles",
            "5000",
            "--sample",
            "random",
            "--designs",
            "2",
            "--engines",
            "cpu",
        ],
        &["--designs 2", "fill area too small"],
    );
}

/// Finding 7: values that printed nonsense with exit 0.
#[test]
fn values_that_made_nonsense_are_refused_naming_the_rule() {
    let d = tempfile::tempdir().unwrap();
    for (key, value, rule) in [
        ("conveyor_length_m", "1e308", "(0, 1000] m"),
        ("contraction_ratio", "2.0", "(0, 1)"),
        ("f_max_hz", "1e300", "(0, 10000] Hz"),
    ] {
        let cfg = d.path().join(format!("{key}.toml"));
        std::fs::write(&cfg, format!("env = \"earth\"\n[performance]\n{key} = {value}\n")).unwrap();
        refused(&["simulate", "--config", cfg.to_str().unwrap()], &[&format!("`[performance] {key}`"), rule]);
    }
    refused(
        &["synth", "--setup", "data/validation/test3.toml", "--mass-g", "1e308", "--out", "/nonexistent/s.csv"],
        &["--mass-g", "(0, 1000000] g", "1e308"],
    );
    // input_mass below the teeth's sum, and one empty input_mass cell
    let csv = d.path().join("m.csv");
    std::fs::write(
        &csv,
        "run,tooth_1,tooth_2,tooth_3,tooth_4,input_mass\n1,0.94,0.49,0.41,0.05,1.00\n2,0.9,0.5,0.4,0.1,2\n",
    )
    .unwrap();
    refused(
        &["fit", "--data", csv.to_str().unwrap(), "--setup", "data/validation/test3.toml"],
        &["run `1`", "189 % of its input_mass 1 g", "[0, 1.5]"],
    );
    std::fs::write(
        &csv,
        "run,tooth_1,tooth_2,tooth_3,tooth_4,input_mass\n1,0.94,0.49,0.41,0.05,\n2,0.9,0.5,0.4,0.1,2\n",
    )
    .unwrap();
    refused(
        &["fit", "--data", csv.to_str().unwrap(), "--setup", "data/validation/test3.toml"],
        &["column `input_mass`", "record it for every run"],
    );
}

/// Finding 8: messages that named the wrong rule or needed guessing.
#[test]
fn messages_name_the_users_flag_and_the_true_rule() {
    refused(&["simulate", "--env", "earth", "--k-drag=-1"], &["--k-drag must be a finite number >= 0", "0 = vacuum"]);
    // a negative value needs no `=`
    let o = sawtooth_in(
        repo(),
        &[
            "simulate",
            "--env",
            "earth",
            "--design",
            "47.376,45.884,34.375,36.916,62.853,17.552,1.299,58.595",
            "--particles",
            "20",
            "--launch-offset",
            "-18.434",
            "--json",
        ],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    assert!(v.get("distribution").is_some());
    refused(&["simulate", "--env", "earth", "--k-drag", "-1"], &["--k-drag must be a finite number >= 0"]);
    refused(
        &with(&["diagnose"], &with(&TEST3, &["--effects", "all,polydisperse", "--out", "/nonexistent/d"])),
        &["`all` stands alone"],
    );
    refused(
        &["simulate", "--env", "earth", "--effect", "polydisperse=0.1", "--effect", "polydisperse=0.2"],
        &["effect `polydisperse` given twice"],
    );
    refused(&["simulate", "--env", "lunar", "--effect", "quadratic-drag=150e-6,2500"], &["quadratic-drag", "vacuum"]);
}

/// Findings 1-2: a user's files are never taken for a run; the project's own temporary
/// files never block a rerun.
#[test]
fn a_users_folder_is_never_written_into_and_a_killed_runs_is_rerun() {
    let d = tempfile::tempdir().unwrap();
    let u = d.path().join("u");
    std::fs::create_dir(&u).unwrap();
    std::fs::write(u.join("run.toml"), "notes\n").unwrap();
    std::fs::write(u.join("pareto.csv"), "mine\n").unwrap();
    let small = [
        "--env",
        "earth",
        "--pop",
        "8",
        "--generations",
        "1",
        "--particles",
        "30",
        "--final-particles",
        "30",
        "--replicates",
        "1",
        "--quiet",
    ];
    let o = sawtooth_in(repo(), &with(&["optimize", "--out", u.to_str().unwrap()], &small));
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains("is not a folder of sawtooth's"), "{}", o.stderr);
    assert_eq!(std::fs::read_to_string(u.join("pareto.csv")).unwrap(), "mine\n");
    assert_eq!(std::fs::read_to_string(u.join("run.toml")).unwrap(), "notes\n");
    for (cmd, file) in [("fit", "fit.json"), ("diagnose", "diagnosis.json")] {
        let f = d.path().join(cmd);
        std::fs::create_dir(&f).unwrap();
        std::fs::write(f.join(file), "mine\n").unwrap();
        refused(
            &with(&[cmd], &with(&TEST3, &["--out", f.to_str().unwrap()])),
            &["--out", "is not a folder of sawtooth's"],
        );
        assert_eq!(std::fs::read_to_string(f.join(file)).unwrap(), "mine\n");
    }
    // killed between the marker's temporary file and its rename
    let w = d.path().join("w");
    std::fs::create_dir(&w).unwrap();
    std::fs::write(w.join(".sawtooth.lock"), "").unwrap();
    std::fs::write(w.join("..sawtooth-run.Xy12Ab.sawtooth-tmp"), "optim").unwrap();
    let o = sawtooth_in(repo(), &with(&["optimize", "--out", w.to_str().unwrap()], &small));
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(w.join("pareto.csv").exists());
}

/// An edit of a loaded JSON document (a checkpoint, a plan).
type JsonEdit = Box<dyn Fn(&mut serde_json::Value)>;

/// Finding 4 and 7, and what-to-build 3: checkpoints and plans are validated as input.
#[test]
fn edited_checkpoints_and_plans_are_refused_by_field() {
    let d = tempfile::tempdir().unwrap();
    let run = d.path().join("run");
    let small = [
        "--env",
        "earth",
        "--pop",
        "8",
        "--generations",
        "2",
        "--particles",
        "30",
        "--final-particles",
        "30",
        "--replicates",
        "1",
        "--quiet",
    ];
    let o = sawtooth_in(repo(), &with(&["optimize", "--out", run.to_str().unwrap()], &small));
    assert_eq!(o.code, 0, "{}", o.stderr);
    let ck = run.join("checkpoint.json");
    let good: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&ck).unwrap()).unwrap();
    let resume = |extra: &[&str]| {
        let mut a = vec!["optimize", "--out", run.to_str().unwrap(), "--resume", "--generations", "3", "--quiet"];
        a.extend_from_slice(extra);
        sawtooth_in(repo(), &a)
    };
    let edits: Vec<(&str, JsonEdit)> = vec![
        ("`population` holds 0", Box::new(|v| v["population"] = serde_json::json!([]))),
        ("`population[0].x` has 5", Box::new(|v| v["population"][0]["x"].as_array_mut().unwrap().truncate(5))),
        ("`population[0].x` has 0", Box::new(|v| v["population"][0]["x"] = serde_json::json!([]))),
        ("`population[0].x` has 9", Box::new(|v| v["population"][0]["x"].as_array_mut().unwrap().push("1".into()))),
        ("`generation` 999999", Box::new(|v| v["generation"] = 999_999.into())),
    ];
    for (want, edit) in edits {
        let mut v = good.clone();
        edit(&mut v);
        std::fs::write(&ck, serde_json::to_string(&v).unwrap()).unwrap();
        let o = resume(&[]);
        assert_eq!(o.code, 2, "{want}: {}", o.stderr);
        assert!(o.stderr.contains(want) && o.stderr.contains("checkpoint.json"), "{want}: {}", o.stderr);
    }
    std::fs::write(&ck, serde_json::to_string(&good).unwrap()).unwrap();
    let o = resume(&["--engine", "gpu"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains("--engine gpu differs from the run's cpu"), "{}", o.stderr);
    let o = resume(&["--teeth", "50"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains("scenario.sim.teeth") && !o.stderr.contains("environment.g"), "{}", o.stderr);

    // a plan: members' settings by the run's rules, and at least one member
    let camp = d.path().join("camp");
    let o = sawtooth_in(
        repo(),
        &with(
            &["gpu-sweep", "--alpha", "10..11", "--step", "1", "--plan", "--out", camp.to_str().unwrap()],
            &small[..small.len() - 1],
        ),
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let plan_path = camp.join("plan.json");
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan_path).unwrap()).unwrap();
    let edits: Vec<(&str, JsonEdit)> = vec![
        (
            "`config.pop` must lie in [4, 100000]",
            Box::new(|v| v["members"][0]["manifest"]["config"]["pop"] = 1_000_000_000u64.into()),
        ),
        (
            "`sim.particles`",
            Box::new(|v| v["members"][1]["manifest"]["scenario"]["sim"]["particles"] = 4_294_967_295u64.into()),
        ),
        (
            "`config.max_generations`",
            Box::new(|v| v["members"][0]["manifest"]["config"]["max_generations"] = 1_000_000_000_000u64.into()),
        ),
        ("`members` (their number) must lie in [1, 100000]", Box::new(|v| v["members"] = serde_json::json!([]))),
    ];
    for (want, edit) in edits {
        let mut v = plan.clone();
        edit(&mut v);
        std::fs::write(&plan_path, serde_json::to_string(&v).unwrap()).unwrap();
        for sub in ["run", "gather", "status"] {
            let o = sawtooth_in(repo(), &["campaign", sub, camp.to_str().unwrap()]);
            assert_eq!(o.code, 2, "{sub} {want}: {}", o.stderr);
            assert!(o.stderr.contains(want) && o.stderr.contains("plan.json"), "{sub} {want}: {}", o.stderr);
        }
    }
}
