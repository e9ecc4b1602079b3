//! The binary as a user meets it: outputs, and bad input answered with a named field,
//! a non-zero exit and no panic.

use std::process::Command;

fn sawtooth(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_sawtooth")).args(args).output().expect("run binary");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

const LUNAR_C: &str = "47.346,46.898,32.183,43.687,94.42,11.964,0.840,32.051";

#[test]
fn simulate_json_has_the_documented_keys() {
    let (code, out, err) =
        sawtooth(&["simulate", "--env", "lunar", "--design", LUNAR_C, "--particles", "20", "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for k in ["distribution", "d_avg_m", "lost_fraction", "fill_area_mm2", "bounces"] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    for k in ["stroke_m", "n_wire", "t_cool_s", "f_stroke_hz", "m_dot_kg_s", "w_spec_j_kg", "p_avg_w"] {
        assert!(v["performance"].get(k).is_some(), "missing performance.{k}");
    }
    assert_eq!(v["distribution"].as_array().unwrap().len(), 100);
}

#[test]
fn same_seed_same_output_different_seed_different_output() {
    let run = |seed: &str| sawtooth(&["simulate", "--env", "earth", "--design", LUNAR_C, "--seed", seed, "--json"]).1;
    assert_eq!(run("5"), run("5"));
    assert_ne!(run("5"), run("6"));
}

/// `bench` says what each engine ran on (the CPU's model; for the cpu engine also its SIMD
/// path, chosen at run time), so a timing can be traced to its machine and build.
#[test]
fn bench_names_each_engines_device() {
    let args = [
        "bench",
        "--env",
        "lunar",
        "--designs",
        "4",
        "--particles",
        "20",
        "--repeats",
        "1",
        "--engines",
        "listing,cpu",
    ];
    let (code, out, err) = sawtooth(&args);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("listing: listing engine on the host CPU"), "{out}");
    let cpu = out.lines().find(|l| l.starts_with("cpu: cpu engine on the host CPU")).unwrap_or_else(|| panic!("{out}"));
    // the SIMD path it took (the widest this CPU has, or the one SAWTOOTH_SIMD names)
    assert!(cpu.ends_with(&format!("{})", sawtooth::simd::selected().describe())), "{cpu}");
    // and which CPU: its model name, so that a timing can be traced to its machine
    assert!(cpu.contains(&format!("({}; ", sawtooth::engine::host_cpu())), "{cpu}");
    if let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") {
        if let Some(name) = info.lines().find(|l| l.starts_with("model name")) {
            assert!(cpu.contains(name.split_once(':').unwrap().1.trim()), "{cpu}");
        }
    }
    let (code, out, err) = sawtooth(&[&args[..], &["--json"]].concat());
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["devices"]["cpu"].as_str().is_some_and(|d| d.contains("SIMD ")), "{v}");
    assert!(v["devices"]["listing"].as_str().is_some(), "{v}");
}

/// `bench` refuses a batch it cannot time, naming the flag: no designs, no repetitions, no
/// particles (it used to run an empty batch, or one repetition for `--repeats 0`).
#[test]
fn bench_refuses_what_it_cannot_time() {
    for (flag, says) in [
        ("--designs", "'--designs <DESIGNS>'"),
        ("--repeats", "'--repeats <REPEATS>'"),
        ("--particles", "`[sim] particles` (--particles)"),
    ] {
        let (code, out, err) = sawtooth(&["bench", "--engines", "cpu", flag, "0"]);
        assert_eq!(code, 2, "{flag} 0: {out}{err}");
        assert!(err.contains(says), "{flag} 0: {err}");
        assert!(out.is_empty(), "{flag} 0 printed a table: {out}");
    }
}

#[test]
fn example_configs_run() {
    for f in ["examples/lunar_solution_c.toml", "examples/earth_solution_c.toml", "examples/validation_test3.toml"] {
        let path = format!("{}/{f}", env!("CARGO_MANIFEST_DIR"));
        let (code, out, err) = sawtooth(&["simulate", "--config", &path]);
        assert_eq!(code, 0, "{f}: {err}");
        assert!(out.contains("d_avg"), "{f}");
    }
}

