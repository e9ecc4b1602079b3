//! Build-time checks of the WGSL kernels (issue 16, after vello_shaders/build.rs):
//! - writes `shared/constants.wgsl` into OUT_DIR from src/kernel_codes.rs, the one
//!   declaration of the state, surface, randomisation and draw-id codes both sides use;
//! - composes every kernel exactly as the runtime does (src/engine/gpu/compose.rs) and
//!   validates it with naga, every validation flag on: a broken shader fails `cargo build`
//!   with naga's message instead of failing later at pipeline creation.

use std::path::Path;

#[allow(dead_code)]
#[path = "src/kernel_codes.rs"]
mod shared;

#[allow(dead_code)]
#[path = "src/engine/gpu/compose.rs"]
mod compose;

#[path = "src/engine/gpu/validate.rs"]
mod validate;

fn main() {
    for path in
        ["build.rs", "shaders", "src/kernel_codes.rs", "src/engine/gpu/compose.rs", "src/engine/gpu/validate.rs"]
    {
        println!("cargo:rerun-if-changed={path}");
    }
    let out_dir = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    let constants = shared::wgsl_constants();
    std::fs::write(Path::new(&out_dir).join("constants.wgsl"), &constants).expect("write constants.wgsl");

    let mut texts = Vec::new();
    for &name in compose::FILES {
        let text = if name == compose::GENERATED {
            constants.clone()
        } else {
            let path = Path::new("shaders").join(name);
            std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("read {}: {e}", path.display()))
        };
        texts.push((name, text));
    }
    let file = |p: &str| texts.iter().find(|(n, _)| *n == p).map(|(_, t)| t.as_str());
    for &kernel in compose::KERNELS {
        let source = compose::compose_with(kernel, &file).unwrap_or_else(|e| panic!("{kernel}: {e}"));
        if let Err(report) = validate::validate_wgsl(kernel, &source) {
            // naga's report (line numbers are the composed source's) on stderr, which cargo
            // shows when the build script fails
            eprintln!("{report}\nshader {kernel} does not validate (line numbers: after #import expansion)");
            std::process::exit(1);
        }
    }
}
