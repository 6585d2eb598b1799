//! Generated logs: what a RINS on a ship would log for known installation errors, and what its
//! data recorder makes of it.
//!
//! - [`scenario`]: the three scenarios' parameters, and a generated log held whole;
//! - [`samples`]: the generator of eq (3), one row per sample instant with its truth;
//! - [`ship_motion`]: the ship's slow motions (turns, heading weave, slow heel and trim);
//! - [`rotation_scheme`]: how the RINS turns within a rotation period (the angle `rho(t)` of
//!   eq (2));
//! - [`recorder`]: what reaches the log of those rows (lost rows, outages, loose time stamps).

pub mod recorder;
pub mod rotation_scheme;
pub mod samples;
pub mod scenario;
pub mod ship_motion;
