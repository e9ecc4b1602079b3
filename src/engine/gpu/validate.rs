//! Parse and validate a composed WGSL module with naga, every validation flag on (as vello's
//! build script does). Run by build.rs on every kernel, so a broken shader fails
//! `cargo build` with naga's message, and by tests/shaders.rs (also on deliberately broken
//! sources). build.rs includes this file with `#[path]`: keep it free of crate paths.

/// The validated module, or naga's report (with the offending source lines) as text.
pub fn validate_wgsl(name: &str, source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: WGSL parse error\n{}", e.emit_to_string_with_path(source, name)))?;
    naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::default())
        .validate(&module)
        .map_err(|e| format!("{name}: WGSL validation error\n{}", e.emit_to_string_with_path(source, name)))?;
    Ok(module)
}
