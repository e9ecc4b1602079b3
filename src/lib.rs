//! sawtooth: simulate and optimise a sawtooth conveyor for lunar regolith.
//!
//! - [`model`]: the thesis's physics (geometry, fill area, flights, restitution, performance).
//! - [`engine`]: batch evaluators behind one interface (`listing` port, fast `cpu` reference).
//! - [`io`]: configuration files, trajectory CSV, the flight plot.
//! - [`plot`]: the one plotting layer every figure goes through (SVG or PNG).
//! - [`dem`]: a bridge to the LIGGGHTS DEM engine: cases, campaigns, model vs DEM.
//! - [`cli`]: the thin command-line layer.
//! - [`x86_64_v3`]: hot loops compiled a second time for AVX2 CPUs, same bits.

pub mod calibrate;
pub mod cli;
pub mod dem;
pub mod diagnose;
pub mod engine;
pub mod fit;
pub mod io;
pub mod libm_lanes;
pub mod model;
pub mod optim;
pub mod plot;
pub mod x86_64_v3;
