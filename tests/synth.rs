//! `sawtooth synth`: measurement-like runs in the measured-data format, deterministic per
//! seed, quantised to the scale, carrying the effect they were made with.

use std::process::Command;

use sawtooth::io::measured;

fn synth(args: &[&str], out: &std::path::Path) -> String {
    let setup = concat!(env!("CARGO_MANIFEST_DIR"), "/data/validation/test3.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_sawtooth"))
        .args(["synth", "--setup", setup, "--runs", "6", "--particles", "600", "--out", out.to_str().unwrap()])
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(out).unwrap()
}

#[test]
fn synthetic_runs_read_back_as_measured_data() {
    let dir = std::env::temp_dir().join(format!("sawtooth-synth-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let a = synth(&["--seed", "4"], &dir.join("a.csv"));
    assert_eq!(a, synth(&["--seed", "4"], &dir.join("b.csv")), "same seed, same data");
    assert_ne!(a, synth(&["--seed", "5"], &dir.join("c.csv")));
    let runs = measured::parse(&a, "a.csv").unwrap();
    assert_eq!(runs.runs.len(), 6);
    for r in &runs.runs {
        for m in &r.teeth_g {
            assert!(((m / 0.01) - (m / 0.01).round()).abs() < 1e-6, "{m} is not on the 0.01 g scale");
        }
        let total: f64 = r.teeth_g.iter().sum();
        let input = r.input_mass_g.unwrap();
        assert!(total <= input * 1.0 + 0.05 && total >= 0.9 * input, "recovered {total} of {input}");
    }
    // the effect is in the data
    let poly =
        measured::parse(&synth(&["--seed", "4", "--effect", "polydisperse=0.6"], &dir.join("d.csv")), "d.csv").unwrap();
    let (m0, m1) = (runs.mean_fractions(), poly.mean_fractions());
    let l1: f64 = m0.iter().zip(&m1).map(|(x, y)| (x - y).abs()).sum();
    assert!(l1 > 0.05, "polydispersity barely changed the synthetic data ({l1})");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn synth_rejects_bad_input() {
    let o = Command::new(env!("CARGO_BIN_EXE_sawtooth"))
        .args(["synth", "--setup", "/nonexistent.toml", "--out", "/tmp/x.csv"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let setup = concat!(env!("CARGO_MANIFEST_DIR"), "/data/validation/test3.toml");
    let o = Command::new(env!("CARGO_BIN_EXE_sawtooth"))
        .args(["synth", "--setup", setup, "--effect", "spin=1", "--out", "/tmp/x.csv"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("unknown effect"));
    // each bad number named by its flag
    for (args, needle) in [
        (["--runs", "0"], "--runs"),
        (["--particles", "0"], "--particles"),
        (["--resolution-g", "0"], "--resolution-g must lie in [1e-15, 1000] g"),
        (["--resolution-g", "1e308"], "--resolution-g must lie in [1e-15, 1000] g"),
        (["--mass-g", "0"], "--mass-g must lie in [0.001, 1000000] g"),
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_sawtooth"))
            .args(["synth", "--setup", setup, "--out", "/tmp/x.csv"])
            .args(args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
    }
}
