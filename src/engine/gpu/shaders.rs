//! WGSL sources, composed with a tiny `#import shared/x.wgsl` preprocessor (as vello does):
//! each import is replaced by the file's text, once.

/// (path relative to shaders/, text), embedded at compile time.
pub const FILES: &[(&str, &str)] = &[
    ("particles.wgsl", include_str!("../../../shaders/particles.wgsl")),
    ("shared/types.wgsl", include_str!("../../../shaders/shared/types.wgsl")),
    ("shared/rng.wgsl", include_str!("../../../shaders/shared/rng.wgsl")),
    ("shared/flight.wgsl", include_str!("../../../shaders/shared/flight.wgsl")),
    ("shared/trig.wgsl", include_str!("../../../shaders/shared/trig.wgsl")),
];

/// Entry-point files (the others are only imported).
pub const KERNELS: &[&str] = &["particles.wgsl"];

fn file(path: &str) -> Option<&'static str> {
    FILES.iter().find(|(p, _)| *p == path).map(|(_, t)| *t)
}

/// The source of `path` with its imports expanded.
pub fn compose(path: &str) -> Result<String, String> {
    let mut seen = Vec::new();
    expand(path, &mut seen)
}

fn expand(path: &str, seen: &mut Vec<String>) -> Result<String, String> {
    let text = file(path).ok_or_else(|| format!("unknown shader file `{path}`"))?;
    seen.push(path.to_string());
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        if let Some(rest) = line.trim().strip_prefix("#import ") {
            let import = rest.trim();
            if !seen.iter().any(|s| s == import) {
                out.push_str(&expand(import, seen)?);
            }
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    Ok(out)
}
