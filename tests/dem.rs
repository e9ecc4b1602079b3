//! `sawtooth dem` (issue 31) against the model it bridges to, and with the real engine:
//! LIGGGHTS 3.8 (Debian package `liggghts`, installed by scripts/test.sh). The real-engine
//! tests need a package, so they are the full tier's (plain `cargo test` skips them and says
//! so, also where LIGGGHTS is installed); where LIGGGHTS is missing they skip, except with
//! CI=true, where they FAIL (as tests/gpu_conformance.rs does for a missing Vulkan adapter).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;

use sawtooth::dem::stl::parse_vertices;
use sawtooth::io::config::ConfigFile;
use sawtooth::model::fill::{in_polygon, polygon_area};
use sawtooth::model::geometry::{check_design, Profile};
use sawtooth::model::prepare;

pub(crate) const RIG: &str = "data/validation/test3.toml";

pub(crate) fn sawtooth_env(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sawtooth"));
    c.args(args).current_dir(env!("CARGO_MANIFEST_DIR"));
    for (k, v) in env {
        c.env(k, v);
    }
    let out = c.output().expect("run binary");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

pub(crate) fn sawtooth(args: &[&str]) -> (i32, String, String) {
    sawtooth_env(args, &[])
}

/// True when the full tier runs and LIGGGHTS can run here; with CI=true its absence fails the
/// test instead.
pub(crate) fn liggghts_present(test: &str) -> bool {
    if !common::full_tier(test, "runs LIGGGHTS, a Debian package") {
        return false;
    }
    match sawtooth::dem::run::find_liggghts() {
        Ok(_) => true,
        Err(e) => {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("CI=true but LIGGGHTS is missing: {e:#}");
            }
            eprintln!("skipped: {e:#}");
            false
        }
    }
}

pub(crate) fn tmp(name: &str) -> (tempfile::TempDir, PathBuf) {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(name);
    (d, p)
}

/// The rig at the coarse overlap of 10 % (`[dem] max_overlap_fraction`): a quarter of the
/// default's cost, for tests of the mechanics at CI size (the rig's d_avg is converged there
/// already, docs/dem.md), written into `dir` with `extra` config lines after it.
pub(crate) fn coarse_rig(dir: &Path, extra: &str) -> String {
    let rig = read(&Path::new(env!("CARGO_MANIFEST_DIR")).join(RIG));
    std::fs::create_dir_all(dir).unwrap();
    let p = dir.join("rig-coarse.toml");
    std::fs::write(&p, format!("{rig}\n[dem]\nmax_overlap_fraction = 0.1\n{extra}")).unwrap();
    p.to_str().unwrap().to_string()
}

