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
        refused(&["simulate", "--config", "/dev/zero"], &["--config", "/dev/zero", "is a character device"]);
        refused(
            &with(&["fit", "--data", "/dev/zero"], &["--setup", "data/validation/test3.toml"]),
            &["--data", "/dev/zero", "is a character device"],
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
    refused(&["optimize", "--tol", "-1", "--out", "/nonexistent/o"], &["--tol must lie in [1e-12, 1]"]);
    refused(
        &["simulate", "--env", "lunar", "--k-elastic", "-0.5"],
        &["`[collision] k_elastic` (--k-elastic)", "[0, 1]"],
    );
    refused(&["simulate", "--env", "lunar", "--aor", "-3"], &["--aor", "[0, 89] degrees"]);
    let dir = tempfile::tempdir().unwrap();
    let config = dir.path().join("heavy.toml");
    std::fs::write(&config, "[environment]\ng_m_s2 = 1e308\n").unwrap();
    refused(&["simulate", "--config", config.to_str().unwrap()], &["g_m_s2", "[0.001, 100] m/s^2"]);
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
        ("conveyor_length_m", "1e308", "[0.01, 1000] m"),
        ("contraction_ratio", "2.0", "[1e-4, 1)"),
        ("f_max_hz", "1e300", "[1e-4, 10000] Hz"),
    ] {
        let cfg = d.path().join(format!("{key}.toml"));
        std::fs::write(&cfg, format!("env = \"earth\"\n[performance]\n{key} = {value}\n")).unwrap();
        refused(&["simulate", "--config", cfg.to_str().unwrap()], &[&format!("`[performance] {key}`"), rule]);
    }
    refused(
        &["synth", "--setup", "data/validation/test3.toml", "--mass-g", "1e308", "--out", "/nonexistent/s.csv"],
        &["--mass-g", "[0.001, 1000000] g", "1e308"],
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

/// Write each edit of `good` to `path` in turn and run `reader` on it: each is refused with
/// exit status 2 and no panic, naming the edit's rule (`want`) and `file`.
fn each_edit_is_refused(
    path: &Path,
    good: &serde_json::Value,
    edits: Vec<(&str, JsonEdit)>,
    file: &str,
    reader: &dyn Fn() -> Outcome,
) {
    for (want, edit) in edits {
        let mut v = good.clone();
        edit(&mut v);
        std::fs::write(path, serde_json::to_string(&v).unwrap()).unwrap();
        let o = reader();
        assert_eq!(o.code, 2, "{want}: {}", o.stderr);
        assert!(!o.stderr.contains("panicked"), "{want}: {}", o.stderr);
        assert!(o.stderr.contains(want) && o.stderr.contains(file), "{want}: {}", o.stderr);
    }
}

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
    each_edit_is_refused(&ck, &good, edits, "checkpoint.json", &|| resume(&[]));
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

// ---- issue 45 ---------------------------------------------------------------------------

/// A stand-in for LIGGGHTS (`SAWTOOTH_LIGGGHTS`): the grains end where they were placed, at
/// rest, and `$HOSTILE` names one way a blown-up run writes its dump (or none).
const FAKE_LIGGGHTS: &str = r#"#!/bin/sh
# a fake LIGGGHTS for tests/hostile_input.rs: reads grains.data, writes final.dump and stroke_time.txt
# a single-grain impact run (`dem impact`, the campaign's measured law): the grain leaves the plate
if [ -f grain.data ]; then
  printf 'ITEM: TIMESTEP\n1\nITEM: NUMBER OF ATOMS\n1\nITEM: BOX BOUNDS ff ff pp\n0 1\n0 1\n0 1\nITEM: ATOMS id type diameter mass x y z vx vy vz omegax omegay omegaz\n1 1 0.001 1e-6 0 0.01 0 0.1 0.5 0 0 0 0\n' > final.dump
  echo "Step Atoms KinEng vrms t"
  exit 0
fi
awk 'BEGIN { pi = atan2(0, -1) }
/^Atoms/ { atoms = 1; next }
atoms && NF == 7 { n++; line[n] = sprintf("%d 1 %.9g %.9g %.9g %.9g %.9g 0 0 0", $1, $3, $4 * pi * $3 ^ 3 / 6, $5, $6, $7) }
END {
  print "ITEM: TIMESTEP\n1\nITEM: NUMBER OF ATOMS\n" n "\nITEM: BOX BOUNDS ff ff pp\n0 1\n0 1\n0 1\nITEM: ATOMS id type diameter mass x y z vx vy vz"
  for (i = 1; i <= n; i++) print line[i]
}' grains.data | awk -v mode="$HOSTILE" '
NR == 10 && mode == "nan" { $5 = "nan" }
NR == 10 && mode == "inf" { $6 = "inf" }
NR == 10 && mode == "negative-mass" { $4 = "-" $4 }
NR == 11 && mode == "duplicate-id" { $1 = 1 }
NR == 10 && mode == "huge-id" { $1 = "1000000000000000000" }
NR == 10 && mode == "heavy" { $4 = $4 * 1000 }
NR == 10 && mode == "outside" { $5 = 1000 }
{ print }' > final.dump
case "$HOSTILE" in
  stroke-nan) echo nan ;; stroke-inf) echo inf ;; stroke-negative) echo -1 ;; *) echo 0.5 ;;
