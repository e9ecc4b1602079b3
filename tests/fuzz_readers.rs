//! Fuzzing every reader of user input (issue 34) with proptest at scale: cargo-fuzz needs a
//! nightly toolchain this project cannot install, so each reader gets a mutation fuzzer
//! built from proptest strategies over a committed corpus (tests/fuzz/corpus/KIND/): the
//! TOML config, the setup, the measured-data CSV, the campaign plan and the checkpoint, the
//! DEM's readers (a DEM campaign's and a DEM check's plan.json, a run's result.json and the
//! engine's dump) and an optimisation's pareto.csv, and random designs through design
//! validation and preparation. Every case must end as a
//! value or an error: a panic fails the test (proptest shrinks it and records its seed under
//! tests/fuzz/regressions/, replayed first on every later run), an abort kills it (the
//! address space is capped, so an unbounded allocation aborts instead of swapping), and a
//! watchdog aborts the process when one case runs past `CASE_LIMIT` (a hang).
//!
//! Normal test runs do `FUZZ_CASES` (default 2000) cases per reader; the long run of
//! docs/reliability.md is `FUZZ_CASES=1000000 cargo test --release --locked --test
//! fuzz_readers -- --nocapture --test-threads 1`, printing cases per second per reader.
//! `FUZZ_SEED` (a number) varies the stream of cases; the default is fixed, so a failure
//! in CI is the same failure on a laptop.

use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Once;
use std::time::{Duration, Instant};

use proptest::prelude::*;
use proptest::test_runner::{Config, FileFailurePersistence, RngAlgorithm, TestRng, TestRunner};
use serde_json::Value;

use sawtooth::campaigns::plan::parse_plan;
use sawtooth::dem::campaign::{parse_plan as parse_dem_plan, Plan as DemPlan};
use sawtooth::dem::check::parse_plan as parse_check_plan;
use sawtooth::dem::gather::{check_dump, check_result, parse_dump, reduce, DumpGrain, RunResult};
use sawtooth::dem::losses::{classify, last_seen};
use sawtooth::dem::sizes::grain_mass;
use sawtooth::dem::Case;
use sawtooth::io::config::ConfigFile;
use sawtooth::io::measured;
use sawtooth::model::design::{LOWER_BOUND_CLI, UPPER_BOUND_CLI};
use sawtooth::model::prepare::prepare;
use sawtooth::model::{Design, Scenario};
use sawtooth::optim::checkpoint::{validate_state, Shape};
use sawtooth::optim::front::{parse_pareto_csv, picks};
use sawtooth::optim::test_problems::Zdt1;
use sawtooth::optim::{Mode, Nsga2, State};

/// One case running longer than this is a hang: the watchdog aborts the process.
const CASE_LIMIT: Duration = Duration::from_secs(30);
/// Address space of the fuzzing process: an input that made a reader allocate without
/// bound aborts here instead of taking the machine's memory.
const ADDRESS_SPACE_BYTES: u64 = 8 << 30;

fn cases() -> u32 {
    std::env::var("FUZZ_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(2000)
}

fn runner(target: &str) -> TestRunner {
    let seed: u64 = std::env::var("FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(34);
    let mut bytes = [0u8; 32];
    bytes[..8].copy_from_slice(&seed.to_le_bytes());
    for (i, b) in target.bytes().enumerate() {
        bytes[8 + i % 24] ^= b;
    }
    let config = Config {
        cases: cases(),
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(Box::leak(
            format!("tests/fuzz/regressions/{target}.txt").into_boxed_str(),
        )))),
        max_shrink_iters: 2000,
        ..Config::default()
    };
    TestRunner::new_with_rng(config, TestRng::from_seed(RngAlgorithm::ChaCha, &bytes))
}

static CASE_STARTED_MS: AtomicU64 = AtomicU64::new(0);
static GUARDS: Once = Once::new();

fn now_ms() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap().as_millis() as u64
}

