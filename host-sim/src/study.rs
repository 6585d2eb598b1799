//! Studies of many generated runs in memory: [`monte_carlo`] (error statistics over independent
//! runs of one scenario) and [`compare`] (every method on every scenario, a table for
//! docs/results.md).

pub mod compare;
pub mod monte_carlo;
