//! # estimator-core
//!
//! Real-time identification of the four rotation-axis installation errors `x1..x4` of a rotational
//! inertial navigation system (RINS) from its own attitude output, after Hu, Chen, Zhang and Wu,
//! "Correlation-Averaging Methods and Kalman Filter-based Parameter Identification for Rotational
//! Inertial Navigation System" (the paper; equation numbers below are the paper's).
//!
//! One sample a second goes in ([`Sample`]); an [`Output`] comes out: the four errors with their
//! 1-sigma, a [`Status`], and the attitude with eq (2)'s oscillation removed.
//! The method and its derivation: docs/method.md; what it achieves: docs/results.md.
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
//! Configure, step once a sample, read the estimate: the example of [`Estimator`].
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
