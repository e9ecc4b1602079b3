//! Finding and running LIGGGHTS on a written case.
//!
//! The binary is `$SAWTOOTH_LIGGGHTS` when set, else `liggghts` on the PATH (Debian's
//! package `liggghts`). It runs in the case folder with `-in in.sawtooth -log log.liggghts`
//! and its screen output is kept in `screen.liggghts`. The screen is not switched off:
//! `-screen none` crashed LIGGGHTS 3.8 while it read the STL (issue 31). Its stdout is made
//! line-buffered through `stdbuf` where coreutils has it: an error makes LIGGGHTS call
//! MPI_Abort, which loses a block-buffered stdout and with it the error line.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{bail, Context as _};

use super::case::{ALL_LOST, DUMP, SCRIPT, STROKE_START, STROKE_TIME, TRACK};

/// Environment variable naming the LIGGGHTS binary (overrides the PATH lookup).
pub const BINARY_ENV: &str = "SAWTOOTH_LIGGGHTS";
pub const SCREEN: &str = "screen.liggghts";
pub const LOG: &str = "log.liggghts";

fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path).map(|d| d.join(name)).find(|p| p.is_file())
}

/// The LIGGGHTS binary, or a message that says how to get it and what works without it.
pub fn find_liggghts() -> anyhow::Result<PathBuf> {
    if let Some(p) = std::env::var_os(BINARY_ENV) {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        bail!(
            "{BINARY_ENV}={} is not a file: point it at the LIGGGHTS binary, or unset it to use `liggghts` from the PATH (Debian package `liggghts`: apt-get install liggghts); `sawtooth dem write` writes the case without running it",
            p.display()
        );
    }
    on_path("liggghts").context(
        "LIGGGHTS not found: no `liggghts` on the PATH. Install the Debian package `liggghts` (apt-get install liggghts) or set SAWTOOTH_LIGGGHTS to the binary; `sawtooth dem write --config C.toml --out DIR` writes the case to run elsewhere (cd DIR && liggghts -in in.sawtooth)",
    )
}

/// One thermo line's numbers: step, grains left, kinetic energy (J), RMS speed (m/s), stroke
/// time (s; negative while settling).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thermo {
    pub step: u64,
    pub atoms: u64,
    pub rms_speed_m_s: f64,
    pub stroke_time_s: f64,
}

/// A thermo line of the case's `thermo_style custom step atoms ke v_vrms v_t`, or None.
pub fn parse_thermo(line: &str) -> Option<Thermo> {
    let f: Vec<&str> = line.split_whitespace().collect();
    if f.len() != 5 {
        return None;
    }
    Some(Thermo {
        step: f[0].parse().ok()?,
        atoms: f[1].parse().ok()?,
        rms_speed_m_s: f[3].parse().ok()?,
        stroke_time_s: f[4].parse().ok()?,
    })
}

/// The first `ERROR` line of LIGGGHTS's output (with the line after it when the message
/// continues there), if any.
pub fn error_line(output: &str) -> Option<String> {
    let lines: Vec<&str> = output.lines().collect();
    let i = lines.iter().position(|l| l.contains("ERROR"))?;
    Some(lines[i].trim().to_string())
}

/// How a run went.
#[derive(Clone, Debug)]
pub struct Finished {
    pub wall_s: f64,
    pub last: Option<Thermo>,
}

/// Run the case in `dir`, calling `progress` with each thermo line. A failure names the
/// LIGGGHTS error line and keeps the folder.
pub fn run_case(binary: &Path, dir: &Path, progress: &mut dyn FnMut(&Thermo)) -> anyhow::Result<Finished> {
    let _ = std::fs::remove_file(dir.join(DUMP));
    let _ = std::fs::remove_file(dir.join(STROKE_TIME));
    let _ = std::fs::remove_file(dir.join(ALL_LOST));
    let _ = std::fs::remove_file(dir.join(TRACK));
    let _ = std::fs::remove_file(dir.join(STROKE_START));
    let started = Instant::now();
    let mut cmd = match on_path("stdbuf") {
        Some(stdbuf) => {
            let mut c = Command::new(stdbuf);
            c.arg("-oL").arg(binary);
            c
        }
        None => Command::new(binary),
    };
    cmd.args(["-in", SCRIPT, "-log", LOG])
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().with_context(|| format!("starting {}", binary.display()))?;
    let stdout = child.stdout.take().expect("piped");
    let stderr = child.stderr.take().expect("piped");
    // stderr on its own thread, so that neither pipe fills while the other is read
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut BufReader::new(stderr), &mut s);
        s
    });
    let screen_path = dir.join(SCREEN);
    let mut screen =
        std::fs::File::create(&screen_path).with_context(|| format!("creating {}", screen_path.display()))?;
    let mut text = String::new();
    let mut last = None;
    for line in BufReader::new(stdout).lines() {
        let line = line.unwrap_or_default();
        let _ = writeln!(screen, "{line}");
        if let Some(t) = parse_thermo(&line) {
            progress(&t);
            last = Some(t);
        }
        text.push_str(&line);
        text.push('\n');
    }
    let status = child.wait().context("waiting for LIGGGHTS")?;
    let err = err_reader.join().unwrap_or_default();
    let _ = screen.write_all(err.as_bytes());
    let all = format!("{text}{err}");
    if let Some(e) = error_line(&all) {
        bail!(
            "LIGGGHTS failed in {}: {e} (the case folder is kept; its output is in {})",
            dir.display(),
            screen_path.display()
        );
    }
    if !status.success() {
        bail!(
            "LIGGGHTS exited with {status} in {} without an ERROR line (the case folder is kept; output in {})",
            dir.display(),
            screen_path.display()
        );
    }
    if !dir.join(DUMP).is_file() && !dir.join(ALL_LOST).is_file() {
        bail!(
            "LIGGGHTS finished in {} but wrote neither {DUMP} nor {ALL_LOST} (output in {})",
            dir.display(),
            screen_path.display()
        );
    }
    Ok(Finished { wall_s: started.elapsed().as_secs_f64(), last })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thermo_lines_are_read_and_other_lines_are_not() {
        let t = parse_thermo("   12000      150 1.2e-07  0.0123  -0.5").unwrap();
        assert_eq!((t.step, t.atoms), (12000, 150));
        assert_eq!(t.rms_speed_m_s, 0.0123);
        assert!(parse_thermo("Step Atoms KinEng vrms t").is_none());
        assert!(parse_thermo("Loop time of 0.06 on 1 procs for 5000 steps with 3 atoms").is_none());
    }

    #[test]
    fn the_error_line_is_found() {
        let out = "Reading STL file\nERROR: Illegal fix mesh/surface command (fix_mesh.cpp:42)\nMPI_ABORT";
        assert_eq!(error_line(out).unwrap(), "ERROR: Illegal fix mesh/surface command (fix_mesh.cpp:42)");
        assert!(error_line("all fine").is_none());
    }
}
