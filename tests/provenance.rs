//! The repository's source is the project's own (issue 33; LICENSE-MIT, LICENSE-APACHE):
//! no source file carries another project's copyright or licence header, and none holds
//! the constants that mark code taken from glibc's libm (its `sincos` table and
//! coefficients, its `atan2` table and coefficients, fdlibm's `expm1` coefficients), which
//! the engine carried until its own functions replaced them (`src/lane_math.rs`).
//!
//! The markers are spliced from pieces so that this file does not match itself, and the
//! scanner is held against planted text first, so the test can fail.

use std::path::{Path, PathBuf};

/// Words that open another project's copyright or licence notice.
fn header_markers() -> Vec<String> {
    [
        ["Copy", "right (C)"],
        ["Copy", "right (c)"],
        ["Copy", "right ©"],
        ["SPDX-License", "-Identifier"],
        ["All rights ", "reserved"],
        ["GNU Lesser General ", "Public License"],
        ["GNU General ", "Public License"],
        ["Free Software ", "Foundation"],
        ["Sun Micro", "systems"],
        ["IBM Accurate Mathematical ", "Library"],
        ["Permission to use, copy, ", "modify"],
        ["This file is part of the ", "GNU C Library"],
        ["Licensed under the Apache License, ", "Version"],
    ]
    .iter()
    .map(|p| p.concat())
    .collect()
}

/// Bit patterns (as 16 lowercase hex digits) and decimal digits that occur in glibc's and
/// fdlibm's libm and in no formula the project needs: a file holding one copied them.
fn foreign_constants() -> Vec<String> {
    [
        // glibc sincos: the polynomial tails, the three-piece π/2 and the first table rows
        ["3f81111111", "110ece"],
        ["bf2a01a019", "db08b8"],
        ["3ec71de27b", "9a7ed9"],
        ["be5addffc2", "fcdf59"],
        ["3ff921fb58", "000000"],
        ["be4dde973c", "000000"],
        ["bc8cb3b398", "000000"],
        ["bacd747f23", "e32ed7"],
        ["3f811110e8", "29872f"],
        ["3f56c16bed", "d9e239"],
        // glibc atan2: the polynomial and the first rows of its table
        ["3fc9999999", "9997fd"],
        ["bfc2492492", "3f7603"],
        ["3fbc71c6e5", "129a3b"],
        ["bfb7458022", "b13c25"],
        ["3fb375f08b", "31cbce"],
        ["3fb0400665", "e0244e"],
        ["3fb03a737b", "53dd20"],
        ["3fefdf1fcf", "5cfb72"],
        // fdlibm expm1: its Q1-Q5 in bits and in decimal
        ["bfa1111111", "1110f4"],
        ["3f5a01a019", "fe5585"],
        ["bf14ce199e", "aadbb7"],
        ["3ed0cfca86", "e65239"],
        ["be8afdb76e", "09c32d"],
        ["3.333333333", "33331316428"],
        ["1.587301587", "25481460165"],
        ["7.936507578", "67487942473"],
    ]
    .iter()
    .map(|p| p.concat())
    .collect()
}

/// What in `text` marks it as taken from elsewhere: each marker found, by name.
fn findings(text: &str) -> Vec<String> {
    let mut found: Vec<String> = header_markers().into_iter().filter(|m| text.contains(m.as_str())).collect();
    // digits compared without Rust's `_` separators and in lower case
    let digits: String = text.chars().filter(|&c| c != '_').collect::<String>().to_lowercase();
    found.extend(foreign_constants().into_iter().filter(|c| digits.contains(c.as_str())));
    found
}

/// The source files: code, shaders, scripts and build files under the repository root,
/// not the build output, virtual environments, licence texts or documents.
fn source_files(root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if path.is_dir() {
                let skipped =
                    name.starts_with('.') || ["target", "node_modules", "__pycache__"].contains(&name.as_str());
                if !skipped && !name.contains("venv") {
                    stack.push(path);
                }
            } else if ["rs", "wgsl", "py", "sh", "toml", "pyi", "cfg"]
                .iter()
                .any(|ext| path.extension().is_some_and(|e| e == *ext))
            {
                out.push(path);
            }
        }
    }
    out.sort();
    out
}

/// The scanner finds each kind of marker in planted text, and none in the project's own
/// kind of text: without this a broken scanner would pass any tree.
#[test]
fn the_scanner_finds_planted_headers_and_constants() {
    let header = format!("/* {} 1991 Someone.\n   {} */\nint f;", header_markers()[0], header_markers()[4]);
    assert_eq!(findings(&header).len(), 2, "{header}");
    let spaced = &foreign_constants()[0];
    let planted = format!("const S2: f64 = f64::from_bits(0x{}_{});", &spaced[..4], &spaced[4..]);
    assert_eq!(findings(&planted), vec![spaced.clone()], "{planted}");
    let decimal = format!("Q1 = -{}e-02", foreign_constants().last().unwrap());
    assert_eq!(findings(&decimal).len(), 1, "{decimal}");
    let own = "/// sin r = r + r³ S(r²): a near-minimax fit (scripts/fit_polynomials.py)\nconst PI: f64 = 0x3ff921fb54442d18;";
    assert!(findings(own).is_empty(), "{:?}", findings(own));
}

/// No source file of the repository carries a foreign header or glibc's constants.
#[test]
fn no_source_file_is_taken_from_another_project() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let files = source_files(root);
    assert!(
        files.iter().any(|f| f.ends_with("src/lane_math.rs")) && files.len() > 50,
        "the scan reached the sources: {} files",
        files.len()
    );
    let mut bad = Vec::new();
    for f in &files {
        if f.ends_with("tests/provenance.rs") {
            continue; // the markers' pieces
        }
        let Ok(text) = std::fs::read_to_string(f) else { continue }; // not UTF-8: not source
        let found = findings(&text);
        if !found.is_empty() {
            bad.push(format!("{}: {found:?}", f.strip_prefix(root).unwrap().display()));
        }
    }
    assert!(bad.is_empty(), "source files with another project's marks:\n{}", bad.join("\n"));
    for licence in ["LICENSE-MIT", "LICENSE-APACHE"] {
        assert!(root.join(licence).is_file(), "{licence} is missing");
    }
}
