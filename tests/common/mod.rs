//! Helpers shared by the integration tests: the binary as a command, scratch folders, the
//! figures the CLI writes, the test tiers, and ([`campaigns`]) synthetic measurement
//! campaigns diagnosed by the CLI.
// each test binary includes this module and uses a part of it
#![allow(dead_code)]

pub mod campaigns;

use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root: where the tests' relative paths (`data/...`, `examples/...`) point.
pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The `sawtooth` binary of this build as a command, run from the repository root.
pub fn sawtooth() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_sawtooth"));
    c.current_dir(repo());
    c
}

/// `sawtooth args` from the repository root, to its end: exit code, stdout, stderr. Outside
/// a Slurm array task even when the tests run inside one (`campaign run` reads the task).
pub fn run(args: &[&str]) -> (i32, String, String) {
    let o = sawtooth().args(args).env_remove("SLURM_ARRAY_TASK_ID").output().expect("run the sawtooth binary");
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

/// A path under the temporary directory for a folder the test's command makes itself,
/// named after the calling test file, `tag` and this process; whatever an earlier run left
/// there is removed. Every file of `tests/` is a module of one test binary, so two files
/// may use the same tag at the same time: the file's name keeps their folders apart.
#[track_caller]
pub fn fresh_dir(tag: &str) -> PathBuf {
    let file = Path::new(std::panic::Location::caller().file());
    let module = file.file_stem().and_then(|s| s.to_str()).unwrap_or("test");
    let d = std::env::temp_dir().join(format!("sawtooth-{module}-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

/// [`fresh_dir`], made: an empty scratch folder for the test's own files.
#[track_caller]
pub fn scratch(tag: &str) -> PathBuf {
    let d = fresh_dir(tag);
    std::fs::create_dir_all(&d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
    d
}

/// The `<text>` contents of an SVG document (trimmed).
pub fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| Some(t[t.find('>')? + 1..t.find("</text>")?].trim().to_string()))
        .collect()
}

/// The figure has real axes: at least `n` numeric tick labels, and every `label`.
pub fn assert_figure(svg: &str, n: usize, labels: &[&str]) {
    let texts = svg_texts(svg);
    assert!(texts.iter().filter(|t| t.parse::<f64>().is_ok()).count() >= n, "too few tick labels: {texts:?}");
    for l in labels {
        assert!(texts.iter().any(|t| t == l), "`{l}` missing: {texts:?}");
    }
}

/// A run folder's figure exists in both formats: `stem.png` beside `stem.svg`, a real PNG
/// (signature, IHDR) with the SVG's pixel size, drawn (more than a blank page of bytes).
pub fn assert_png_beside(svg_path: &std::path::Path) {
    let svg = std::fs::read_to_string(svg_path).unwrap_or_else(|e| panic!("{}: {e}", svg_path.display()));
    let png_path = svg_path.with_extension("png");
    let png = std::fs::read(&png_path).unwrap_or_else(|e| panic!("{}: {e}", png_path.display()));
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{} is not a PNG", png_path.display());
    assert_eq!(&png[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    let attr = |name: &str| -> u32 {
        let at = svg.find(&format!("{name}=\"")).expect("svg size attribute") + name.len() + 2;
        svg[at..at + svg[at..].find('"').unwrap()].parse().expect("integer svg size")
    };
    assert_eq!((be(&png[16..20]), be(&png[20..24])), (attr("width"), attr("height")), "{}", png_path.display());
    assert!(png.len() > 5000, "{} holds only {} bytes", png_path.display(), png.len());
}

/// Whether the heavy tests run: the full tier (`bash scripts/test.sh` sets
/// `SAWTOOTH_TEST_TIER=full`) or CI (`CI=true`, where nothing may be left out). Plain
/// `cargo test` is the fast tier; there a heavy test says on stderr that it was skipped and
/// how to run it, written past libtest's output capture so that it shows on a passing run.
pub fn full_tier(test: &str, why_heavy: &str) -> bool {
    let full = std::env::var("SAWTOOTH_TEST_TIER").is_ok_and(|v| v == "full")
        || std::env::var("CI").is_ok_and(|v| v == "true");
    if !full {
        use std::io::Write;
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED {test} (fast tier; {why_heavy}): runs in the full tier, `bash scripts/test.sh`, \
             or with SAWTOOTH_TEST_TIER=full cargo test --release --test suite {test}"
        );
    }
    full
}

/// The GPU engine on whatever Vulkan adapter the machine has (lavapipe in the full tier), or
/// None where there is none: the GPU tests then skip and say so, except with CI=true, where
/// a missing adapter fails them (scripts/test.sh installs lavapipe first).
pub fn gpu_engine() -> Option<sawtooth::engine::gpu::GpuEngine> {
    use sawtooth::engine::gpu::{AdapterChoice, GpuEngine};
    match GpuEngine::new(AdapterChoice::Any) {
        Ok(g) => Some(g),
        Err(e) => {
            if std::env::var("CI").is_ok_and(|v| v == "true") {
                panic!("CI=true but no Vulkan adapter: {e:#}");
            }
            eprintln!("skipping GPU test (no Vulkan adapter; scripts/test.sh installs lavapipe): {e:#}");
            None
        }
    }
}