#[test]
fn trajectories_and_plot_are_written() {
    let dir = std::env::temp_dir().join(format!("sawtooth-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // README's `--trajectories out/traj.csv --plot out/earth.svg` in a fresh checkout: the
    // folder is not there yet, and is made
    let csv = dir.join("out").join("t.csv");
    let svg = dir.join("out").join("t.svg");
    let (code, _, err) = sawtooth(&[
        "simulate",
        "--design",
        LUNAR_C,
        "--particles",
        "8",
        "--trajectories",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.starts_with("particle,bounce,x_m,y_m,state"));
    assert!(text.lines().count() > 8);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("x [mm]") && text.contains("y [mm]"));
    // --plot x.png writes a real PNG (it used to be refused)
    let png = dir.join("t.png");
    let (code, _, err) =
        sawtooth(&["simulate", "--design", LUNAR_C, "--particles", "8", "--plot", png.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(&png).unwrap();
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "PNG signature");
    let mut reader = png::Decoder::new(&bytes[..]).read_info().unwrap();
    let mut rgb = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut rgb).unwrap();
    assert_eq!(info.width, 1200);
    let colours: std::collections::HashSet<&[u8]> = rgb[..info.buffer_size()].chunks(3).collect();
    assert!(colours.len() > 20, "a blank PNG: {} colours", colours.len());
    std::fs::remove_dir_all(&dir).ok();
}

/// `--trajectories /dev/stdout` prints the CSV before the summary, also when stdout is a
/// file (writing it through a second open of /dev/stdout overwrote one with the other, and
/// as root an atomic rename would have replaced the /dev/stdout link itself).
#[test]
fn trajectories_go_to_stdout_in_order() {
    let dir = std::env::temp_dir().join(format!("sawtooth-cli-stdout-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("stdout.txt");
    let status = Command::new(env!("CARGO_BIN_EXE_sawtooth"))
        .args(["simulate", "--design", LUNAR_C, "--particles", "3", "--trajectories", "/dev/stdout"])
        .stdout(std::fs::File::create(&file).unwrap())
        .status()
        .unwrap();
    assert!(status.success());
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(text.starts_with("particle,bounce,x_m,y_m,state\n"), "{text}");
    let summary = text.find("d_avg").expect("the summary follows the CSV");
    assert!(text[..summary].lines().count() > 3, "{text}");
    assert!(std::fs::symlink_metadata("/dev/stdout").map_or(true, |m| m.file_type().is_symlink()));
    std::fs::remove_dir_all(&dir).ok();
}

/// The gpu engine's slice setting comes from the environment; a malformed one is refused by
/// name before anything runs (read before the engine looks for an adapter).
#[test]
fn a_malformed_gpu_slice_setting_is_refused_by_name() {
    // `auto` too: a malformed setting is not a missing GPU to fall back from
    for engine in ["gpu", "auto"] {
        let out = Command::new(env!("CARGO_BIN_EXE_sawtooth"))
            .args(["bench", "--engines", engine, "--designs", "2", "--particles", "10", "--repeats", "1"])
            .env("SAWTOOTH_GPU_SLICE_DESIGNS", "250 designs")
            .output()
            .expect("run binary");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{engine}: {err}");
        assert!(
            err.contains("SAWTOOTH_GPU_SLICE_DESIGNS must be a whole number") && err.contains("'250 designs'"),
            "{err}"
        );
        assert!(out.stdout.is_empty() && !err.contains("panicked"), "{engine}: {err}");
    }
}

fn assert_bad_input(args: &[&str], needle: &str) {
    let (code, _, err) = sawtooth(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: stderr `{err}` lacks `{needle}`");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn bad_input_names_the_field_and_exits_2() {
    assert_bad_input(&["simulate", "--design", "47,46,32"], "8 comma-separated");
    assert_bad_input(&["simulate", "--design", "47,46,32,43,94,11,abc,32"], "v0");
    assert_bad_input(&["simulate", "--design", "47,46,32,43,94,11,NaN,32"], "v0");
    assert_bad_input(&["simulate", "--design", "47,46,45,43,94,11,0.84,32"], "l_b <= r");
    // values no conveyor has are refused before they overflow the performance model
    assert_bad_input(&["simulate", "--design", "47,46,32,43,94,11,0.84,1e300"], "`a` must lie in [0.01, 10000] m/s^2");
    assert_bad_input(&["simulate", "--design", "47,46,32,43,94,11,0.84,inf"], "`a` must lie in [0.01, 10000] m/s^2 (");
    // the message names what the user wrote: the flag, and the config file's key with its unit
    assert_bad_input(&["simulate", "--design", LUNAR_C, "--k-elastic", "1.5"], "`[collision] k_elastic` (--k-elastic)");
    assert_bad_input(&["simulate", "--design", LUNAR_C, "--particles", "0"], "`[sim] particles` (--particles)");
    let dir = std::env::temp_dir().join(format!("sawtooth-cli-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let config = dir.join("g.toml");
    std::fs::write(&config, "env = \"lunar\"\n[environment]\ng_m_s2 = -1.0\n").unwrap();
    assert_bad_input(
        &["simulate", "--design", LUNAR_C, "--config", config.to_str().unwrap()],
        "`[environment] g_m_s2`",
    );
    // an output that is an input is refused before anything is written
    let setup = dir.join("setup.toml");
    std::fs::copy(concat!(env!("CARGO_MANIFEST_DIR"), "/data/validation/test3.toml"), &setup).unwrap();
    let before = std::fs::read(&setup).unwrap();
    let s = setup.to_str().unwrap();
    assert_bad_input(&["synth", "--setup", s, "--runs", "2", "--out", s], "is the --setup file");
    assert_bad_input(&["simulate", "--config", s, "--particles", "5", "--trajectories", s], "is the --config file");
    assert_eq!(std::fs::read(&setup).unwrap(), before, "the input was overwritten");
    let _ = std::fs::remove_dir_all(&dir);
    assert_bad_input(&["simulate", "--design", LUNAR_C, "--env", "mars"], "mars");
    assert_bad_input(&["simulate", "--design", LUNAR_C, "--material", "cheese"], "cheese");
    // the figure is SVG or PNG by the extension: any other name is refused before simulating
    assert_bad_input(
        &["simulate", "--design", LUNAR_C, "--particles", "8", "--plot", "/tmp/sawtooth-never-written.pdf"],
        "--plot /tmp/sawtooth-never-written.pdf: the figure's format follows the file name's extension: .svg or .png",
    );
    assert!(!std::path::Path::new("/tmp/sawtooth-never-written.pdf").exists());
    assert_bad_input(&["simulate"], "no design");
    assert_bad_input(&["simulate", "--config", "/nonexistent/x.toml"], "/nonexistent/x.toml");
}

#[test]
fn malformed_toml_names_the_key() {
    let dir = std::env::temp_dir().join(format!("sawtooth-toml-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, "[sim]\nparticels = 10\n").unwrap();
    assert_bad_input(&["simulate", "--config", bad.to_str().unwrap(), "--design", LUNAR_C], "particels");
    std::fs::write(&bad, "[design\nl_c_mm = 1\n").unwrap();
    assert_bad_input(&["simulate", "--config", bad.to_str().unwrap()], "bad.toml");
    std::fs::remove_dir_all(&dir).ok();
}

/// `SAWTOOTH_SIMD` forces the cpu engine's path (to measure what other CPUs run), `bench`
/// names the path taken, and every path gives the same results to the bit: the lanes are
/// one code, held to the scalar kernel, and no path fuses a multiply-add. A path this CPU
/// lacks, a name that is none, and the retired `SAWTOOTH_CPU_LEVEL` are refused by name
/// (exit 2) before any work.
#[test]
fn every_simd_path_gives_the_same_results_and_bench_names_it() {
    use sawtooth::simd::Simd;
    let run = |simd: Option<&str>, args: &[&str]| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_sawtooth"));
        cmd.env_remove("SAWTOOTH_CPU_LEVEL");
        if let Some(simd) = simd {
            cmd.env("SAWTOOTH_SIMD", simd);
        } else {
            cmd.env_remove("SAWTOOTH_SIMD");
        }
        let out = cmd.args(args).output().expect("run binary");
        let text = |b: &[u8]| String::from_utf8_lossy(b).to_string();
        (out.status.code(), text(&out.stdout), text(&out.stderr))
    };
    let bench = ["bench", "--designs", "2", "--particles", "10", "--repeats", "1", "--engines", "cpu"];
    for env in ["lunar", "earth"] {
        let simulate = ["simulate", "--env", env, "--design", LUNAR_C, "--particles", "200", "--json"];
        let (code, widest, err) = run(None, &simulate);
        assert_eq!(code, Some(0), "{err}");
        for simd in Simd::ALL {
            let (code, out, err) = run(Some(simd.name()), &simulate);
            if simd.supported() {
                assert_eq!((code, out), (Some(0), widest.clone()), "{env}, SAWTOOTH_SIMD={}: {err}", simd.name());
            } else {
                assert_eq!(code, Some(2), "{err}");
                let named = format!("SAWTOOTH_SIMD={}: this CPU lacks", simd.name());
                assert!(err.contains(&named) && !err.contains("panicked"), "{err}");
            }
        }
    }
    for simd in Simd::ALL.into_iter().filter(|s| s.supported()) {
        let (code, out, err) = run(Some(simd.name()), &bench);
        assert_eq!(code, Some(0), "{err}");
        let cpu = out.lines().find(|l| l.starts_with("cpu: ")).unwrap_or_else(|| panic!("{out}"));
        assert!(cpu.ends_with(&format!("{})", simd.describe())), "{cpu}");
    }
    let (code, _, err) = run(Some("sse2"), &bench);
    assert_eq!(code, Some(2));
    assert!(err.contains("SAWTOOTH_SIMD=\"sse2\" is none of scalar, avx2, avx512, neon"), "{err}");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_sawtooth"));
    let out = cmd.env_remove("SAWTOOTH_SIMD").env("SAWTOOTH_CPU_LEVEL", "baseline").args(bench).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("SAWTOOTH_CPU_LEVEL") && err.contains("SAWTOOTH_SIMD=scalar"), "{err}");
}
