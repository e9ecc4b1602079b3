//! The DEM reference checked before it is trusted (issue 42 §7), with the real engine
//! (LIGGGHTS 3.8): a single grain gives the configured COR and the model with the DEM's
//! measured law follows its impacts; a lone grain lands on the same tooth in the DEM and in the
//! model with the DEM's law (one grain leaves the contact mapping as the only physics to
//! differ); `--refine` and `--strokes` at CI size; every result's positions finite. Full tier,
//! as tests/dem.rs.

use std::path::Path;

use sawtooth::io::config::ConfigFile;
use sawtooth::model::collision::Restitution;

use crate::dem::{coarse_rig, liggghts_present, read, sawtooth, sawtooth_env, tmp, RIG};

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Every grain of every run's settled bed is a finite point (a blown-up run is never a result).
fn settled_beds_are_finite(campaign: &Path) {
    for entry in std::fs::read_dir(campaign).unwrap() {
        let run = entry.unwrap().path();
        let result = run.join("result.json");
        if !result.is_file() {
            continue;
        }
        let r = json(&read(&result));
        for p in r["settled_xy_m"].as_array().map(|a| a.as_slice()).unwrap_or(&[]) {
            let xy: Vec<f64> = p.as_array().unwrap().iter().map(f).collect();
            assert!(xy.iter().all(|v| v.is_finite()), "{}: {xy:?}", result.display());
        }
        assert!(r["teeth_g"].as_array().unwrap().iter().all(|m| f(m).is_finite() && f(m) >= 0.0), "{r}");
    }
}

#[test]
fn a_single_grain_gives_the_configured_cor_and_the_measured_law_follows_its_impacts() {
    if !liggghts_present(
        "dem_reference::a_single_grain_gives_the_configured_cor_and_the_measured_law_follows_its_impacts",
    ) {
        return;
    }
    let (_d, dir) = tmp("impact");
    let law = dir.with_extension("law.toml");
    let args = [
        "dem",
        "impact",
        "--config",
        RIG,
        "--speeds",
        "0.3,1.0",
        "--angles",
        "0,20,45,70",
        "--law-out",
        law.to_str().unwrap(),
        "--json",
        "--out",
        dir.to_str().unwrap(),
    ];
    let (code, out, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    let impacts = json(&out);
    let impacts = impacts["impacts"].as_array().unwrap_or_else(|| impacts.as_array().unwrap());
    assert_eq!(impacts.len(), 8, "{impacts:?}");
    let config = ConfigFile::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(RIG)).unwrap();
    let s = config.scenario().unwrap();
    let measured = ConfigFile::load(&law).unwrap().scenario().unwrap();
    assert_eq!(measured.collision.law, sawtooth::model::scenario::ContactLaw::Dem);
    let with_law = Restitution::new(s.mode, &measured.collision, &s.material);
    for i in impacts {
        let (speed, angle) = (f(&i["speed_m_s"]), f(&i["angle_deg"]));
        // LIGGGHTS's Hertz contact with a constant COR: the configured k_elastic at every speed
        let cor = f(&i["dem_normal_cor"]);
        assert!((cor / s.collision.k_elastic - 1.0).abs() < 0.02, "{speed} m/s, {angle} deg: COR {cor}");
        // the model's bounce with the DEM's measured law, at a speed other than the one it was
        // measured at (v0/2) too
        if angle > 0.0 {
            let a = angle.to_radians();
            let v = [speed * a.sin(), -speed * a.cos()];
            let out = with_law.bounce(v, [0.0, 1.0]);
            let model_kt = out[0] / v[0];
            let dem_kt = f(&i["dem_tangential_ratio"]);
            assert!((model_kt - dem_kt).abs() < 0.1, "{speed} m/s, {angle} deg: k_t model {model_kt}, DEM {dem_kt}");
            assert!((out[1] / -v[1] - cor).abs() < 0.02 * cor, "{speed} m/s, {angle} deg: normal {out:?}");
        }
    }
    assert!(dir.join("impact.svg").is_file() && dir.join("impact.json").is_file());
}

