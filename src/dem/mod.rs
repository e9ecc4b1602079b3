//! A bridge to a real discrete-element engine, LIGGGHTS 3.8 (issue 31; thesis 6.1 names a
//! DEM simulation as the next step). The model's own geometry, fill and sled motion become a
//! LIGGGHTS case; the engine's end positions become tooth masses in the measured-data format,
//! so `fit`, `diagnose` and `dem compare` read a DEM campaign as they read a rig's.
//!
//! One idea per file:
//! - [`settings`]: what a DEM case needs beyond the scenario (`[dem]`, flags), with its rules;
//! - [`stl`]: the tooth profile extruded over a periodic depth, as an STL mesh;
//! - [`grains`]: the grains placed in tooth 0's fill polygon;
//! - [`sizes`]: the polydisperse size law as size classes of equal mass, each with its drag;
//! - [`contact`]: contact parameters from the material, the softened modulus, the time step;
//! - [`motion`]: the sled's motion (stroke, optional return) as mesh velocities;
//! - [`case`]: the LIGGGHTS input script and the case folder;
//! - [`conveyor`]: steady conveying, K cycles on a periodic conveyor of full teeth;
//! - [`doe`]: a design of experiments, designs spread over the optimiser's space, as a check's plan;
//! - [`refine`]: convergence, the campaign again at half the overlap and twice the grains;
//! - [`run`]: finding and running LIGGGHTS, progress, errors;
//! - [`gather`]: the dump read back, grains assigned to teeth, the campaign's CSV and setup;
//! - [`compare`]: the model beside the DEM;
//! - [`impact`]: single grains in LIGGGHTS beside the model's restitution law, and the DEM's
//!   law measured for the model (`ContactLaw::Dem`).
//!
//! Coordinates: the model's global frame (x along the horizontal, y up, tooth 0's p1 at the
//! origin, the conveyor tilted by α as in Eq. 4.21), and z the periodic depth. Gravity is
//! therefore straight down, and the mesh carries the slope.

pub mod campaign;
pub mod case;
pub mod check;
pub mod compare;
pub mod contact;
pub mod conveyor;
pub mod doe;
pub mod gather;
pub mod grains;
pub mod impact;
pub mod losses;
pub mod motion;
pub mod refine;
pub mod run;
pub mod settings;
pub mod sizes;
pub mod stl;

pub use case::{Case, CaseFiles};
pub use settings::DemSettings;