/// The memory cap and the hang watchdog, once per process.
fn guards() {
    GUARDS.call_once(|| {
        #[cfg(target_os = "linux")]
        {
            #[repr(C)]
            struct Rlimit {
                cur: u64,
                max: u64,
            }
            extern "C" {
                fn setrlimit(resource: i32, rlim: *const Rlimit) -> i32;
            }
            const RLIMIT_AS: i32 = 9;
            // SAFETY: a plain system call on a stack value.
            let rc = unsafe { setrlimit(RLIMIT_AS, &Rlimit { cur: ADDRESS_SPACE_BYTES, max: ADDRESS_SPACE_BYTES }) };
            assert_eq!(rc, 0, "setrlimit");
        }
        std::thread::spawn(|| loop {
            std::thread::sleep(Duration::from_millis(500));
            let started = CASE_STARTED_MS.load(Ordering::Relaxed);
            if started != 0 && now_ms().saturating_sub(started) > CASE_LIMIT.as_millis() as u64 {
                eprintln!("fuzz: one case ran past {CASE_LIMIT:?}: a hang; aborting");
                std::process::abort();
            }
        });
    });
}

fn corpus(kind: &str) -> Vec<String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz/corpus").join(kind);
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    let texts: Vec<String> = files.iter().map(|p| std::fs::read_to_string(p).unwrap()).collect();
    assert!(!texts.is_empty(), "no corpus in {}", dir.display());
    texts
}

/// Tokens a mutation inserts or substitutes: the values at and past every bound, the
/// syntax of the formats, and text no reader expects.
const TOKENS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "2",
    "0.5",
    "1e308",
    "-1e308",
    "1e-320",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "4294967295",
    "4294967296",
    "18446744073709551615",
    "18446744073709551616",
    "1e12",
    "999999",
    "\"\"",
    "\"x\"",
    "[]",
    "{}",
    "[[]]",
    "true",
    "null",
    "\n",
    "\r",
    "\r\n",
    "=",
    "[",
    "]",
    ",",
    ",,",
    "\"",
    "#",
    ".",
    "..",
    "[sim]",
    "[performance]",
    "[design]",
    "[environment]",
    "[effects.quadratic_drag]",
    "[requirements]",
    "[measurement]",
    "particles = 4294967295",
    "teeth = 0",
    "max_bounces = 100000000",
    "k_drag_per_s = -1",
    "conveyor_length_m = 1e308",
    "contraction_ratio = 2",
    "env = \"mars\"",
    "mode = \"listing\"",
    "input_mass",
    "tooth_1",
    "tooth_0",
    "run",
    "\u{feff}",
    "é",
    "\u{0}",
    "\t",
    " ",
    "1,2,3,4,5,6,7,8",
    "'",
    "\\",
];

#[derive(Debug, Clone)]
enum Edit {
    Insert { at: u32, token: usize },
    Delete { at: u32, len: u8 },
    Replace { at: u32, len: u8, token: usize },
    DuplicateLine { line: u16 },
    DropLine { line: u16 },
    Free { at: u32, text: String },
}

fn edit() -> impl Strategy<Value = Edit> {
    let t = 0..TOKENS.len();
    prop_oneof![
        (any::<u32>(), t.clone()).prop_map(|(at, token)| Edit::Insert { at, token }),
        (any::<u32>(), any::<u8>()).prop_map(|(at, len)| Edit::Delete { at, len }),
        (any::<u32>(), 0u8..12, t).prop_map(|(at, len, token)| Edit::Replace { at, len, token }),
        any::<u16>().prop_map(|line| Edit::DuplicateLine { line }),
        any::<u16>().prop_map(|line| Edit::DropLine { line }),
        (any::<u32>(), "\\PC{0,12}").prop_map(|(at, text)| Edit::Free { at, text }),
    ]
}

