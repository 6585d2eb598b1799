//! # estimator-core
//!
//! Real-time identification of the four rotation-axis installation errors `x1..x4` of a rotational
//! inertial navigation system (RINS) from its own attitude output, after Hu, Chen, Zhang and Wu,
//! "Correlation-Averaging Methods and Kalman Filter-based Parameter Identification for Rotational
//! Inertial Navigation System" (the paper; equation numbers below are the paper's).
//!
//! One sample a second goes in ([`Sample`]); an [`Output`] comes out: the four errors with their
//! 1-sigma, a [`Status`], and the attitude with eq (2)'s oscillation removed.
//!
//! Where each step of the method lives:
//! - eq (2), the oscillation model: [`installation`];
//! - eq (8), the correlation products: [`correlation`];
//! - eq (11), the one-period moving average: [`moving_average`];
//! - the sample grid (interval, jitter, clock steps): [`time_grid`]; lost samples: [`gap_fill`];
//!   the rotation pattern (period, shape, health): [`rotation_pattern`];
//! - eqs (13)-(18), the Kalman filter: [`kalman`], used by the three methods in [`methods`];
//! - input checks: [`sample`]; the sway gate: [`sway_gate`]; what one step reports: [`output`];
//!   how it all fits together: [`estimator`];
//! - attitude at the navigation rate (100-200 Hz) averaged into the grid's bins: [`binning`].
//!
//! For tests and tools, with the `synthetic` feature: RINS output for known errors (`synthetic`).
//!
//! `#![no_std]`, no allocator: every buffer has a const-generic capacity, and
//! `size_of::<Estimator>()` is checked by a test.
//!
//! # Example
//! Configure, step once a sample, read the estimate. The samples here are a ship's roll and pitch
//! sway (periods of 8 and 11 s) plus eq (2)'s oscillation for known errors, on a one-way rotation
//! of 480 s at 1 Hz; the estimator learns the interval and the period from them.
//!
//! ```
//! use core::f64::consts::TAU;
//! use estimator_core::installation::Angles;
//! use estimator_core::units::{arcsec_to_rad, rad_to_arcsec, EARTH_RATE_RAD_PER_S};
//! use estimator_core::{Config, Estimator, Real, Sample, Status};
//!
//! let x_arcsec = [200.0, -150.0, 300.0, -250.0]; // the installation errors to find
//! let x_rad = x_arcsec.map(|x| arcsec_to_rad(x) as Real);
//! let latitude_deg: f64 = 30.0;
//! let mut estimator: Estimator = Estimator::new(Config::default())?;
//! let mut last = None;
//! for k in 0..4000 {
//!     let t_s = f64::from(k);
//!     let rotation_deg = 360.0 * t_s / 480.0;
//!     let platform_deg = (EARTH_RATE_RAD_PER_S * t_s).to_degrees();
//!     let lat = latitude_deg.to_radians() as Real;
//!     let rows = Angles::new(rotation_deg.to_radians() as Real, platform_deg.to_radians() as Real, (lat.sin(), lat.cos()));
//!     let error = rows.oscillation(&x_rad); // eq (2): what the errors do to the attitude
//!     let roll_deg = 3.0 * (TAU * t_s / 8.0).sin() + f64::from(error.roll_rad).to_degrees();
//!     let pitch_deg = 1.0 * (TAU * t_s / 11.0).sin() + f64::from(error.pitch_rad).to_degrees();
//!     let heading_deg = 45.0 + f64::from(error.heading_rad).to_degrees();
//!     let sample = Sample::from_degrees(t_s, rotation_deg, platform_deg, latitude_deg, heading_deg, roll_deg, pitch_deg);
//!     // A bad sample comes back as an error and changes nothing.
//!     last = Some(estimator.step(&sample).expect("a healthy sample"));
//! }
//! let output = last.expect("4000 outputs");
//! assert_eq!(output.status, Status::Converged);
//! let estimate = output.estimate.expect("an estimate after 4000 s");
//! for i in 0..4 {
//!     let error_arcsec = rad_to_arcsec(f64::from(estimate.x_rad[i])) - x_arcsec[i];
//!     assert!(error_arcsec.abs() < 1.0, "x{}: off by {error_arcsec:.2} arcsec", i + 1);
//! }
//! # Ok::<(), estimator_core::ConfigError>(())
//! ```
#![warn(missing_docs)]
#![no_std]
#![cfg_attr(
    not(test),
    deny(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]
// `!(x > 0.0)` is how the core says "not positive, or NaN": deliberate, not a readability slip.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// Indexed loops over small fixed-size channel arrays read like the equations they implement.
#![allow(clippy::needless_range_loop)]
// `MethodState` holds the selected method inline (no allocator): its variants differ in size.
#![allow(clippy::large_enum_variant)]
// `WindowAverage::len` is the window's length, not a fill count; "empty" means nothing here.
#![allow(clippy::len_without_is_empty)]

#[cfg(test)]
extern crate std;

/// The floating-point type of the step: `f32` by default (the Cortex-M4F has a single-precision
/// FPU), `f64` with the `f64` feature. Time is always `f64`.
#[cfg(not(feature = "f64"))]
pub type Real = f32;
/// The floating-point type of the step: `f32` by default, `f64` with the `f64` feature.
#[cfg(feature = "f64")]
pub type Real = f64;

pub mod binning;
pub mod checkpoint;
pub mod code;
pub mod config;
pub mod correlation;
pub mod estimates_csv;
pub mod estimator;
pub mod gap_fill;
pub mod installation;
pub mod kalman;
pub mod learned;
pub mod math;
pub mod methods;
pub mod moving_average;
pub mod output;
pub mod rotation_pattern;
pub mod sample;
pub mod sway_gate;
#[cfg(any(test, feature = "synthetic"))]
pub mod synthetic;
pub mod time_grid;
pub mod units;

pub use code::UnknownCode;
pub use config::{Config, ConfigError, Method, Prior};
pub use estimator::{CompensateError, Estimator};
pub use output::{
    Counters, ErrorChange, Estimate, Health, Holdup, Output, RejectCounts, RotationSummary, Status,
};
pub use rotation_pattern::PatternKind;
pub use rotation_pattern::RotationFault;
pub use sample::{Attitude, Field, RejectReason, Sample, SampleError};