esac > stroke_time.txt
echo "Step Atoms KinEng vrms t"
"#;

/// The fake engine written into `dir`, executable; its path.
fn fake_liggghts(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("fake-liggghts");
    std::fs::write(&p, FAKE_LIGGGHTS).unwrap();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        std::fs::set_permissions(&p, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    p
}

/// `sawtooth args` with the fake engine and `$HOSTILE` set, under the probe's limits.
fn with_fake_engine(fake: &Path, hostile: &str, args: &[&str]) -> Outcome {
    let mut cmd = common::sawtooth();
    cmd.args(args).env("SAWTOOTH_LIGGGHTS", fake).env("HOSTILE", hostile).env_remove("SLURM_ARRAY_TASK_ID");
    let o = cmd.output().expect("run binary");
    Outcome {
        code: o.status.code().unwrap_or(-1),
        stdout: String::from_utf8_lossy(&o.stdout).into(),
        stderr: String::from_utf8_lossy(&o.stderr).into(),
    }
}

const RIG: &str = "data/validation/test3.toml";

/// Issue 45, 1: a LIGGGHTS whose dump holds NaN or infinite positions, negative or wrong
/// masses, duplicated or unknown ids, grains outside the box, or a stroke time that is not a
/// time was reported as a perfect run ("d_avg 0.00 mm, 0 of 20 grains lost") and written into
/// dem.csv. Each is a failed run now: exit 2 naming the rule, the folder kept with its reason,
/// no result.json, no dem.csv. The same fake engine writing an honest dump is accepted.
#[test]
fn a_blown_up_dem_run_is_a_failed_run_never_a_number() {
    let d = tempfile::tempdir().unwrap();
    let fake = fake_liggghts(d.path());
    let campaign = |name: &str| d.path().join(name);
    let run = |hostile: &str, out: &Path| {
        with_fake_engine(
            &fake,
            hostile,
            &[
                "dem",
                "run",
                "--config",
                RIG,
                "--particles",
                "20",
                "--runs",
                "1",
                "--jobs",
                "1",
                "--out",
                out.to_str().unwrap(),
            ],
        )
    };
    let honest = campaign("honest");
    let o = run("", &honest);
    assert_eq!(o.code, 0, "an honest dump: {}", o.stderr);
    assert!(honest.join("dem.csv").is_file() && honest.join("run-001/result.json").is_file());
    for (hostile, rule) in [
        ("nan", "grain 1: position x is NaN"),
        ("inf", "grain 1: position y is inf"),
        ("negative-mass", "grain 1: mass -"),
        ("heavy", "is not the"),
        ("duplicate-id", "grain 1: the id appears twice"),
        ("huge-id", "grain 1000000000000000000: the id is not one of the placed grains' (1..=20)"),
        ("outside", "lies outside the case's box"),
        ("stroke-nan", "the stroke time at the end of the run is NaN s"),
        ("stroke-inf", "the stroke time at the end of the run is inf s"),
        ("stroke-negative", "the stroke time at the end of the run is -1 s"),
    ] {
        let out = campaign(hostile);
        let o = run(hostile, &out);
        assert_eq!(o.code, 2, "{hostile}: exit {}\n{}", o.code, o.stderr);
        assert!(!o.stderr.contains("panicked"), "{hostile}: {}", o.stderr);
        assert!(o.stderr.contains(rule) && o.stderr.contains("not a believable run"), "{hostile}: {}", o.stderr);
        assert!(!o.stdout.contains("d_avg"), "{hostile} printed a comparison: {}", o.stdout);
        let rd = out.join("run-001");
        assert!(!rd.join("result.json").exists() && !out.join("dem.csv").exists(), "{hostile}: a result was kept");
        assert!(rd.join("final.dump").is_file(), "{hostile}: the run's folder was not kept for inspection");
        let reason = std::fs::read_to_string(rd.join("failure.txt")).unwrap();
        assert!(reason.contains(rule), "{hostile}: failure.txt says {reason}");
        // the same command tries the seed again; an honest engine now finishes it
        let o = run("", &out);
        assert_eq!(o.code, 0, "{hostile}, rerun: {}", o.stderr);
        assert!(!rd.join("failure.txt").exists() && rd.join("result.json").is_file());
    }
}

/// Issue 45, 1: an edited result.json or plan.json of a DEM campaign is refused naming the
/// file and its field: no "NaN ± NaN", no panic on a longer `teeth_g` (dem/compare.rs), no
/// hang on `"runs": 4294967295`, no `[dem] particles = 0`.
#[test]
fn edited_dem_results_and_plans_are_refused_by_field() {
    let d = tempfile::tempdir().unwrap();
    let fake = fake_liggghts(d.path());
    let out = d.path().join("dem");
    let o = with_fake_engine(
        &fake,
        "",
        &[
            "dem",
            "run",
            "--config",
            RIG,
            "--particles",
            "20",
            "--runs",
            "2",
            "--jobs",
            "1",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let compare = || sawtooth_in(repo(), &["dem", "compare", out.to_str().unwrap()]);
    let ok = compare();
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    let result = out.join("run-002/result.json");
    let good: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&result).unwrap()).unwrap();
    let teeth = good["teeth_g"].as_array().unwrap().len();
    let edits: Vec<(&str, JsonEdit)> = vec![
        ("`teeth_g[0]` is -1.0 g", Box::new(|v| v["teeth_g"][0] = (-1.0).into())),
        ("`teeth_g` holds 0 teeth", Box::new(|v| v["teeth_g"] = serde_json::json!([]))),
        ("`teeth_g` adds up to 1e308 g", Box::new(|v| v["teeth_g"][0] = 1e308.into())),
        ("holds 9 teeth", Box::new(|v| v["teeth_g"] = serde_json::Value::from(vec![0.001; 9]))),
        ("`input_mass_g` 0.0 is not", Box::new(|v| v["input_mass_g"] = 0.0.into())),
        ("`input_mass_g` -1.0 is not", Box::new(|v| v["input_mass_g"] = (-1.0).into())),
        ("`lost` 50 exceeds `grains` 20", Box::new(|v| v["lost"] = 50.into())),
        ("`seed` 99 is not run 2's seed 1", Box::new(|v| v["seed"] = 99.into())),
        ("`d_avg_m`", Box::new(|v| v["d_avg_m"] = 1e308.into())),
    ];
    assert!(teeth != 9, "the edit that lengthens teeth_g must lengthen it");
    each_edit_is_refused(&result, &good, edits, "run-002/result.json", &compare);
    std::fs::write(&result, serde_json::to_string(&good).unwrap()).unwrap();
    let plan_path = out.join("plan.json");
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan_path).unwrap()).unwrap();
    let edits: Vec<(&str, JsonEdit)> = vec![
        ("`runs` must lie in [1, 10000]", Box::new(|v| v["runs"] = 4_294_967_295u64.into())),
        ("[dem] particles (--particles) must lie in [1, 200000]", Box::new(|v| v["settings"]["particles"] = 0.into())),
        ("`environment.g` must lie in [0.001, 100]", Box::new(|v| v["scenario"]["environment"]["g"] = 1e-300.into())),
        ("`first_seed`", Box::new(|v| v["first_seed"] = u64::MAX.into())),
        ("`strokes` must lie in [3, 200]", Box::new(|v| v["strokes"] = 4_294_967_295u64.into())),
        ("`period_teeth` 7 belongs to a steady plan", Box::new(|v| v["period_teeth"] = 7.into())),
        (
            "`period_teeth` must lie in [2, 64]",
            Box::new(|v| {
                v["strokes"] = 5.into();
                v["period_teeth"] = 1000.into()
            }),
        ),
    ];
    each_edit_is_refused(&plan_path, &plan, edits, "plan.json", &compare);
    std::fs::write(&plan_path, serde_json::to_string(&plan).unwrap()).unwrap();
    // a refinement's ladder (refine.json, as `dem run --refine` writes it) is read within its
    // rules: its numerics join the comparison; an edited one is refused by field
    let compared: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compare.json")).unwrap()).unwrap();
    let d_avg = compared["dem_d_avg_mm"]["mean"].as_f64().unwrap();
    let rung = |d: f64, overlap: f64, particles: u32| {
        serde_json::json!({"max_overlap_fraction": overlap, "particles": particles, "dir": ".",
                           "d_avg_mm": d, "d_avg_sd_mm": 0.5, "wall_s": 1.0})
    };
    let ladder = serde_json::json!({"levels": [{
        "base": rung(d_avg, 0.1, 20), "half_overlap": rung(d_avg + 0.2, 0.05, 20),
        "double_grains": rung(d_avg - 0.3, 0.1, 40),
        "overlap_move_mm": 0.2, "grains_move_mm": -0.3, "allowed_mm": 1.0, "converged": true}],
        "converged": true});
    let marker = out.join(".sawtooth-run");
    let m = std::fs::read_to_string(&marker).unwrap();
    std::fs::write(&marker, m.replacen("wrote = [", "wrote = [\"refine.json\", ", 1)).unwrap();
    let refine = out.join("refine.json");
    std::fs::write(&refine, serde_json::to_string(&ladder).unwrap()).unwrap();
    let ok = sawtooth_in(repo(), &["dem", "compare", out.to_str().unwrap(), "--json"]);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    let c: serde_json::Value = serde_json::from_str(&ok.stdout).unwrap();
    assert_eq!(c["numerics_error_mm"].as_f64(), Some(0.3), "{c}");
    assert_eq!(c["numerics"]["double_grains"]["particles"], 40, "{c}");
    let edits: Vec<(&str, JsonEdit)> = vec![
        ("`levels` must hold 1 to 3 levels, got 0", Box::new(|v| v["levels"] = serde_json::json!([]))),
        (
            "levels[0].half_overlap.max_overlap_fraction must lie in (0, 1)",
            Box::new(|v| v["levels"][0]["half_overlap"]["max_overlap_fraction"] = 5.0.into()),
        ),
        ("levels[0]: the moves must be finite", Box::new(|v| v["levels"][0]["allowed_mm"] = (-1.0).into())),
        (
            "levels[0].double_grains.particles must be at least 1",
            Box::new(|v| v["levels"][0]["double_grains"]["particles"] = 0.into()),
        ),
    ];
    each_edit_is_refused(&refine, &ladder, edits, "refine.json", &compare);
}