/// The char boundary at or before `at % (len + 1)`.
fn boundary(s: &str, at: u32) -> usize {
    let mut i = at as usize % (s.len() + 1);
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn apply(mut s: String, edits: &[Edit]) -> String {
    for e in edits {
        match e {
            Edit::Insert { at, token } => {
                let i = boundary(&s, *at);
                s.insert_str(i, TOKENS[*token]);
            }
            Edit::Delete { at, len } => {
                let i = boundary(&s, *at);
                let mut j = (i + *len as usize).min(s.len());
                while !s.is_char_boundary(j) {
                    j -= 1;
                }
                s.replace_range(i..j.max(i), "");
            }
            Edit::Replace { at, len, token } => {
                let i = boundary(&s, *at);
                let mut j = (i + *len as usize).min(s.len());
                while !s.is_char_boundary(j) {
                    j -= 1;
                }
                s.replace_range(i..j.max(i), TOKENS[*token]);
            }
            Edit::DuplicateLine { line } | Edit::DropLine { line } => {
                let mut lines: Vec<&str> = s.split('\n').collect();
                let k = *line as usize % lines.len();
                if matches!(e, Edit::DuplicateLine { .. }) {
                    lines.insert(k, lines[k]);
                } else {
                    lines.remove(k);
                }
                s = lines.join("\n");
            }
            Edit::Free { at, text } => {
                let i = boundary(&s, *at);
                s.insert_str(i, text);
            }
        }
    }
    s
}

/// A corpus text with 0-8 edits, or (one case in eight) text from scratch.
fn mutated_text(corpus: Vec<String>) -> impl Strategy<Value = String> {
    let n = corpus.len();
    prop_oneof![
        7 => (0..n, proptest::collection::vec(edit(), 0..8)).prop_map(move |(i, edits)| apply(corpus[i].clone(), &edits)),
        1 => "\\PC{0,200}",
    ]
}

/// A JSON value at and past every bound, or of the wrong kind.
fn hostile_json() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::Bool),
        prop_oneof![Just(0u64), Just(1), Just(4294967295), Just(u64::MAX), any::<u64>()].prop_map(Value::from),
        prop_oneof![Just(-1i64), Just(i64::MIN), any::<i64>()].prop_map(Value::from),
        prop_oneof![Just(1e308), Just(-1e308), Just(1e-320), Just(0.5), any::<f64>()]
            .prop_map(|f| serde_json::Number::from_f64(f).map_or(Value::Null, Value::Number)),
        prop_oneof![
            Just("inf"),
            Just("NaN"),
            Just("-inf"),
            Just("1e999"),
            Just(""),
            Just("cpu"),
            Just("gpu"),
            Just("../x"),
            Just("/abs")
        ]
        .prop_map(|s| Value::String(s.into())),
        Just(Value::Array(Vec::new())),
        Just(serde_json::json!({})),
    ]
}

#[derive(Debug, Clone)]
enum JsonEdit {
    Set { path: u32, value: Value },
    Remove { path: u32 },
    Truncate { path: u32, len: u8 },
    Repeat { path: u32, times: u8 },
}

fn json_edit() -> impl Strategy<Value = JsonEdit> {
    prop_oneof![
        4 => (any::<u32>(), hostile_json()).prop_map(|(path, value)| JsonEdit::Set { path, value }),
        1 => any::<u32>().prop_map(|path| JsonEdit::Remove { path }),
        1 => (any::<u32>(), any::<u8>()).prop_map(|(path, len)| JsonEdit::Truncate { path, len }),
        1 => (any::<u32>(), 0u8..4).prop_map(|(path, times)| JsonEdit::Repeat { path, times }),
    ]
}

/// Every JSON pointer in `v`.
fn pointers(v: &Value, at: String, out: &mut Vec<String>) {
    out.push(at.clone());
    match v {
        Value::Object(m) => m.iter().for_each(|(k, c)| pointers(c, format!("{at}/{k}"), out)),
        Value::Array(a) => a.iter().enumerate().for_each(|(i, c)| pointers(c, format!("{at}/{i}"), out)),
        _ => {}
    }
}

