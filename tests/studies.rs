//! gpu-sweep and the studies end to end with tiny settings: outputs, and a rerun that
//! reads finished runs back instead of recomputing them.

use crate::common;
use common::{assert_figure, assert_png_beside, fresh_dir, run};
use sawtooth::campaigns::study::{GridRow, RunRow, SummaryRow};
use sawtooth::campaigns::sweep::SweepRow;

const GA: &[&str] = &[
    "--pop",
    "16",
    "--generations",
    "4",
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

#[test]
fn sweep_writes_a_summary_per_angle_and_reruns_from_disk() {
    let out = fresh_dir("sweep");
    let o = out.to_str().unwrap();
    let mut args = vec!["gpu-sweep", "--env", "lunar", "--alpha", "20..40", "--step", "10", "--out", o];
    args.extend_from_slice(GA);
    let (code, first, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    for a in ["alpha_020.00", "alpha_030.00", "alpha_040.00"] {
        assert!(out.join(a).join("pareto.csv").exists(), "{a}");
    }
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    assert!(summary.lines().count() >= 4);
    // typed rows, exact floats: each pick's figures are its angle's pareto.csv row to the bit
    let rows: Vec<SweepRow> =
        csv::Reader::from_reader(summary.as_bytes()).deserialize().collect::<Result<_, _>>().unwrap();
    let c30 = rows.iter().find(|r| r.alpha_deg == 30.0 && r.pick == "C").expect("pick C at 30 deg");
    let front = sawtooth::optim::front::read_pareto_csv(&out.join("alpha_030.00/pareto.csv")).unwrap();
    assert!(front.iter().any(|p| p.w_spec_j_kg == c30.w_spec_j_kg && p.w_spec_se == c30.w_spec_se_j_kg), "{c30:?}");
    let svg = std::fs::read_to_string(out.join("sweep.svg")).unwrap();
    assert!(svg.starts_with("<svg"));
    assert_png_beside(&out.join("sweep.svg"));
    assert_figure(
        &svg,
        10,
        &["conveyor angle alpha [deg]", "W_spec [J/kg]", "lowest W_spec (C)", "±1 standard error (re-evaluation)"],
    );
    // finished angles are read back, not rerun: same table, no new evaluations
    let before = std::fs::metadata(out.join("alpha_030.00/evaluations.csv")).unwrap().len();
    let (code, second, _) = run(&args);
    assert_eq!(code, 0);
    assert_eq!(first, second);
    assert_eq!(before, std::fs::metadata(out.join("alpha_030.00/evaluations.csv")).unwrap().len());
    // the rerun's summary is the first one byte for byte (read back from exact pareto.csv)
    assert_eq!(summary, std::fs::read_to_string(out.join("summary.csv")).unwrap());
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn sweep_needs_a_range_and_single_commands_refuse_one() {
    let (code, _, err) = run(&["gpu-sweep", "--out", "/tmp/x"]);
    assert_eq!(code, 2);
    assert!(err.contains("--alpha"), "{err}");
    // a range means one run per angle (gpu-sweep) or one design over the slopes (simulate,
    // optimize); a study of one angle refuses it
    let (code, _, err) = run(&["study", "repeatability", "--alpha", "1..40", "--out", "/tmp/x"]);
    assert_eq!(code, 2);
    assert!(err.contains("gpu-sweep") && err.contains("give one angle"), "{err}");
}

#[test]
fn repeatability_and_sensitivity_write_their_tables() {
    let rep = fresh_dir("rep");
    let mut args = vec!["study", "repeatability", "--env", "lunar", "--runs", "3", "--out", rep.to_str().unwrap()];
    args.extend_from_slice(GA);
    let (code, out, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("CV"), "{out}");
    let summary = std::fs::read_to_string(rep.join("summary.csv")).unwrap();
    assert!(summary.contains("w_spec_j_kg"));
    let runs = std::fs::read_to_string(rep.join("runs.csv")).unwrap();
    assert_eq!(runs.lines().count(), 4);
    let typed: Vec<RunRow> = csv::Reader::from_reader(runs.as_bytes()).deserialize().collect::<Result<_, _>>().unwrap();
    assert_eq!(typed.iter().map(|r| r.run).collect::<Vec<_>>(), [0, 1, 2]);
    let stats: Vec<SummaryRow> =
        csv::Reader::from_reader(summary.as_bytes()).deserialize().collect::<Result<_, _>>().unwrap();
    let w = stats.iter().find(|s| s.metric == "w_spec_j_kg").expect("w_spec_j_kg row");
    let ws: Vec<f64> = typed.iter().filter_map(|r| r.figures.map(|f| f.w_spec_j_kg)).collect();
    assert_eq!(w.n, ws.len());
    assert!((w.mean - ws.iter().sum::<f64>() / ws.len() as f64).abs() <= 1e-9 * w.mean, "{w:?} vs {ws:?}");
    // each run's distance from the target is in the table, and the report calls the runs
    // "at the target" only when every one of them is
    let header: Vec<&str> = runs.lines().next().unwrap().split(',').collect();
    let at = header.iter().position(|c| *c == "at_target").expect("at_target column");
    assert!(header.contains(&"m_dot_from_target_rel"));
    let all_at = runs.lines().skip(1).all(|l| l.split(',').nth(at) == Some("true"));
    assert_eq!(out.contains("NOT at the target"), !all_at, "{out}\n{runs}");
    assert_png_beside(&rep.join("repeatability.svg"));
    // rerunning reads the finished runs back: the same tables to the byte
    let (code, again, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    assert_eq!(again, out);
    assert_eq!(std::fs::read_to_string(rep.join("summary.csv")).unwrap(), summary);
    assert_eq!(std::fs::read_to_string(rep.join("runs.csv")).unwrap(), runs);

    let sens = fresh_dir("sens");
    let mut args = vec![
        "study",
        "sensitivity",
        "--env",
        "lunar",
        "--out",
        sens.to_str().unwrap(),
        "--repeatability",
        rep.to_str().unwrap(),
    ];
    args.extend_from_slice(GA);
    let (code, _, err) = run(&args);
    assert_eq!(code, 0, "{err}");
    // Table C.2's 5 x 5 grid in vacuum
    assert_eq!(std::fs::read_to_string(sens.join("grid.csv")).unwrap().lines().count(), 26);
    let grid: Vec<GridRow> =
        csv::Reader::from_path(sens.join("grid.csv")).unwrap().deserialize().collect::<Result<_, _>>().unwrap();
    assert!(grid
        .iter()
        .all(|g| g.k_drag_per_s == 0.0 && g.w_spec_within_repeatability_ci.is_some() == g.figures.is_some()));
    assert_png_beside(&sens.join("sensitivity.svg"));
    let _ = std::fs::remove_dir_all(&rep);
    let _ = std::fs::remove_dir_all(&sens);
}
