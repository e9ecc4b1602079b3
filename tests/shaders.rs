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

/// The records shared with the host (shaders/shared/types.wgsl) have the size of their Rust
/// twins (src/engine/gpu/layout.rs), and every WGSL field is a 4-byte scalar at offset
/// 4 × index: no implicit padding on the WGSL side, so equal sizes mean equal layouts as
/// long as the field order is kept in sync.
#[test]
fn shared_records_match_their_rust_twins() {
    use sawtooth::engine::gpu::layout::{GpuDesign, GpuOutcome, GpuParticle, GpuPhysics};
    let src = compose("particles.wgsl").unwrap();
    let module = naga::front::wgsl::parse_str(&src).unwrap();
    for (name, rust_size) in [
        ("Physics", std::mem::size_of::<GpuPhysics>()),
        ("Design", std::mem::size_of::<GpuDesign>()),
        ("Particle", std::mem::size_of::<GpuParticle>()),
        ("Outcome", std::mem::size_of::<GpuOutcome>()),
    ] {
        let (members, span) = module
            .types
            .iter()
            .find_map(|(_, t)| match &t.inner {
                naga::TypeInner::Struct { members, span } if t.name.as_deref() == Some(name) => {
                    Some((members.clone(), *span))
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("struct {name} not found"));
        assert_eq!(span as usize, rust_size, "{name}: WGSL {span} bytes, Rust {rust_size}");
        assert_eq!(span % 16, 0, "{name}: pad to a multiple of 16 bytes");
        for (i, m) in members.iter().enumerate() {
            assert_eq!(m.offset as usize, 4 * i, "{name}.{:?}: not a packed 4-byte scalar", m.name);
        }
    }
}
