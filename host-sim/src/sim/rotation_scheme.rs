//! Rotation schemes of the RINS's rotation axis: the rotation angle `rho(t)` of eq (2).
//!
//! Eq (2) holds for any rotation angle `rho(t)`; the paper's RINS turns one way at a constant rate
//! (`rho = 2 pi t / 480 s`), real ones also turn back and forth or stop and go. Every scheme here
//! repeats with the rotation period `T` and is written as the angle turned since the start of the
//! log, unwrapped (the log's `rotation_deg` is it plus a start phase, wrapped to [0, 360)):
//!
//! - `continuous`: one way at a constant rate, `rho = 2 pi t / T` (+360 deg per period);
//! - `reversed`: the same the other way, `rho = -2 pi t / T`;
//! - `reciprocating`: +360 deg in `T/2` at a constant rate, then back -360 deg in `T/2`. The
//!   turnaround is instantaneous: the rate changes sign between one instant and the next, as a
//!   turntable with a stiff servo does it to within a sample;
//! - `four-position`: stop and go one way: four moves of +90 deg of [`MOVE_S`] each, each followed
//!   by a dwell of `T/4 - MOVE_S` (for `T` = 480 s: 90 deg in 15 s, dwell 105 s);
//! - `eight-position`: four moves of +90 deg (0 to 360 deg) then four of -90 deg (back to 0), each
//!   of [`MOVE_S`] and followed by a dwell of `T/8 - MOVE_S` (for `T` = 480 s: dwell 45 s).
//!
//! A period starts with a move. A move follows a cosine velocity profile: over a move of duration
//! `D` the angle advances by `90 deg * f(u)`, `u = t/D`, with `f(u) = u - sin(2 pi u) / (2 pi)`,
//! whose rate `90 deg (1 - cos(2 pi u)) / D` starts and ends at zero with zero acceleration and
//! peaks at twice the mean (12 deg/s for 90 deg in 15 s).
//!
//! A rotation period that differs from the nominal one (the `--period-error` mismatch) is passed
//! as `period_s`: the moves keep their [`MOVE_S`] and the dwells absorb the difference; when a
//! period is too short for its moves (never for the periods the command line accepts) the moves
//! take the whole step and there is no dwell.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

/// Duration of one 90 deg move of the stop-and-go schemes, s.
pub const MOVE_S: f64 = 15.0;
/// Angle of one move of the stop-and-go schemes, rad (90 deg).
pub const MOVE_RAD: f64 = PI / 2.0;

/// How the RINS turns about its rotation axis (also `--scheme`, with the names of [`Self::name`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum RotationScheme {
    /// One way (positive) at a constant rate: the paper's scheme.
    #[default]
    Continuous,
    /// One way, negative, at a constant rate.
    Reversed,
    /// +360 deg in half a period, -360 deg in the other half.
    Reciprocating,
    /// Four 90 deg moves one way, with dwells.
    FourPosition,
    /// Four 90 deg moves forward, four back, with dwells.
    EightPosition,
}

/// Moves and dwells of a stop-and-go scheme.
#[derive(Clone, Copy, Debug, PartialEq)]
struct StopAndGo {
    /// Steps (a move and a dwell) per period.
    steps: usize,
    /// Steps forward before the steps back (`steps` for a one-way scheme).
    forward_steps: usize,
}

impl RotationScheme {
    /// Every scheme, in the order tables list them.
    pub const ALL: [RotationScheme; 5] = [
        RotationScheme::Continuous,
        RotationScheme::Reversed,
        RotationScheme::Reciprocating,
        RotationScheme::FourPosition,
        RotationScheme::EightPosition,
    ];