fn apply_json(mut v: Value, edits: &[JsonEdit]) -> Value {
    for e in edits {
        let mut ps = Vec::new();
        pointers(&v, String::new(), &mut ps);
        let pick = |p: u32| ps[p as usize % ps.len()].clone();
        match e {
            JsonEdit::Set { path, value } => {
                if let Some(t) = v.pointer_mut(&pick(*path)) {
                    *t = value.clone();
                }
            }
            JsonEdit::Remove { path } => {
                let p = pick(*path);
                if let Some((parent, key)) = p.rsplit_once('/') {
                    match v.pointer_mut(parent) {
                        Some(Value::Object(m)) => drop(m.remove(key)),
                        Some(Value::Array(a)) => {
                            if let Ok(i) = key.parse::<usize>() {
                                if i < a.len() {
                                    a.remove(i);
                                }
                            }
                        }
                        _ => {}
                    }
                }
            }
            JsonEdit::Truncate { path, len } => {
                if let Some(Value::Array(a)) = v.pointer_mut(&pick(*path)) {
                    a.truncate(*len as usize % (a.len() + 1));
                }
            }
            JsonEdit::Repeat { path, times } => {
                if let Some(Value::Array(a)) = v.pointer_mut(&pick(*path)) {
                    if let Some(first) = a.first().cloned() {
                        for _ in 0..*times {
                            a.push(first.clone());
                        }
                    }
                }
            }
        }
    }
    v
}

/// A corpus document with 0-6 structural edits, or (one case in eight) its text mutated.
fn mutated_json(corpus: Vec<String>) -> impl Strategy<Value = String> {
    let docs: Vec<Value> = corpus.iter().map(|t| serde_json::from_str(t).unwrap()).collect();
    let n = docs.len();
    prop_oneof![
        7 => (0..n, proptest::collection::vec(json_edit(), 0..6))
            .prop_map(move |(i, edits)| apply_json(docs[i].clone(), &edits).to_string()),
        1 => mutated_text(corpus),
    ]
}

/// Run `target`'s `check` on every case; report cases per second and how many inputs were
/// accepted, so a fuzzer that only ever meets parse errors shows itself.
fn fuzz<S: Strategy>(target: &str, strategy: S, check: impl Fn(&S::Value) -> bool)
where
    S::Value: std::fmt::Debug,
{
    guards();
    let accepted = AtomicU64::new(0);
    let total = AtomicU64::new(0);
    let started = Instant::now();
    let result = runner(target).run(&strategy, |input| {
        CASE_STARTED_MS.store(now_ms(), Ordering::Relaxed);
        total.fetch_add(1, Ordering::Relaxed);
        if check(&input) {
            accepted.fetch_add(1, Ordering::Relaxed);
        }
        CASE_STARTED_MS.store(0, Ordering::Relaxed);
        Ok(())
    });
    let secs = started.elapsed().as_secs_f64();
    let (n, ok) = (total.load(Ordering::Relaxed), accepted.load(Ordering::Relaxed));
    eprintln!(
        "fuzz {target}: {n} cases in {secs:.1} s ({:.0} cases/s), {ok} accepted, {} refused, no panic/abort/hang",
        n as f64 / secs,
        n - ok
    );
    if let Err(e) = result {
        panic!("fuzz {target}: {e}");
    }
    assert!(ok > 0 || n < 50, "fuzz {target}: no input was ever accepted; the mutations are too coarse");
}

/// The config reader as `--config` uses it: parse, scenario, design, requirements.
fn read_config(text: &str) -> bool {
    let Ok(c) = ConfigFile::parse(text) else { return false };
    let scenario_ok = c.scenario().is_ok_and(|s| s.validate().is_ok());
    let _ = c.design();
    if let Some(r) = &c.requirements {
        let _ = r.requirements("fuzz.toml");
    }
    scenario_ok
}

#[test]
fn fuzz_config() {
    fuzz("config", mutated_text(corpus("config")), |t| read_config(t));
}