#[test]
fn a_lone_grain_lands_on_the_same_tooth_in_the_dem_and_in_the_model_with_the_dems_law() {
    if !liggghts_present(
        "dem_reference::a_lone_grain_lands_on_the_same_tooth_in_the_dem_and_in_the_model_with_the_dems_law",
    ) {
        return;
    }
    let (_d, dir) = tmp("lone");
    // one grain, the model launched without its random excess: both sides follow one grain;
    // CI-sized: 1 mm and the coarse overlap (one grain has no bed to compress)
    let config = coarse_rig(&dir.with_extension("cfg"), "particles = 1\ngrain_diameter_m = 0.001\n");
    let text = read(Path::new(&config)).replace("[sim]\n", "[sim]\nrandomise = false\n");
    assert!(text.contains("randomise = false"), "the rig's config has no [sim] table: {text}");
    std::fs::write(&config, text).unwrap();
    let out = dir.to_str().unwrap();
    let (code, _, err) = sawtooth(&["dem", "run", "--config", &config, "--runs", "2", "--jobs", "2", "--out", out]);
    assert_eq!(code, 0, "{err}");
    let (code, text, err) = sawtooth(&["dem", "compare", out, "--json"]);
    assert_eq!(code, 0, "{err}");
    let c = json(&text);
    let model: Vec<f64> =
        c["model_dem_law_pct"].as_array().expect("the campaign measured its law").iter().map(f).collect();
    let dem = c["dem_pct"].as_array().unwrap();
    assert_eq!(model.len(), dem.len());
    for (j, (m, d)) in model.iter().zip(dem).enumerate() {
        let (mean, sd) = (f(&d["mean"]), f(&d["sd"]));
        assert!((m - mean).abs() <= 2.0 * sd + 1.0, "tooth {}: model {m} %, DEM {mean} ± {sd} %: {text}", j + 1);
    }
    // the grain left tooth 1 on both sides
    assert!(model[0] < 50.0, "{model:?}");
    settled_beds_are_finite(&dir);
}

