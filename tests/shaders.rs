//! Every WGSL kernel parses and validates with naga (no GPU needed).

use sawtooth::engine::gpu::shaders::{compose, FILES, KERNELS};

#[test]
fn every_kernel_parses_and_validates() {
    for k in KERNELS {
        let src = compose(k).unwrap();
        let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{k}: {}", e.emit_to_string(&src)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{k}: {}", e.emit_to_string(&src)));
    }
}

#[test]
fn every_shared_file_is_imported_by_some_kernel() {
    let composed: String = KERNELS.iter().map(|k| compose(k).unwrap()).collect();
    for (path, text) in FILES {
        let first = text.lines().find(|l| l.starts_with("fn ") || l.starts_with("struct ")).unwrap_or("");
        assert!(composed.contains(first), "{path} is never imported");
    }
}