/// The setup of `fit`/`diagnose`/`synth`: a config with [measurement] and [design], whose
/// design is then prepared for the scenario (fill area, launch points).
#[test]
fn fuzz_setup() {
    let setups: Vec<String> =
        corpus("config").into_iter().filter(|t| t.contains("[measurement]") || t.contains("[design]")).collect();
    fuzz("setup", mutated_text(setups), |t| {
        let Ok(c) = ConfigFile::parse(t) else { return false };
        let (Ok(s), Some(d)) = (c.scenario(), c.design()) else { return false };
        s.validate().is_ok() && prepare(&s, &d).is_ok()
    });
}

#[test]
fn fuzz_measured_csv() {
    fuzz("measured", mutated_text(corpus("measured")), |t| {
        let Ok(m) = measured::parse(t, "fuzz.csv") else { return false };
        // what `fit` computes from it first
        let _ = (m.mean_fractions(), m.mean_run_fractions(), m.fractions(), m.recovery(), m.std_fractions());
        true
    });
}

#[test]
fn fuzz_plan() {
    fuzz("plan", mutated_json(corpus("plan")), |t| parse_plan(t, "plan.json").is_ok());
}

/// A checkpoint that passes its rules must also resume: one solver step on it.
#[test]
fn fuzz_checkpoint() {
    let config =
        sawtooth::optim::Config { pop: 8, max_generations: 1_000_000, mode: Mode::Standard, ..Default::default() };
    let shape = Shape::new(8, 2);
    fuzz("checkpoint", mutated_json(corpus("checkpoint")), |t| {
        let Ok(mut state) = serde_json::from_str::<State>(t) else { return false };
        if validate_state(&state, &config, shape).is_err() {
            return false;
        }
        Nsga2::new(config.clone()).step(&mut state, &mut Zdt1 { n: 8 });
        true
    });
}

/// Designs from every corner of f64 through the checks a design meets (`--design`,
/// `[design]`, Python) and, where they pass, preparation.
#[test]
fn fuzz_design() {
    // each variable mostly inside the optimiser's bounds (so that some designs pass and
    // reach preparation), else anywhere in f64 or at its special values
    let coord = |i: usize| {
        prop_oneof![
            4 => LOWER_BOUND_CLI[i]..UPPER_BOUND_CLI[i],
            1 => -10.0f64..200.0,
            1 => any::<f64>(),
            1 => prop_oneof![Just(0.0), Just(-0.0), Just(f64::NAN), Just(f64::INFINITY), Just(1e308), Just(1e-320)],
        ]
    };
    let design = (coord(0), coord(1), coord(2), coord(3), coord(4), coord(5), coord(6), coord(7))
        .prop_map(|(a, b, c, d, e, f, g, h)| [a, b, c, d, e, f, g, h]);
    let scenarios = [Scenario::lunar(), Scenario::earth()];
    fuzz("design", (design, any::<bool>()), |(v, earth)| {
        let d = Design::from_cli_units(*v);
        if d.check_sensible(|i| format!("x{i}")).is_err() {
            return false;
        }
        prepare(&scenarios[*earth as usize], &d).is_ok()
    });
}

/// The case the DEM readers' results and dumps belong to: the first run of the committed DEM
/// campaign plan (tests/fuzz/corpus/dem_plan/, 60 grains of the rig of Test 3).
fn dem_case() -> (DemPlan, Case) {
    parse_dem_plan(&corpus("dem_plan")[0], "plan.json").expect("the committed plan holds")
}

/// The case's grains where they were placed, at rest: what an honest engine could end with.
fn placed_grains(case: &Case) -> Vec<DumpGrain> {
    let rho = case.contact.density_kg_m3;
    case.placement
        .grains
        .iter()
        .enumerate()
        .map(|(i, g)| DumpGrain { id: i as u64 + 1, mass_kg: grain_mass(g.diameter_m, rho), pos: g.pos, vel: [0.0; 3] })
        .collect()
}