/// Issue 45, 2: a reader refuses what is not a regular file (a named pipe hung `simulate`,
/// `fit`, `dem write` and `dem check`; a pareto.csv linked to /dev/zero aborted `dem check`),
/// and `--front` has a bound.
#[cfg(unix)]
#[test]
fn readers_refuse_pipes_and_devices_and_front_is_bounded() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("pipe");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let f = fifo.to_str().unwrap();
    let out = d.path().join("out");
    let o = out.to_str().unwrap();
    refused(&["simulate", "--config", f], &["--config", "named pipe (FIFO), not a regular file"]);
    refused(&["fit", "--data", f, "--setup", RIG], &["--data", "named pipe (FIFO)"]);
    refused(&["fit", "--data", "data/validation/test3.csv", "--setup", f], &["named pipe (FIFO)"]);
    refused(&["dem", "write", "--config", f, "--out", o], &["--config", "named pipe (FIFO)"]);
    // a finished optimisation whose pareto.csv is a pipe, then /dev/zero
    let run = d.path().join("run");
    let small = ["--env", "earth", "--pop", "8", "--generations", "1", "--particles", "20", "--final-particles", "20"];
    let mut args = vec!["optimize", "--quiet", "--out", run.to_str().unwrap()];
    args.extend(small);
    let ok = sawtooth_in(repo(), &args);
    assert_eq!(ok.code, 0, "{}", ok.stderr);
    std::fs::remove_file(run.join("pareto.csv")).unwrap();
    std::os::unix::fs::symlink(&fifo, run.join("pareto.csv")).unwrap();
    let check = |extra: &[&str]| {
        let mut a = vec!["dem", "check", run.to_str().unwrap(), "--plan", "--out", o];
        a.extend_from_slice(extra);
        a.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let args = check(&[]);
    refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), &["pareto.csv", "named pipe (FIFO)"]);
    if Path::new("/dev/zero").exists() {
        std::fs::remove_file(run.join("pareto.csv")).unwrap();
        std::os::unix::fs::symlink("/dev/zero", run.join("pareto.csv")).unwrap();
        refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), &["pareto.csv", "character device"]);
    }
    for front in ["4294967295", "18446744073709551615"] {
        let args = check(&["--front", front]);
        refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), &["--front", "[0, 100]"]);
    }
    for (flag, bound) in [("--jobs", "[1, 4096]"), ("--seeds", "[1, 1000]"), ("--particles", "[1, 200000]")] {
        let args = check(&[flag, "0"]);
        refused(&args.iter().map(String::as_str).collect::<Vec<_>>(), &[flag, bound]);
    }
    assert!(!out.exists(), "a refused command made its --out");
}