/// A LIGGGHTS wrapper beside `dir` that edits the deck of the cases whose first line matches
/// `decks` (a `grep` pattern) with the `sed` expression `edit` before running it; the other
/// cases (a campaign's impact cases, which measure its law) run as they are.
fn deck_editing_liggghts(dir: &std::path::Path, decks: &str, edit: &str) -> std::path::PathBuf {
    let liggghts = sawtooth::dem::run::find_liggghts().unwrap();
    let wrapper = dir.with_extension("liggghts.sh");
    std::fs::write(
        &wrapper,
        format!(
            "#!/bin/sh\nif grep -q '{decks}' in.sawtooth; then\n  sed -i '{edit}' in.sawtooth\nfi\nexec '{}' \"$@\"\n",
            liggghts.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&wrapper, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    wrapper
}

/// A LIGGGHTS wrapper beside `dir` that deletes every grain of a conveyor's (or a single
/// stroke's) case right after reading it.
fn emptying_liggghts(dir: &std::path::Path) -> std::path::PathBuf {
    deck_editing_liggghts(dir, "^# sawtooth dem \\(case\\|conveyor\\)", "s/^read_data .*$/&\\ndelete_atoms group all/")
}

/// A run whose every grain leaves the box is a result with every grain lost (credited
/// nothing), not a failure: LIGGGHTS refuses to run a granular case with no grains left, so
/// the deck checks the count before every run and dump and stops with `all_lost.txt`. The
/// grains are made to leave by a LIGGGHTS wrapper that deletes them all right after they are
/// read (a lone grain rolling out of the box while it settles did this on a lunar design).
#[test]
fn a_run_whose_every_grain_leaves_the_box_is_a_result_with_every_grain_lost() {
    if !liggghts_present("dem_reference::a_run_whose_every_grain_leaves_the_box_is_a_result_with_every_grain_lost") {
        return;
    }
    let (_d, dir) = tmp("gone");
    let wrapper = emptying_liggghts(&dir);
    let config = coarse_rig(&dir.with_extension("cfg"), "particles = 4\ngrain_diameter_m = 0.001\n");
    let out = dir.to_str().unwrap();
    let (code, _, err) = sawtooth_env(
        &["dem", "run", "--config", &config, "--runs", "1", "--out", out],
        &[("SAWTOOTH_LIGGGHTS", wrapper.to_str().unwrap())],
    );
    assert_eq!(code, 0, "{err}");
    let run = dir.join("run-001");
    assert!(read(&run.join("in.sawtooth")).contains("delete_atoms group all"), "the wrapper did not empty the case");
    assert!(run.join("all_lost.txt").is_file(), "{err}");
    let r = json(&read(&run.join("result.json")));
    assert_eq!(r["grains"], 4, "{r}");
    assert_eq!(r["lost"], 4, "{r}");
    assert_eq!(r["left_box"], 4, "{r}");
    assert_eq!(f(&r["d_avg_m"]), 0.0, "{r}");
    assert!(r["teeth_g"].as_array().unwrap().iter().all(|m| f(m) == 0.0), "{r}");
    assert!(f(&r["input_mass_g"]) > 0.0, "{r}");
    // deleted before the track's first snapshot: never seen
    assert_eq!(r["left_by"]["unplaced"], 4, "{r}");
}

/// Where the grains LIGGGHTS deletes leave is read from the run's track (`track.dump`): a
/// wrapper kicks every grain straight up at 5 m/s when the stroke starts, far past the box's
/// top, and the run places every one of them `over_top`, after the stroke began.
#[test]
fn grains_that_leave_the_box_are_placed_by_their_last_sighting() {
    if !liggghts_present("dem_reference::grains_that_leave_the_box_are_placed_by_their_last_sighting") {
        return;
    }
    let (_d, dir) = tmp("kicked");
    let wrapper =
        deck_editing_liggghts(&dir, "^# sawtooth dem case", "s/^# the stroke$/&\\nvelocity all set 0.0 5.0 0.0/");
    let config = coarse_rig(&dir.with_extension("cfg"), "particles = 6\ngrain_diameter_m = 0.001\n");
    let out = dir.to_str().unwrap();
    let (code, _, err) = sawtooth_env(
        &["dem", "run", "--config", &config, "--runs", "1", "--out", out],
        &[("SAWTOOTH_LIGGGHTS", wrapper.to_str().unwrap())],
    );
    assert_eq!(code, 0, "{err}");
    let run = dir.join("run-001");
    assert!(read(&run.join("in.sawtooth")).contains("velocity all set 0.0 5.0 0.0"), "the wrapper did not kick");
    assert!(run.join("track.dump").is_file() && run.join("stroke_start.txt").is_file());
    let r = json(&read(&run.join("result.json")));
    assert_eq!(r["left_box"], 6, "{r}");
    assert_eq!(r["left_by"]["over_top"], 6, "{r}");
    assert_eq!(r["left_by"]["while_settling"], 0, "{r}");
    assert!(err.contains("6 over the top"), "{err}");
}

#[test]
fn refine_runs_the_campaign_at_half_the_overlap_and_twice_the_grains_and_judges_it() {
    if !liggghts_present(
        "dem_reference::refine_runs_the_campaign_at_half_the_overlap_and_twice_the_grains_and_judges_it",
    ) {
        return;
    }
    let (_d, dir) = tmp("refine");
    let out = dir.to_str().unwrap();
    // CI-sized: the coarse overlap of 10 % (a quarter of the default's cost) and 24 grains
    let config = coarse_rig(&dir.with_extension("cfg"), "");
    let args = [
        "dem",
        "run",
        "--config",
        &config,
        "--particles",
        "24",
        "--runs",
        "2",
        "--jobs",
        "2",
        "--refine",
        "--out",
        out,
    ];
    let (code, table, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(table.contains("level 1: overlap 0.1 x 24 grains"), "{table}");
    let r = json(&read(&dir.join("refine.json")));
    let level = &r["levels"][0];
    assert_eq!(f(&level["half_overlap"]["max_overlap_fraction"]), 0.05);
    assert_eq!(level["double_grains"]["particles"].as_u64(), Some(48));
    // the verdict is the rule applied to the moves it reports
    let allowed = f(&level["allowed_mm"]);
    let moved = f(&level["overlap_move_mm"]).abs().max(f(&level["grains_move_mm"]).abs());
    assert_eq!(level["converged"].as_bool(), Some(moved <= allowed), "{level}");
    assert!(allowed >= 0.03 * f(&level["base"]["d_avg_mm"]) - 1e-9, "{level}");
    for sub in ["refine-01-ov0.05-n24", "refine-02-ov0.1-n48"] {
        assert!(dir.join(sub).join("dem.csv").is_file(), "{sub}");
        settled_beds_are_finite(&dir.join(sub));
    }
    // a level is a campaign of its own: compared with the model as the base one is
    let level2 = dir.join("refine-02-ov0.1-n48");
    let (code, _, err) = sawtooth(&["dem", "compare", level2.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    assert!(level2.join("compare.json").is_file());
    // and the base campaign's comparison carries the ladder's numerics
    let (code, compared, err) = sawtooth(&["dem", "compare", out, "--json"]);
    assert_eq!(code, 0, "{err}");
    let c = json(&compared);
    let moved = f(&c["numerics"]["overlap_move_mm"]).abs().max(f(&c["numerics"]["grains_move_mm"]).abs());
    assert_eq!(f(&c["numerics_error_mm"]), moved, "{c}");
    // again: everything is read back, nothing runs, the same ladder
    let before = read(&dir.join("refine.json"));
    let (code, again, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("settling"), "{err}");
    assert_eq!(read(&dir.join("refine.json")), before, "{again}");
}

#[test]
fn strokes_convey_grains_steadily_and_report_the_advance_beside_the_models() {
    if !liggghts_present("dem_reference::strokes_convey_grains_steadily_and_report_the_advance_beside_the_models") {
        return;
    }
    let (_d, dir) = tmp("steady");
    let out = dir.to_str().unwrap();
    let config = coarse_rig(&dir.with_extension("cfg"), "");
    let args = [
        "dem",
        "run",
        "--config",
        &config,
        "--particles",
        "20",
        "--strokes",
        "3",
        "--period-teeth",
        "2",
        "--runs",
        "1",
        "--jobs",
        "1",
        "--out",
        out,
    ];
    let (code, table, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(table.contains("advance"), "{table}");
    let run = json(&read(&dir.join("run-001/steady.json")));
    let advance: Vec<f64> = run["cycles"].as_array().unwrap().iter().map(|c| f(&c["advance_m"])).collect();
    assert_eq!(advance.len(), 3, "{run}");
    // the grains move up the conveyor, every stroke by a finite amount less than the period
    assert!(advance.iter().all(|a| a.is_finite()), "{advance:?}");
    assert!(advance[1..].iter().all(|a| *a > 0.0), "{advance:?}");
    for k in 0..=3 {
        assert!(dir.join(format!("run-001/cycle-{k:03}.dump")).is_file());
    }
    // every grain the conveyor lost is placed by its track (a periodic conveyor has no
    // ends: through the mesh or over the top), and none passed through the mesh
    assert!(dir.join("run-001/track.dump").is_file());
    let left = &run["left_by"];
    let count = |k: &str| left[k].as_u64().unwrap_or_else(|| panic!("left_by.{k}: {run}"));
    let lost_in_cycles: u64 = run["cycles"].as_array().unwrap().iter().map(|c| c["lost"].as_u64().unwrap()).sum();
    let placed = ["through_mesh", "over_top", "unplaced"].iter().map(|k| count(k)).sum::<u64>();
    assert_eq!(placed, lost_in_cycles, "{run}");
    assert_eq!((count("behind_first_tooth"), count("past_last_tooth")), (0, 0), "{run}");
    assert_eq!(count("through_mesh"), 0, "{run}");
    // the campaign is its own: the same command again resumes it (nothing left to run, the
    // same steady.json), and `dem compare` reads it
    let before = read(&dir.join("steady.json"));
    let (code, _, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("started"), "a finished run ran again: {err}");
    assert_eq!(read(&dir.join("steady.json")), before);
    let (code, compared, err) = sawtooth(&["dem", "compare", out]);
    assert_eq!(code, 0, "{err}");
    assert!(compared.contains("advance"), "{compared}");
}

/// A steady conveyor whose every grain leaves the box conveys nothing: the deck stops
/// before a run LIGGGHTS would refuse, and every stroke's advance is zero.
#[test]
fn a_conveyor_whose_every_grain_leaves_the_box_advances_nothing() {
    if !liggghts_present("dem_reference::a_conveyor_whose_every_grain_leaves_the_box_advances_nothing") {
        return;
    }
    let (_d, dir) = tmp("steady-gone");
    let wrapper = emptying_liggghts(&dir);
    let config = coarse_rig(&dir.with_extension("cfg"), "particles = 4\ngrain_diameter_m = 0.001\n");
    let out = dir.to_str().unwrap();
    let args =
        ["dem", "run", "--config", &config, "--strokes", "3", "--period-teeth", "2", "--runs", "1", "--out", out];
    let (code, _, err) = sawtooth_env(&args, &[("SAWTOOTH_LIGGGHTS", wrapper.to_str().unwrap())]);
    assert_eq!(code, 0, "{err}");
    let run = dir.join("run-001");
    assert!(read(&run.join("in.sawtooth")).contains("delete_atoms group all"), "the wrapper did not empty the case");
    assert!(run.join("all_lost.txt").is_file(), "{err}");
    let r = json(&read(&run.join("steady.json")));
    let advance: Vec<f64> = r["cycles"].as_array().unwrap().iter().map(|c| f(&c["advance_m"])).collect();
    assert_eq!(advance, vec![0.0; 3], "{r}");
    assert_eq!(f(&r["mass_per_tooth_kg"]), 0.0, "{r}");
    // every grain is counted as gone, the way the track allows
    let left = &r["left_by"];
    let total: u64 = left.as_object().unwrap_or_else(|| panic!("{r}")).values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(total, r["grains"].as_u64().unwrap(), "{r}");
}