pub(crate) fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The case's mesh is the model's profile (every tooth's p1, p2, p4 on it, the slab's two
/// faces), and its grains fill the model's fill polygon of tooth 0 with the model's fill mass.
#[test]
fn the_mesh_and_the_grains_are_the_models_geometry_and_fill() {
    let (_d, dir) = tmp("case");
    let (code, out, err) =
        sawtooth(&["dem", "write", "--config", RIG, "--particles", "120", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("120 grains") && out.contains("100.0 % of the model's fill mass"), "{out}");
    let config = ConfigFile::load(Path::new(&format!("{}/{RIG}", env!("CARGO_MANIFEST_DIR")))).unwrap();
    let s = config.scenario().unwrap();
    let design = config.design().unwrap();
    let prep = prepare(&s, &design).unwrap();
    let case: serde_json::Value = serde_json::from_str(&read(&dir.join("case.json"))).unwrap();
    let teeth = case["teeth"].as_u64().unwrap() as u32;
    assert!((2..=s.sim.teeth).contains(&teeth), "{teeth}");
    let depth = case["placement"]["depth_m"].as_f64().unwrap();

    let vertices = parse_vertices(&read(&dir.join("sled.stl")));
    assert!(vertices.iter().all(|v| v[2] == 0.0 || (v[2] - depth).abs() < 1e-12));
    let profile = Profile::new(&design, check_design(&design).unwrap(), s.environment.alpha_deg, teeth);
    let on_mesh = |p: [f64; 2]| vertices.iter().any(|v| (v[0] - p[0]).hypot(v[1] - p[1]) < 1e-9);
    for j in 0..teeth {
        for (name, q) in
            [("p1", profile.p1_of(j)), ("p2", profile.point_of(j, profile.p2)), ("p4", profile.point_of(j, profile.p4))]
        {
            assert!(on_mesh(q), "tooth {j}'s {name} {q:?} is not a mesh vertex");
        }
    }
    let x_max = vertices.iter().map(|v| v[0]).fold(f64::NEG_INFINITY, f64::max);
    assert!((x_max - profile.point_of(teeth - 1, profile.p4)[0]).abs() < 1e-9, "the mesh ends at the last p4");

    // grains: `id type diameter density x y z`, all inside the model's fill polygon
    let data = read(&dir.join("grains.data"));
    let atoms: Vec<Vec<f64>> = data
        .split("Atoms")
        .nth(1)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(atoms.len(), 120);
    let (mut mass, poly) = (0.0, &prep.fill.polygon);
    for a in &atoms {
        assert!(in_polygon([a[4], a[5]], poly), "grain {} at ({}, {}) is outside the fill", a[0], a[4], a[5]);
        mass += a[3] * std::f64::consts::PI * a[2].powi(3) / 6.0;
    }
    let fill_mass = polygon_area(poly) * depth * s.material.bulk_density;
    assert!((mass / fill_mass - 1.0).abs() < 1e-6, "grains {mass} kg vs fill {fill_mass} kg");
    // the script runs the mesh and the grains it was written with
    let script = read(&dir.join("in.sawtooth"));
    for line in [
        "read_data grains.data",
        "fix sled all mesh/surface file sled.stl type 2",
        "move/mesh mesh sled linear/variable",
        "fix drag all viscous",
    ] {
        assert!(script.contains(line), "missing `{line}`");
    }
}

/// Bad input is refused by name with exit status 2, before anything runs.
#[test]
fn designs_and_scenarios_the_mesh_cannot_represent_are_refused_by_name() {
    let (_d, dir) = tmp("case");
    let out = dir.to_str().unwrap();
    for (extra, expected) in [
        (vec!["--compat", "listing"], "listing compatibility mode"),
        (vec!["--effect", "impact-scatter=5"], "effect `impact-scatter` is not carried"),
        (vec!["--design", "20,15,5,16,60,0,1,60"], "r <= l_a"),
        (vec!["--particles", "100000", "--grain-diameter-um", "800"], "cannot seat 100000 grains"),
        (vec!["--grain-diameter-um=-3"], "--grain-diameter-um"),
    ] {
        let mut args = vec!["dem", "write", "--config", RIG, "--out", out];
        args.extend(extra.iter());
        let (code, _, err) = sawtooth(&args);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(err.contains(expected), "{extra:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // a grain stated for one count (a campaign's setup.toml states both) is not silently
    // given to another count: the mass would not be the fill's
    let stated = dir.with_extension("stated.toml");
    let rig = read(std::path::Path::new(RIG));
    std::fs::write(&stated, format!("{rig}\n[dem]\nparticles = 150\ngrain_diameter_m = 5e-4\n")).unwrap();
    let config = stated.to_str().unwrap();
    let (code, _, err) = sawtooth(&["dem", "write", "--config", config, "--particles", "300", "--out", out]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--particles 300 differs from the config's [dem] particles 150"), "{err}");
    assert!(err.contains("grain_diameter_m (0.500 mm)") && err.contains("--grain-diameter-um"), "{err}");
    for fine in [vec!["--particles", "150"], vec!["--particles", "300", "--grain-diameter-um", "400"]] {
        let mut args = vec!["dem", "write", "--config", config, "--out", out];
        args.extend(fine.iter());
        let (code, _, err) = sawtooth(&args);
        assert_eq!(code, 0, "{fine:?}: {err}");
    }
}

/// Without LIGGGHTS the message names the Debian package and the `dem write` alternative.
#[test]
fn a_missing_engine_names_the_package_and_dem_write() {
    let (_d, dir) = tmp("campaign");
    let args = ["dem", "run", "--config", RIG, "--particles", "50", "--runs", "1", "--out", dir.to_str().unwrap()];
    let (code, _, err) = sawtooth_env(&args, &[("PATH", "/nonexistent"), ("SAWTOOTH_LIGGGHTS", "")]);
    // an empty SAWTOOTH_LIGGGHTS names no file
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("liggghts") && err.contains("dem write"), "{err}");
    let (code, _, err) = sawtooth_env(&args, &[("PATH", "/nonexistent")]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("Debian package `liggghts`") && err.contains("dem write"), "{err}");
}

/// A LIGGGHTS error comes back as its log's ERROR line, and the case folder stays.
#[test]
fn an_engine_error_is_its_error_line_and_the_case_is_kept() {
    if !liggghts_present("dem::an_engine_error_is_its_error_line_and_the_case_is_kept") {
        return;
    }
    let (_d, dir) = tmp("case");
    let (code, _, err) =
        sawtooth(&["dem", "write", "--config", RIG, "--particles", "60", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let script =
        read(&dir.join("in.sawtooth")).replace("pair_coeff * *", "pair_coeff * *\nfix broken all no_such_style 1");
    std::fs::write(dir.join("in.sawtooth"), script).unwrap();
    let binary = sawtooth::dem::run::find_liggghts().unwrap();
    let e = sawtooth::dem::run::run_case(&binary, &dir, &mut |_| {}).unwrap_err().to_string();
    assert!(e.contains("ERROR") && e.contains("no_such_style"), "{e}");
    assert!(e.contains("case folder is kept") && dir.join("sled.stl").is_file(), "{e}");
}

/// Fine grains make a thin slab (four diameters deep): the rig at 600 grains is 1.0 mm deep,
/// at 2 400 grains 0.5 mm. With 2 mm facets LIGGGHTS 3.8 stopped at set-up on the 1.0 mm slab
/// (`region_neighbor_list_I.h:165`, issue 42); facets no longer than the depth pass. Set-up
/// only (every `run` made `run 0`): the mesh is read, binned and checked, no step is taken.
#[test]
fn a_thin_slab_of_fine_grains_passes_the_engines_mesh_set_up() {
    if !liggghts_present("dem::a_thin_slab_of_fine_grains_passes_the_engines_mesh_set_up") {
        return;
    }
    let binary = sawtooth::dem::run::find_liggghts().unwrap();
    for particles in ["600", "2400"] {
        let (_d, dir) = tmp("case");
        let (code, _, err) =
            sawtooth(&["dem", "write", "--config", RIG, "--particles", particles, "--out", dir.to_str().unwrap()]);
        assert_eq!(code, 0, "{err}");
        let script: String = read(&dir.join("in.sawtooth"))
            .lines()
            .map(|l| if l.starts_with("run ") { "run 0".to_string() } else { l.to_string() })
            .collect::<Vec<_>>()
            .join("\n");
        std::fs::write(dir.join("in.sawtooth"), script).unwrap();
        let out = Command::new(&binary)
            .args(["-in", "in.sawtooth", "-echo", "none", "-log", "none"])
            .current_dir(&dir)
            .output()
            .expect("run LIGGGHTS");
        let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success() && !text.contains("ERROR"), "{particles} grains: {text}");
        assert!(text.contains(&format!("{particles} atoms")), "{particles} grains: {text}");
    }
}

/// The real engine, CI-sized: grains launched from tooth 0 of the validation rig land in
/// later teeth, with d_avg within the model's order of magnitude; the campaign is measured
/// data `fit` reads; `compare` draws it; the same command again resumes (nothing to do).
#[test]
fn a_real_stroke_lands_grains_in_later_teeth_as_the_model_does() {
    if !liggghts_present("dem::a_real_stroke_lands_grains_in_later_teeth_as_the_model_does") {
        return;
    }
    let (_d, dir) = tmp("campaign");
    let out = dir.to_str().unwrap();
    let config = coarse_rig(&dir.with_extension("cfg"), "");
    let args = ["dem", "run", "--config", &config, "--particles", "100", "--runs", "1", "--jobs", "1", "--out", out];
    let (code, table, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(table.contains("d_avg: model"), "{table}");

    let result: serde_json::Value = serde_json::from_str(&read(&dir.join("run-001/result.json"))).unwrap();
    let teeth_g: Vec<f64> = result["teeth_g"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let loaded = result["input_mass_g"].as_f64().unwrap();
    let later: f64 = teeth_g[1..].iter().sum::<f64>() / loaded;
    assert!(later > 0.3, "only {later} of the mass left tooth 1: {teeth_g:?}");

    let (code, json, err) = sawtooth(&["dem", "compare", out, "--json"]);
    assert_eq!(code, 0, "{err}");
    let c: serde_json::Value = serde_json::from_str(&json).unwrap();
    let (model, dem) = (c["model_d_avg_mm"].as_f64().unwrap(), c["dem_d_avg_mm"]["mean"].as_f64().unwrap());
    assert!(model > 0.0 && dem > model / 3.0 && dem < model * 3.0, "d_avg: model {model} mm, DEM {dem} mm");
    assert!(dir.join("compare.svg").is_file() && dir.join("compare.png").is_file());

    // fit reads the campaign as it reads a rig's
    let csv = dir.join("dem.csv");
    let setup = dir.join("setup.toml");
    let (code, fit, err) = sawtooth(&[
        "fit",
        "--data",
        csv.to_str().unwrap(),
        "--setup",
        setup.to_str().unwrap(),
        "--at",
        "k_elastic=0.854,mu_fric=0.133",
        "--holdout",
        "0",
        "--bootstrap",
        "0",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(fit.contains("\"data\""), "{fit}");

    // the same command again: every run is done, nothing runs
    let (code, _, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("resuming: 1 of 1 runs already done"), "{err}");
}

/// The polydisperse size law in the real engine, CI-sized: the case holds the law's five size
/// classes, each with its own Stokes drag, LIGGGHTS runs it, every grain keeps its class's
/// diameter, the campaign's loaded mass is the grains' mass, grains leave tooth 1, and the
/// setup describes the rig without switching the size law on (what `diagnose` must find).
#[test]
fn a_polydisperse_fill_runs_as_size_classes_with_their_own_drag() {
    if !liggghts_present("dem::a_polydisperse_fill_runs_as_size_classes_with_their_own_drag") {
        return;
    }
    let (_d, dir) = tmp("poly");
    let out = dir.to_str().unwrap();
    let config = coarse_rig(&dir.with_extension("cfg"), "");
    let args = [
        "dem",
        "run",
        "--config",
        &config,
        "--particles",
        "80",
        "--effect",
        "polydisperse=0.3",
        "--runs",
        "1",
        "--jobs",
        "1",
        "--out",
        out,
    ];
    let (code, _, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");

    let script = read(&dir.join("run-001/in.sawtooth"));
    assert_eq!(script.matches(" viscous ").count(), 5, "{script}");
    assert_eq!(script.matches("group size").count(), 5, "{script}");
    let case: serde_json::Value = serde_json::from_str(&read(&dir.join("run-001/case.json"))).unwrap();
    let classes = case["placement"]["classes"].as_array().unwrap();
    let class_d: Vec<f64> = classes.iter().map(|c| c["diameter_m"].as_f64().unwrap()).collect();
    let dump = read(&dir.join("run-001/final.dump"));
    let atoms: Vec<Vec<f64>> = dump
        .lines()
        .skip_while(|l| !l.starts_with("ITEM: ATOMS"))
        .skip(1)
        .map(|l| l.split_whitespace().map(|f| f.parse().unwrap()).collect())
        .collect();
    assert!(!atoms.is_empty());
    // columns: id type diameter mass ...; every grain's diameter is one of the classes'
    for a in &atoms {
        assert!(class_d.iter().any(|d| (a[2] / d - 1.0).abs() < 1e-6), "diameter {} not a class's: {class_d:?}", a[2]);
    }
    let sizes_seen = class_d.iter().filter(|d| atoms.iter().any(|a| (a[2] / **d - 1.0).abs() < 1e-6)).count();
    assert_eq!(sizes_seen, 5);

    let result: serde_json::Value = serde_json::from_str(&read(&dir.join("run-001/result.json"))).unwrap();
    let loaded = result["input_mass_g"].as_f64().unwrap();
    let placed_g = case["placement"]["mass_kg"].as_f64().unwrap() * 1e3;
    // the dump prints masses to about 7 digits
    assert!((loaded / placed_g - 1.0).abs() < 1e-5, "loaded {loaded} g, placed {placed_g} g");
    let teeth_g: Vec<f64> = result["teeth_g"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    let later: f64 = teeth_g[1..].iter().sum::<f64>() / loaded;
    assert!(later > 0.3, "only {later} of the mass left tooth 1: {teeth_g:?}");

    let setup = read(&dir.join("setup.toml"));
    assert!(!setup.contains("[effects"), "{setup}");
    assert!(setup.contains("polydisperse size law"), "{setup}");
}

/// Every file of a folder, by name (lock and marker left out: they hold the run's id).
fn files_of(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap())
        .filter(|e| e.file_type().unwrap().is_file())
        .map(|e| (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).unwrap()))
        .filter(|(n, _)| !n.starts_with(".sawtooth"))
        .collect();
    out.sort();
    out
}

/// Same inputs and seed, same outputs: `dem write` twice gives the same files byte for
/// byte, and LIGGGHTS run twice on the same case leaves the same grains in the same teeth
/// (and the same end positions), so a DEM campaign can be repeated and its seed spread is
/// the seeds', not the engine's. (Serial LIGGGHTS; an MPI run's domain decomposition may sum
/// contact forces in another order.)
#[test]
fn the_same_case_twice_gives_the_same_files_and_the_same_tooth_masses() {
    let d = tempfile::tempdir().unwrap();
    let write = |name: &str| {
        let dir = d.path().join(name);
        let args =
            ["dem", "write", "--config", RIG, "--particles", "40", "--seed", "7", "--out", dir.to_str().unwrap()];
        let (code, _, err) = sawtooth(&args);
        assert_eq!(code, 0, "{err}");
        files_of(&dir)
    };
    let (first, second) = (write("case-1"), write("case-2"));
    let names: Vec<&str> = first.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["case.json", "grains.data", "in.sawtooth", "sled.stl"]);
    for ((name, a), (_, b)) in first.iter().zip(&second) {
        assert!(a == b, "{name} differs between two `dem write` of the same inputs");
    }

    if !liggghts_present("dem::the_same_case_twice_gives_the_same_files_and_the_same_tooth_masses") {
        return;
    }
    // CI-sized: the rig's grains have landed 0.5 s after the stroke; stop there
    let config = coarse_rig(&d.path().join("cfg"), "max_time_s = 0.5\n");
    let run = |name: &str| {
        let dir = d.path().join(name);
        let args = [
            "dem",
            "run",
            "--config",
            &config,
            "--particles",
            "40",
            "--seed",
            "7",
            "--runs",
            "1",
            "--jobs",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ];
        let (code, _, err) = sawtooth(&args);
        assert_eq!(code, 0, "{err}");
        let result: serde_json::Value = serde_json::from_str(&read(&dir.join("run-001/result.json"))).unwrap();
        (result["teeth_g"].clone(), result["lost"].clone(), std::fs::read(dir.join("run-001/final.dump")).unwrap())
    };
    let (teeth_1, lost_1, dump_1) = run("run-1");
    let (teeth_2, lost_2, dump_2) = run("run-2");
    assert!(teeth_1.as_array().is_some_and(|t| !t.is_empty()), "{teeth_1}");
    assert_eq!(teeth_1, teeth_2, "tooth masses (g) of two runs of one case");
    assert_eq!(lost_1, lost_2);
    assert!(dump_1 == dump_2, "the end positions (final.dump) of two runs of one case differ");
}

/// Many designs on a cluster: `dem check --plan` writes a plan whose members are DEM runs
/// (design x seed), `campaign slurm` its job array, each array task runs one member through
/// the script's own command line, and `campaign gather` writes the report `dem check` gives.
/// No Slurm daemon: the scripts are read and run by bash with the task id Slurm would set.
#[test]
fn a_dem_check_runs_as_a_job_array_of_dem_runs_and_gathers_the_same_report() {
    let d = tempfile::tempdir().unwrap();
    let (opt, chk) = (d.path().join("opt"), d.path().join("check"));
    let (opt_s, chk_s) = (opt.to_str().unwrap(), chk.to_str().unwrap());
    let (code, _, err) = sawtooth(&[
        "optimize",
        "--env",
        "earth",
        "--pop",
        "12",
        "--generations",
        "2",
        "--algorithm",
        "nsga2",
        "--particles",
        "20",
        "--final-particles",
        "40",
        "--replicates",
        "2",
        "--requirements",
        "table-2.2",
        "--quiet",
        "--out",
        opt_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let check_args = ["dem", "check", opt_s, "--front", "0", "--seeds", "2", "--particles", "30", "--out", chk_s];
    let mut plan_args = check_args.to_vec();
    plan_args.push("--plan");
    let (code, said, err) = sawtooth(&plan_args);
    assert_eq!(code, 0, "{err}");
    assert!(said.contains("nothing run yet") && said.contains("campaign slurm"), "{said}");
    // the same plan again is the same check (read back exactly); another one is refused
    let (code, _, err) = sawtooth(&plan_args);
    assert_eq!(code, 0, "the same --plan again: {err}");
    let mut other = plan_args.clone();
    other[6] = "3";
    let (code, _, err) = sawtooth(&other);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("another plan"), "{err}");

    // the plan: every finalist's DEM campaign of 2 seeds; members are finalist x seed
    let plan: serde_json::Value = serde_json::from_str(&read(&chk.join("plan.json"))).unwrap();
    let finalists = plan["finalists"].as_array().unwrap();
    assert!((1..=3).contains(&finalists.len()), "{plan}");
    assert!(finalists.iter().all(|f| f["campaign"]["runs"] == 2 && f["campaign"]["settings"]["particles"] == 30));
    assert!(finalists[0]["label"].as_str().unwrap().starts_with('A'), "{plan}");
    let members = 2 * finalists.len();

    let (code, status, err) = sawtooth(&["campaign", "status", chk_s]);
    assert_eq!(code, 0, "{err}");
    assert!(status.contains(&format!("finished 0, not finished {members}")), "{status}");
    let (code, _, err) = sawtooth(&["campaign", "gather", chk_s]);
    assert_eq!(code, 2, "a gather before the members ran must refuse: {err}");
    assert!(err.contains(&format!("{members} of {members} members")) && err.contains("--task"), "{err}");

    // the Slurm scripts: one array task per member, each running `campaign run DIR --task I`
    let (code, _, err) = sawtooth(&["campaign", "slurm", chk_s, "--time", "30:00"]);
    assert_eq!(code, 0, "{err}");
    let array = read(&chk.join("slurm/array.sbatch"));
    let gather = read(&chk.join("slurm/gather.sbatch"));
    assert!(array.contains(&format!("#SBATCH --array=0-{}\n", members - 1)), "{array}");
    assert!(array.contains("#SBATCH --cpus-per-task=1") && array.contains("#SBATCH --time=30:00"), "{array}");
    assert!(array.contains("campaign run") && array.contains("--task \"$SLURM_ARRAY_TASK_ID\""), "{array}");
    assert!(gather.contains("campaign gather"), "{gather}");

    if !liggghts_present("dem::a_dem_check_runs_as_a_job_array_of_dem_runs_and_gathers_the_same_report") {
        return;
    }
    // each task as Slurm would start it: the script under bash with its task id
    for task in 0..members {
        let o = Command::new("bash")
            .arg(chk.join("slurm/array.sbatch"))
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .output()
            .unwrap();
        assert!(o.status.success(), "task {task}: {}", String::from_utf8_lossy(&o.stderr));
        assert!(String::from_utf8_lossy(&o.stdout).contains(&format!("member {task} (")));
    }
    let (code, status, _) = sawtooth(&["campaign", "status", chk_s]);
    assert_eq!(code, 0);
    assert!(status.contains(&format!("finished {members}, not finished 0")), "{status}");
    let o = Command::new("bash").arg(chk.join("slurm/gather.sbatch")).output().unwrap();
    assert!(o.status.success(), "gather: {}", String::from_utf8_lossy(&o.stderr));
    let gathered: serde_json::Value = serde_json::from_str(&read(&chk.join("check.json"))).unwrap();
    assert_eq!(gathered["designs"].as_array().unwrap().len(), finalists.len(), "{gathered}");
    // each design's DEM d_avg is the mean over its members' own result files
    for (f, design) in finalists.iter().zip(gathered["designs"].as_array().unwrap()) {
        let label = f["label"].as_str().unwrap();
        assert_eq!(design["label"], label);
        let runs: Vec<f64> = (1..=2)
            .map(|r| {
                let path = chk.join(label).join(format!("run-{r:03}/result.json"));
                serde_json::from_str::<serde_json::Value>(&read(&path)).unwrap()["d_avg_m"].as_f64().unwrap()
            })
            .collect();
        let mean_mm = 1e3 * (runs[0] + runs[1]) / 2.0;
        let reported = design["dem_d_avg_mm"]["mean"].as_f64().unwrap();
        assert!((reported - mean_mm).abs() <= 1e-9 * mean_mm.abs().max(1.0), "{label}: {reported} vs {mean_mm}");
    }
    let first = &gathered["designs"][0];
    assert!(first["dem_compliant"].is_boolean(), "the run's requirements judged again: {gathered}");
    // the design as every file spells it: its eight named columns with their units
    assert!(first["design"]["l_c_mm"].is_number() && first["design"]["a_m_s2"].is_number(), "{gathered}");
    assert!(first["dem_m_dot_op_kg_h"].is_number() && first["dem_operating_limit"].is_string(), "{gathered}");

    // `dem check` on the same folder: every run is done, nothing runs, the same report
    let mut json_args = check_args.to_vec();
    json_args.push("--json");
    let (code, local, err) = sawtooth(&json_args);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("started"), "a finished check ran again: {err}");
    assert_eq!(serde_json::from_str::<serde_json::Value>(&local).unwrap(), gathered);
}

/// A design of experiments (issue 43, 2): `dem doe` draws designs spread over the
/// optimiser's space under its constraints and the draw's own rules, and runs them as a DEM
/// check (the same plan, status, gather and report), each design's campaign ending with the
/// `dem.csv` and `setup.toml` that `fit` reads. The same draw seed draws the same designs.
#[test]
fn a_design_of_experiments_draws_spread_designs_and_runs_them_as_a_check() {
    let d = tempfile::tempdir().unwrap();
    let doe = d.path().join("doe");
    let doe_s = doe.to_str().unwrap();
    let args = [
        "dem",
        "doe",
        "--env",
        "earth",
        "--designs",
        "2",
        "--seeds",
        "1",
        "--particles",
        "30",
        "--max-d-avg-mm",
        "150",
        "--jobs",
        "1",
        "--out",
        doe_s,
    ];
    let mut plan_args = args.to_vec();
    plan_args.push("--plan");
    let (code, said, err) = sawtooth(&plan_args);
    assert_eq!(code, 0, "{err}");
    assert!(said.contains("2 designs x 1 seeds = 2 members") && said.contains("nothing run yet"), "{said}");
    assert!(err.contains("designs drawn in the pool") && err.contains("doe-02 --design"), "{err}");
    // the same draw again is the same plan (a plan of other designs would be refused)
    let (code, _, err) = sawtooth(&plan_args);
    assert_eq!(code, 0, "the same draw again: {err}");
    let mut other = plan_args.clone();
    other.extend(["--draw-seed", "2"]);
    let (code, _, err) = sawtooth(&other);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("another plan"), "{err}");
    let plan: serde_json::Value = serde_json::from_str(&read(&doe.join("plan.json"))).unwrap();
    let finalists = plan["finalists"].as_array().unwrap();
    let labels: Vec<&str> = finalists.iter().map(|f| f["label"].as_str().unwrap()).collect();
    assert_eq!(labels, ["doe-01", "doe-02"]);
    for f in finalists {
        assert!(f["model_d_avg_m"].as_f64().unwrap() <= 0.150, "--max-d-avg-mm: {f}");
        assert_eq!(f["campaign"]["scenario"]["environment"]["alpha_deg"], 35.0, "{f}");
    }
    assert_ne!(finalists[0]["campaign"]["design"], finalists[1]["campaign"]["design"]);
    for f in finalists {
        // the plan states each design's mesh, so that a later rule cannot move it
        assert!(f["campaign"]["settings"]["teeth"].as_u64().is_some_and(|t| t >= 5), "{f}");
    }
    // the same draw remade at twice the grains, judged at the count it was drawn at (at 30
    // grains the floor is 6.7 mm, and some drawn fills cannot seat 30 grains that coarse: the
    // draw skips them, and so must its remake, where 60 finer grains would seat)
    let finer = d.path().join("doe-finer");
    let mut finer_args = plan_args.clone();
    let at = finer_args.iter().position(|a| *a == "30").unwrap();
    finer_args[at] = "60";
    *finer_args.iter_mut().find(|a| **a == doe_s).unwrap() = finer.to_str().unwrap();
    finer_args.extend(["--draw-particles", "30"]);
    let (code, _, err) = sawtooth(&finer_args);
    assert_eq!(code, 0, "{err}");
    let remade: serde_json::Value = serde_json::from_str(&read(&finer.join("plan.json"))).unwrap();
    for (a, b) in finalists.iter().zip(remade["finalists"].as_array().unwrap()) {
        assert_eq!(a["campaign"]["design"], b["campaign"]["design"]);
        assert_eq!(b["campaign"]["settings"]["particles"], 60);
    }
    let (code, status, err) = sawtooth(&["campaign", "status", doe_s]);
    assert_eq!(code, 0, "{err}");
    assert!(status.contains("finished 0, not finished 2"), "{status}");

    // bad draws are refused naming the flag and the rule
    for (flag, value, rule) in
        [("--designs", "0", "--designs"), ("--min-grain-mm", "-1", "[0, 50]"), ("--max-d-avg-mm", "0", "> 0 mm")]
    {
        let out = d.path().join(format!("bad{flag}"));
        let (code, _, err) =
            sawtooth(&["dem", "doe", "--env", "earth", flag, value, "--plan", "--out", out.to_str().unwrap()]);
        assert_eq!(code, 2, "{flag} {value}: {err}");
        assert!(err.contains(rule), "{flag} {value}: {err}");
    }

    if !liggghts_present("dem::a_design_of_experiments_draws_spread_designs_and_runs_them_as_a_check") {
        return;
    }
    let mut json_args = args.to_vec();
    json_args.push("--json");
    let (code, out, err) = sawtooth(&json_args);
    assert_eq!(code, 0, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["designs"].as_array().unwrap().len(), 2, "{report}");
    assert!(report["run_dir"].as_str().unwrap().contains("design of experiments"), "{report}");
    for label in labels {
        for f in ["dem.csv", "setup.toml"] {
            assert!(doe.join(label).join(f).is_file(), "{label}/{f}");
        }
        let (code, cmp, err) = sawtooth(&["dem", "compare", doe.join(label).to_str().unwrap()]);
        assert_eq!(code, 0, "{label}: {err}");
        assert!(cmp.contains("d_avg: model"), "{cmp}");
    }
    // a drawn design's folder is a campaign `dem run` resumes from its setup.toml (the way to
    // `--refine` it): its runs are read back, nothing runs again
    let first = doe.join("doe-01");
    let setup = first.join("setup.toml");
    let (code, _, err) = sawtooth(&[
        "dem",
        "run",
        "--config",
        setup.to_str().unwrap(),
        "--runs",
        "1",
        "--jobs",
        "1",
        "--out",
        first.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("settling"), "nothing runs again: {err}");
}

/// The loop's check (issue 43, 4): a run optimised on the corrected lunar model
/// (`data/dem/lunar-corrected.toml`: fitted coefficients and an effect the DEM does not take)
/// is checked in DEM against the physics it was corrected to (`--config`), not against its
/// own fitted coefficients; without `--config` the effect is refused by name.
#[test]
fn a_run_on_the_corrected_model_is_checked_against_the_reference_physics() {
    let d = tempfile::tempdir().unwrap();
    let corrected = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/dem/lunar-corrected.toml");
    let (opt, chk) = (d.path().join("opt"), d.path().join("check"));
    let (code, _, err) = sawtooth(&[
        "optimize",
        "--config",
        corrected.to_str().unwrap(),
        "--pop",
        "20",
        "--generations",
        "3",
        "--algorithm",
        "nsga2",
        "--particles",
        "20",
        "--final-particles",
        "40",
        "--quiet",
        "--out",
        opt.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let args = ["dem", "check", opt.to_str().unwrap(), "--front", "0", "--seeds", "1", "--particles", "150", "--plan"];
    let mut own = args.to_vec();
    own.extend(["--out", chk.to_str().unwrap()]);
    let (code, _, err) = sawtooth(&own);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("fill-surface-loss") && err.contains("not carried into a DEM case"), "{err}");
    let reference = d.path().join("lunar.toml");
    std::fs::write(&reference, "env = \"lunar\"\n").unwrap();
    let mut with_ref = args.to_vec();
    with_ref.extend(["--config", reference.to_str().unwrap(), "--out", chk.to_str().unwrap()]);
    let (code, _, err) = sawtooth(&with_ref);
    assert_eq!(code, 0, "{err}");
    let plan: serde_json::Value = serde_json::from_str(&read(&chk.join("plan.json"))).unwrap();
    let text = read(&corrected);
    let fitted: toml::Table = toml::from_str(&text).unwrap();
    for f in plan["finalists"].as_array().unwrap() {
        let s = &f["campaign"]["scenario"];
        // the lunar preset's contact (Table 4.2), not the corrected model's fitted values
        assert_eq!(s["collision"]["k_elastic"], 0.872, "{s}");
        assert_ne!(s["collision"]["k_elastic"].as_f64(), fitted["collision"]["k_elastic"].as_float());
        assert!(s.get("effects").is_none_or(|e| e.as_object().is_none_or(|o| o.values().all(|v| v.is_null()))), "{s}");
        assert!(plan["command"].as_str().unwrap().contains("--config"), "{plan}");
    }
}