/// The files of `dir`, sorted (nothing, when it does not exist).
fn names_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map(|r| r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect())
        .unwrap_or_default();
    v.sort();
    v
}

/// Issue 45, 3: nothing is written into a folder the run does not own, not even a lock file:
/// a forged old-style marker beside a user's pareto.csv, an `--out` linked to a user's folder
/// (every command that owns one), a campaign member's folder linked outside; and a killed
/// DEM check's stale temporary file is gone after the rerun.
#[cfg(unix)]
#[test]
fn nothing_is_written_into_a_folder_the_run_does_not_own() {
    let d = tempfile::tempdir().unwrap();
    let small = [
        "--env",
        "earth",
        "--pop",
        "8",
        "--generations",
        "1",
        "--particles",
        "20",
        "--final-particles",
        "20",
        "--replicates",
        "1",
        "--quiet",
    ];
    // a forged marker in the format of older versions, and the user's front
    let forged = d.path().join("forged");
    std::fs::create_dir(&forged).unwrap();
    std::fs::write(forged.join(".sawtooth-run"), "optimize\n").unwrap();
    std::fs::write(forged.join("pareto.csv"), "mine\n").unwrap();
    for resume in [false, true] {
        let mut args = with(&["optimize", "--out", forged.to_str().unwrap()], &small);
        if resume {
            args.push("--resume");
        }
        let o = sawtooth_in(repo(), &args);
        assert_eq!(o.code, 2, "resume {resume}: {}", o.stderr);
        assert_eq!(std::fs::read_to_string(forged.join("pareto.csv")).unwrap(), "mine\n");
        assert_eq!(names_in(&forged), [".sawtooth-run", "pareto.csv"], "resume {resume}");
    }
    // an --out linked to a user's folder: refused, and no lock file left there
    let user = d.path().join("user");
    std::fs::create_dir(&user).unwrap();
    std::fs::write(user.join("notes.txt"), "mine\n").unwrap();
    let link = d.path().join("link");
    std::os::unix::fs::symlink(&user, &link).unwrap();
    let l = link.to_str().unwrap();
    let commands: Vec<Vec<&str>> = vec![
        with(&["optimize", "--out", l], &small),
        with(&["fit", "--out", l, "--pop", "5", "--generations", "1", "--polish", "0", "--bootstrap", "0"], &TEST3),
        with(&["diagnose", "--out", l, "--pop", "5", "--generations", "1", "--polish", "0"], &TEST3),
        with(&["gpu-sweep", "--alpha", "10..11", "--plan", "--out", l], &small),
        with(&["study", "repeatability", "--runs", "2", "--plan", "--out", l], &small),
        vec!["dem", "write", "--config", RIG, "--particles", "20", "--out", l],
    ];
    for args in &commands {
        let o = sawtooth_in(repo(), args);
        assert_eq!(o.code, 2, "{args:?}: {}", o.stderr);
        assert!(o.stderr.contains("not a folder of sawtooth's"), "{args:?}: {}", o.stderr);
        assert_eq!(names_in(&user), ["notes.txt"], "{args:?} wrote into the user's folder");
    }
    // a campaign's member folder linked outside: refused by name, nothing written there
    let camp = d.path().join("camp");
    let o = sawtooth_in(
        repo(),
        &with(&["gpu-sweep", "--alpha", "10..11", "--plan", "--out", camp.to_str().unwrap()], &small),
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(camp.join("plan.json")).unwrap()).unwrap();
    let member = plan["members"][0]["dir"].as_str().unwrap().to_string();
    let outside = d.path().join("outside");
    std::fs::create_dir(&outside).unwrap();
    std::os::unix::fs::symlink(&outside, camp.join(&member)).unwrap();
    let o = sawtooth_in(repo(), &["campaign", "run", camp.to_str().unwrap(), "--task", "0"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains("is a link to") && o.stderr.contains(&member), "{}", o.stderr);
    let o = sawtooth_in(repo(), &["campaign", "run", camp.to_str().unwrap(), "--task", "1"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(o.stderr.contains(&member), "{}", o.stderr);
    assert!(names_in(&outside).is_empty(), "a task wrote outside its campaign: {:?}", names_in(&outside));

    // a DEM check killed while it wrote a case: its temporary file goes when the member runs again
    let run = d.path().join("run");
    let o = sawtooth_in(repo(), &with(&["optimize", "--out", run.to_str().unwrap()], &small));
    assert_eq!(o.code, 0, "{}", o.stderr);
    let chk = d.path().join("chk");
    let o = sawtooth_in(
        repo(),
        &[
            "dem",
            "check",
            run.to_str().unwrap(),
            "--front",
            "0",
            "--seeds",
            "1",
            "--particles",
            "20",
            "--plan",
            "--out",
            chk.to_str().unwrap(),
        ],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(chk.join("plan.json")).unwrap()).unwrap();
    let label = plan["finalists"][0]["label"].as_str().unwrap().to_string();
    // a first attempt leaves the member's folders as a killed one does (marked, a case in
    // them); its temporary file is what a kill during the case's writing leaves
    let fake = fake_liggghts(d.path());
    let o = with_fake_engine(&fake, "nan", &["campaign", "run", chk.to_str().unwrap(), "--task", "0"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    let rd = chk.join(&label).join("run-001");
    let stale = rd.join(".sled.stl.Xy12Ab.sawtooth-tmp");
    std::fs::write(&stale, "torn").unwrap();
    let o = with_fake_engine(&fake, "", &["campaign", "run", chk.to_str().unwrap(), "--task", "0"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    assert!(!stale.exists(), "the stale temporary file of the killed run is still there");
    assert!(rd.join("result.json").is_file());
}

/// Issue 45, 4: values that mean nothing are refused by name (1e-300 inside an open lower
/// bound, 1e308, an edited checkpoint, a member folder with a newline or NUL); values that do
/// mean something work (δ = −1, 0 or 1e-320: δ is the offset added to the launch angle, and
/// Table 5.1's lower bound is 0).
#[test]
fn values_that_mean_nothing_are_refused_by_name() {
    let d = tempfile::tempdir().unwrap();
    let lunar_c = |delta: &str, v0: &str| format!("47.346,46.898,32.183,43.687,94.42,{delta},{v0},32.051");
    for delta in ["-1", "0", "1e-320"] {
        let o = sawtooth_in(
            repo(),
            &["simulate", "--env", "lunar", "--design", &lunar_c(delta, "0.840"), "--particles", "20"],
        );
        assert_eq!(o.code, 0, "delta {delta}: {}", o.stderr);
    }
    refused(
        &["simulate", "--env", "lunar", "--design", &lunar_c("11.964", "1e-320")],
        &["design field `v0`", "[0.01, 100] m/s", "1e-320"],
    );
    let config = |name: &str, text: &str| {
        let p = d.path().join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    for (text, names) in [
        ("[environment]\ng_m_s2 = 1e-300\n", &["`[environment] g_m_s2`", "[0.001, 100] m/s^2"][..]),
        ("[material]\nbulk_density_kg_m3 = 1e-300\n", &["`[material] bulk_density_kg_m3`", "[1, 25000]"][..]),
        ("[performance]\nsled_width_m = 1e-300\n", &["`[performance] sled_width_m`", "[0.001, 100] m"][..]),
        ("[performance]\nf_max_hz = 1e-300\n", &["`[performance] f_max_hz`", "[1e-4, 10000] Hz"][..]),
    ] {
        let c = config("c.toml", &format!("env = \"lunar\"\n{text}"));
        refused(&["simulate", "--config", &c, "--design", &lunar_c("11.964", "0.840")], names);
    }
    let setup = std::fs::read_to_string(repo().join(RIG)).unwrap();
    for key in ["scale_resolution_g", "particle_mass_g"] {
        let edited: String = setup
            .lines()
            .map(|l| if l.starts_with(key) { format!("{key} = 1e308") } else { l.to_string() })
            .collect::<Vec<_>>()
            .join("\n");
        let s = config("setup.toml", &edited);
        for cmd in ["fit", "diagnose"] {
            refused(
                &[cmd, "--data", "data/validation/test3.csv", "--setup", &s, "--out", "/nonexistent/x"],
                &[&format!("measurement.{key} must lie in"), "1e308"],
            );
        }
    }
    refused(
        &["synth", "--setup", RIG, "--resolution-g", "1e308", "--out", "/nonexistent/s.csv"],
        &["--resolution-g", "[1e-15, 1000] g"],
    );
    refused(
        &["study", "repeatability", "--target-mass-flow", "1e308", "--plan", "--out", "/nonexistent/st"],
        &["--target-mass-flow", "[1e-6, 100] kg/s"],
    );

    // a checkpoint whose objectives or variables the solver never makes
    let run = d.path().join("run");
    let small = [
        "--env",
        "earth",
        "--pop",
        "8",
        "--generations",
        "1",
        "--particles",
        "20",
        "--final-particles",
        "20",
        "--quiet",
    ];
    let o = sawtooth_in(repo(), &with(&["optimize", "--out", run.to_str().unwrap()], &small));
    assert_eq!(o.code, 0, "{}", o.stderr);
    let ck = run.join("checkpoint.json");
    let good: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&ck).unwrap()).unwrap();
    let edits: Vec<(&str, JsonEdit)> = vec![
        (
            "`population[0].eval.objectives[0]` is -1e308",
            Box::new(|v| v["population"][0]["eval"]["objectives"] = serde_json::json!(["-1e308", "NaN"])),
        ),
        (
            "`population[0].eval.objectives[1]` is NaN",
            Box::new(|v| v["population"][0]["eval"]["objectives"][1] = "NaN".into()),
        ),
        ("`population[0].x[0]` is 1e308", Box::new(|v| v["population"][0]["x"][0] = "1e308".into())),
    ];
    for (want, edit) in edits {
        let mut v = good.clone();
        edit(&mut v);
        std::fs::write(&ck, serde_json::to_string(&v).unwrap()).unwrap();
        refused(&["optimize", "--out", run.to_str().unwrap(), "--resume", "--quiet"], &[want, "checkpoint.json"]);
    }

    // a campaign member's folder with a newline or NUL in its name
    let camp = d.path().join("camp");
    let o = sawtooth_in(
        repo(),
        &with(&["gpu-sweep", "--alpha", "10..11", "--plan", "--out", camp.to_str().unwrap()], &small),
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let plan_path = camp.join("plan.json");
    let plan: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&plan_path).unwrap()).unwrap();
    for dir in ["alpha\n010", "alpha\u{0}010", "../outside", ".hidden"] {
        let mut v = plan.clone();
        v["members"][0]["dir"] = dir.into();
        std::fs::write(&plan_path, serde_json::to_string(&v).unwrap()).unwrap();
        for sub in [&["status"][..], &["slurm"][..], &["run", "--task", "0"][..]] {
            let mut args = vec!["campaign", sub[0], camp.to_str().unwrap()];
            args.extend_from_slice(&sub[1..]);
            refused(&args, &["member 0", "`dir`", "plain folder name"]);
        }
    }
}

/// Issue 45, 5: `fit --at` on a DEM campaign of two seeds scores both (the default holdout of
/// three runs did not fit the data); a plain fit on two runs holds one out; `dem run --help`
/// names `--particles` as the DEM's grains with the DEM's default.
#[test]
fn fit_fits_small_campaigns_and_dem_help_names_its_grains() {
    let d = tempfile::tempdir().unwrap();
    let fake = fake_liggghts(d.path());
    let out = d.path().join("dem");
    let o = with_fake_engine(
        &fake,
        "",
        &[
            "dem",
            "run",
            "--config",
            RIG,
            "--particles",
            "20",
            "--runs",
            "2",
            "--jobs",
            "1",
            "--out",
            out.to_str().unwrap(),
        ],
    );
    assert_eq!(o.code, 0, "{}", o.stderr);
    let (data, setup) = (out.join("dem.csv"), out.join("setup.toml"));
    let fit = |extra: &[&str]| {
        let mut a = vec!["fit", "--data", data.to_str().unwrap(), "--setup", setup.to_str().unwrap(), "--json"];
        a.extend_from_slice(&["--particles", "200", "--bootstrap", "0"]);
        a.extend_from_slice(extra);
        sawtooth_in(repo(), &a)
    };
    let o = fit(&["--at", "k_elastic=0.8"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    assert!(v["objective"].is_number() || v["sse_percent2"].is_number(), "{v}");
    let o = fit(&["--pop", "5", "--generations", "1", "--polish", "0"]);
    assert_eq!(o.code, 0, "{}", o.stderr);
    let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
    assert_eq!(v["settings"]["holdout"], 1, "{}", v["settings"]);
    let o = fit(&["--holdout", "3"]);
    assert_eq!(o.code, 2, "{}", o.stderr);
    assert!(
        o.stderr.contains("--holdout must be < the number of runs") && o.stderr.contains("hold out at most 1"),
        "{}",
        o.stderr
    );

    let o = sawtooth_in(repo(), &["dem", "run", "--help"]);
    assert_eq!(o.code, 0);
    let help = o.stdout.split("--particles").nth(1).unwrap_or_default();
    assert!(help.contains("DEM grains per run") && help.contains("[dem] particles, else 600]"), "{}", o.stdout);
}