    /// The scheme's name on the command line and in truth files.
    pub fn name(self) -> &'static str {
        match self {
            RotationScheme::Continuous => "continuous",
            RotationScheme::Reversed => "reversed",
            RotationScheme::Reciprocating => "reciprocating",
            RotationScheme::FourPosition => "four-position",
            RotationScheme::EightPosition => "eight-position",
        }
    }

    /// The scheme of a [`name`](Self::name).
    pub fn parse(name: &str) -> Option<RotationScheme> {
        RotationScheme::ALL.into_iter().find(|s| s.name() == name)
    }

    fn stop_and_go(self) -> Option<StopAndGo> {
        match self {
            RotationScheme::FourPosition => Some(StopAndGo {
                steps: 4,
                forward_steps: 4,
            }),
            RotationScheme::EightPosition => Some(StopAndGo {
                steps: 8,
                forward_steps: 4,
            }),
            _ => None,
        }
    }

    /// Dwell at each position for a period of `period_s`, s (`None`: the scheme does not stop).
    pub fn dwell_s(self, period_s: f64) -> Option<f64> {
        self.stop_and_go()
            .map(|g| (period_s / g.steps as f64 - MOVE_S).max(0.0))
    }

    /// Shortest period whose moves leave a dwell of zero or more, s (0: any period).
    pub fn min_period_s(self) -> f64 {
        self.stop_and_go().map_or(0.0, |g| g.steps as f64 * MOVE_S)
    }

    /// Net angle turned per period, rad: +2 pi (one way), -2 pi (reversed) or 0 (back and forth).
    pub fn net_rad_per_period(self) -> f64 {
        match self {
            RotationScheme::Continuous | RotationScheme::FourPosition => 2.0 * PI,
            RotationScheme::Reversed => -2.0 * PI,
            RotationScheme::Reciprocating | RotationScheme::EightPosition => 0.0,
        }
    }

    /// Angle turned since `t = 0` at time `t_s` (>= 0) for a rotation period of `period_s` (> 0),
    /// rad, unwrapped.
    pub fn rho_rad(self, t_s: f64, period_s: f64) -> f64 {
        match self {
            // Written as the generator always wrote it, so one-way logs stay bit-identical.
            RotationScheme::Continuous => 2.0 * PI / period_s * t_s,
            RotationScheme::Reversed => -(2.0 * PI / period_s * t_s),
            RotationScheme::Reciprocating => {
                let u = t_s.rem_euclid(period_s);
                let half = period_s / 2.0;
                if u < half {
                    2.0 * PI * u / half
                } else {
                    2.0 * PI * (1.0 - (u - half) / half)
                }
            }
            RotationScheme::FourPosition | RotationScheme::EightPosition => {
                let g = self.stop_and_go().unwrap_or(StopAndGo {
                    steps: 4,
                    forward_steps: 4,
                });
                let cycles = (t_s / period_s).floor();
                let u = (t_s - cycles * period_s).max(0.0);
                let step_s = period_s / g.steps as f64;
                let step = ((u / step_s).floor() as usize).min(g.steps - 1);
                let move_s = MOVE_S.min(step_s);
                let in_move = ((u - step as f64 * step_s) / move_s).clamp(0.0, 1.0);
                let f = in_move - (2.0 * PI * in_move).sin() / (2.0 * PI);
                let start_of_cycle = cycles * self.net_rad_per_period();
                let within = if step < g.forward_steps {
                    (step as f64 + f) * MOVE_RAD
                } else {
                    (g.forward_steps as f64 - (step - g.forward_steps) as f64 - f) * MOVE_RAD
                };
                start_of_cycle + within
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const T: f64 = 480.0;

    fn deg(rad: f64) -> f64 {
        rad.to_degrees()
    }

    #[test]
    fn names_round_trip() {
        for s in RotationScheme::ALL {
            assert_eq!(RotationScheme::parse(s.name()), Some(s));
            assert_eq!(
                serde_json::to_string(&s).unwrap(),
                format!("\"{}\"", s.name())
            );
        }
        assert_eq!(RotationScheme::parse("four_position"), None);
    }

    #[test]
    fn every_scheme_repeats_with_its_period_and_net_turn() {
        for s in RotationScheme::ALL {
            for period in [360.0, 480.0, 720.0] {
                for t in [0.0, 3.0, 14.0, 100.0, 239.5, 241.0, 300.0, 359.0] {
                    let d = s.rho_rad(t + 2.0 * period, period) - s.rho_rad(t, period);
                    assert!(
                        (d - 2.0 * s.net_rad_per_period()).abs() < 1e-9,
                        "{} T {period} t {t}: {d}",
                        s.name()
                    );
                }
            }
            assert_eq!(s.rho_rad(0.0, T), 0.0, "{}", s.name());
        }
    }

    #[test]
    fn one_way_schemes_turn_at_constant_rate_in_their_direction() {
        for t in [0.0, 1.0, 100.0, 1000.5] {
            assert_eq!(RotationScheme::Continuous.rho_rad(t, T), 2.0 * PI / T * t);
            assert_eq!(RotationScheme::Reversed.rho_rad(t, T), -2.0 * PI / T * t);
        }
        assert!((deg(RotationScheme::Continuous.rho_rad(120.0, T)) - 90.0).abs() < 1e-12);
        assert!((deg(RotationScheme::Reversed.rho_rad(120.0, T)) + 90.0).abs() < 1e-12);
    }

    #[test]
    fn reciprocating_goes_out_360_and_back_at_constant_rate() {
        let s = RotationScheme::Reciprocating;
        assert!((deg(s.rho_rad(60.0, T)) - 90.0).abs() < 1e-9);
        assert!((deg(s.rho_rad(239.0, T)) - 358.5).abs() < 1e-9);
        assert!(
            (deg(s.rho_rad(240.0, T)) - 360.0).abs() < 1e-9,
            "turnaround at T/2"
        );
        assert!((deg(s.rho_rad(241.0, T)) - 358.5).abs() < 1e-9);
        assert!((deg(s.rho_rad(420.0, T)) - 90.0).abs() < 1e-9);
        // 1.5 deg/s out, -1.5 deg/s back.
        for t in [10.0, 100.0, 230.0] {
            assert!((deg(s.rho_rad(t + 1.0, T) - s.rho_rad(t, T)) - 1.5).abs() < 1e-9);
            assert!((deg(s.rho_rad(t + 241.0, T) - s.rho_rad(t + 240.0, T)) + 1.5).abs() < 1e-9);
        }
    }

    /// Times (on a 0.5 s grid over one period) at which the angle does not move, as runs
    /// (start, length, angle deg).
    fn dwells(s: RotationScheme, period: f64) -> Vec<(f64, f64, f64)> {
        let mut runs: Vec<(f64, f64, f64)> = Vec::new();
        let dt = 0.5;
        let n = (period / dt) as usize;
        for k in 0..n {
            let t = k as f64 * dt;
            let (a, b) = (s.rho_rad(t, period), s.rho_rad(t + dt, period));
            if a == b {
                match runs.last_mut() {
                    Some(r) if (r.0 + r.1 - t).abs() < 1e-9 => r.1 += dt,
                    _ => runs.push((t, dt, deg(a))),
                }
            }
        }
        runs
    }

    #[test]
    fn four_position_dwells_at_four_positions_after_15_s_moves() {
        let s = RotationScheme::FourPosition;
        assert_eq!(s.dwell_s(T), Some(105.0));
        let runs = dwells(s, T);
        assert_eq!(runs.len(), 4, "{runs:?}");
        for (i, (start, len, angle)) in runs.iter().enumerate() {
            assert!((start - (i as f64 * 120.0 + 15.0)).abs() < 1e-9, "{runs:?}");
            assert!((len - 105.0).abs() < 1e-9, "{runs:?}");
            assert!((angle - 90.0 * (i + 1) as f64).abs() < 1e-9, "{runs:?}");
        }
        // The moves only go forward, smoothly: zero rate at both ends, 12 deg/s in the middle.
        for k in 0..150 {
            let t = k as f64 * 0.1;
            assert!(s.rho_rad(t + 0.1, T) > s.rho_rad(t, T));
        }
        let mid_rate = deg(s.rho_rad(7.55, T) - s.rho_rad(7.45, T)) / 0.1;
        assert!((mid_rate - 12.0).abs() < 0.01, "{mid_rate}");
        let start_rate = deg(s.rho_rad(0.01, T)) / 0.01;
        assert!(start_rate < 0.01, "{start_rate}");
        // Next period: four more positions further on.
        assert!((deg(s.rho_rad(T + 20.0, T)) - 450.0).abs() < 1e-9);
    }

    #[test]
    fn eight_position_goes_four_steps_out_and_four_back() {
        let s = RotationScheme::EightPosition;
        assert_eq!(s.dwell_s(T), Some(45.0));
        let runs = dwells(s, T);
        assert_eq!(runs.len(), 8, "{runs:?}");
        let angles = [90.0, 180.0, 270.0, 360.0, 270.0, 180.0, 90.0, 0.0];
        for (i, (start, len, angle)) in runs.iter().enumerate() {
            assert!((start - (i as f64 * 60.0 + 15.0)).abs() < 1e-9, "{runs:?}");
            assert!((len - 45.0).abs() < 1e-9, "{runs:?}");
            assert!((angle - angles[i]).abs() < 1e-9, "{runs:?}");
        }
        // Out during the first half's moves, back during the second half's.
        assert!(s.rho_rad(5.1, T) > s.rho_rad(5.0, T));
        assert!(s.rho_rad(245.1, T) < s.rho_rad(245.0, T));
        assert_eq!(RotationScheme::EightPosition.min_period_s(), 120.0);
        assert_eq!(RotationScheme::FourPosition.min_period_s(), 60.0);
    }

    #[test]
    fn period_error_lengthens_the_dwells_not_the_moves() {
        let s = RotationScheme::FourPosition;
        let period = T * 1.01;
        let runs = dwells(s, period);
        assert_eq!(runs.len(), 4);
        assert!((runs[0].0 - 15.0).abs() < 1e-9);
        assert!((s.dwell_s(period).unwrap() - (period / 4.0 - 15.0)).abs() < 1e-12);
        // Too short a period: moves fill the steps, no dwell, still 360 deg per period.
        assert_eq!(RotationScheme::EightPosition.dwell_s(100.0), Some(0.0));
        let d = RotationScheme::FourPosition.rho_rad(50.0 + 40.0, 40.0)
            - RotationScheme::FourPosition.rho_rad(50.0, 40.0);
        assert!((d - 2.0 * PI).abs() < 1e-9);
    }
}