/// `grains` as LIGGGHTS's `write_dump ... custom id type diameter mass x y z vx vy vz` writes
/// them (six significant digits).
fn dump_text(case: &Case, grains: &[DumpGrain]) -> String {
    let mut s = format!(
        "ITEM: TIMESTEP\n1\nITEM: NUMBER OF ATOMS\n{}\nITEM: BOX BOUNDS ff ff pp\n0 1\n0 1\n0 1\nITEM: ATOMS id type diameter mass x y z vx vy vz \n",
        grains.len()
    );
    for g in grains {
        let d = case.placement.grains[g.id as usize - 1].diameter_m;
        let n = |v: f64| format!("{:.5e}", v);
        s.push_str(&format!(
            "{} 1 {} {} {} {} {} 0 0 0 \n",
            g.id,
            n(d),
            n(g.mass_kg),
            n(g.pos[0]),
            n(g.pos[1]),
            n(g.pos[2])
        ));
    }
    s
}

/// A DEM campaign's plan.json (`dem run`, `dem compare`): serde, then every rule and the case.
#[test]
fn fuzz_dem_plan() {
    fuzz("dem_plan", mutated_json(corpus("dem_plan")), |t| parse_dem_plan(t, "plan.json").is_ok());
}

/// A DEM check's plan.json (`campaign run/gather/status/slurm` on a check's folder).
#[test]
fn fuzz_dem_check_plan() {
    fuzz("dem_check_plan", mutated_json(corpus("dem_check_plan")), |t| parse_check_plan(t, "plan.json").is_ok());
}

/// A run's result.json, read back against its campaign: a real LIGGGHTS run's (of the case
/// as it was built when the corpus was made) and one reduced from the placed grains, which
/// passes as it is.
#[test]
fn fuzz_dem_result() {
    let (plan, case) = dem_case();
    let honest = reduce(&case, &placed_grains(&case), 0.5, 1.0);
    check_result(&honest, &case, plan.first_seed, 0).expect("the placed grains' result passes");
    let mut docs = corpus("dem_result");
    docs.push(serde_json::to_string_pretty(&honest).unwrap());
    fuzz("dem_result", mutated_json(docs), |t| {
        let Ok(r) = serde_json::from_str::<RunResult>(t) else { return false };
        check_result(&r, &case, plan.first_seed, 0).is_ok()
    });
}

/// The engine's dump, parsed and checked against the case: a real LIGGGHTS dump and one of
/// the placed grains; the latter passes as it is.
#[test]
fn fuzz_dem_dump() {
    let (_, case) = dem_case();
    let placed = dump_text(&case, &placed_grains(&case));
    check_dump(&case, &parse_dump(&placed).unwrap(), Some(0.5)).expect("the placed grains pass");
    let mut docs = corpus("dem_dump");
    docs.push(placed);
    fuzz("dem_dump", mutated_text(docs), |t| {
        let Ok(grains) = parse_dump(t) else { return false };
        check_dump(&case, &grains, Some(0.5)).is_ok()
    });
}

/// A run's track (where the grains LIGGGHTS deleted left): a real LIGGGHTS track cut to the
/// committed case's grains, read line by line, then every grain placed as if deleted.
#[test]
fn fuzz_dem_track() {
    let (_, case) = dem_case();
    let grains = case.placement.grains.len();
    let real = &corpus("dem_track")[0];
    let seen = last_seen(real.as_bytes(), grains).expect("the real track reads");
    assert!(seen.iter().filter(|s| s.is_some()).count() >= 10, "the corpus sights grains");
    fuzz("dem_track", mutated_text(corpus("dem_track")), |t| {
        let Ok(seen) = last_seen(t.as_bytes(), grains) else { return false };
        let by = classify(&case, 0, &seen, &vec![true; grains]);
        assert_eq!(by.total(), grains, "every deleted grain is placed once");
        true
    });
}

/// An optimisation's pareto.csv as `dem check` reads it: parsed, then the picks A, B, C.
#[test]
fn fuzz_pareto() {
    fuzz("pareto", mutated_text(corpus("pareto")), |t| {
        let Ok(front) = parse_pareto_csv(t, "pareto.csv") else { return false };
        let _ = picks(&front);
        !front.is_empty()
    });
}
