//! sawtooth: simulate and optimise a sawtooth conveyor for lunar regolith.
//!
//! - [`model`]: the thesis's physics (geometry, fill area, flights, restitution, performance).
//! - [`engine`]: batch evaluators behind one interface (`listing` port, fast `cpu` reference).
//! - [`io`]: configuration files, measured data, trajectory CSV, atomic writes, run folders.
//! - [`kernel_codes`]: the integer codes the Rust and WGSL kernels share (generated into WGSL).
//! - [`plot`]: the one plotting layer every figure goes through (SVG or PNG), and the flight plot.
//! - [`schema`]: the one declaration of every bounded input (counts, intervals, file sizes).
//! - [`io`]: configuration files, trajectory CSV, the flight plot.
//! - [`plot`]: the one plotting layer every figure goes through (SVG or PNG).
//! - [`dem`]: a bridge to the LIGGGHTS DEM engine: cases, campaigns, model vs DEM.
//! - [`cli`]: the thin command-line layer.
//! - [`lane`]: the lane type (one number, or AVX2, AVX-512 or NEON lanes) the SIMD code is written over.
//! - [`lane_math`]: the engine's own `exp_m1`, `sin_cos`, `atan2`, one code for scalar and lanes.
//! - [`simd`]: which instruction set the cpu engine runs on (`SAWTOOTH_SIMD`), same bits on each.

pub mod calibrate;
pub mod campaigns;
pub mod cli;
pub mod dem;
pub mod diagnose;
pub mod engine;
pub mod fit;
pub mod io;
pub mod kernel_codes;
pub mod lane;
pub mod lane_math;
pub mod model;
pub mod optim;
pub mod plot;
pub mod protocol;
pub mod scenario_request;
pub mod schema;
pub mod simd;
