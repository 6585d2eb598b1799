//! The generator of eq (3): the rows of a scenario and their truth, one sample instant at a time
//! ([`Samples`]), so a log of millions of rows can be written without holding it; eq (2) in
//! `f64` ([`oscillation_rad`]), the truth the core's `f32` implementation is tested against.

use crate::sim::scenario::{sway, Row, RowTruth, ScenarioParams};
use crate::sim::ship_motion::{turns, weave};
use estimator_core::units::{arcsec_to_rad, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Earth radius for the latitude drift of a moving ship, m.
const EARTH_RADIUS_M: f64 = 6_371_000.0;

/// Eq (2) in f64: (heading, roll, pitch) errors in rad for errors `x` in rad.
pub fn oscillation_rad(x: &[f64; 4], rho: f64, s: f64, lat: f64) -> [f64; 3] {
    let (sl, cl) = lat.sin_cos();
    let (sr, cr) = rho.sin_cos();
    let (srs, crs) = (rho - s).sin_cos();
    [
        -x[0] * cl * crs - x[1] * cl * srs - x[2] * sl * sr + x[3] * sl * cr,
        -x[0] * sl * crs - x[1] * sl * srs + x[2] * cl * sr - x[3] * cl * cr,
        x[0] * srs - x[1] * crs,
    ]
}

/// The rows of a scenario and their truth, one sample instant at a time (`k * sample_interval_s`,
/// `k = 0, 1, ...` while below `duration_s`).
pub struct Samples<'a> {
    p: &'a ScenarioParams,
    rng: ChaCha8Rng,
    white: Normal<f64>,
    jitter: Normal<f64>,
    lf: Vec<[f64; 5]>,
    w_lf: f64,
    gm_sigma: f64,
    gm_a: f64,
    gm_drive: Normal<f64>,
    gm: [f64; 3],
    /// True rotation period (nominal with the period error), s.
    period_s: f64,
    north_rate_rad_s: f64,
    /// The roll and pitch the rotating gyro bias has tilted the attitude by so far, rad.
    gyro_tilt_rad: [f64; 2],
    k: usize,
    n: usize,
}

impl<'a> Samples<'a> {
    /// The rows of `p`, from its first sample instant.
    pub fn new(p: &'a ScenarioParams) -> Samples<'a> {
        let mut rng =
            ChaCha8Rng::seed_from_u64(p.seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xA77_17D3);
        let white = Normal::new(0.0, arcsec_to_rad(p.noise_arcsec).max(0.0))
            .unwrap_or(Normal::new(0.0, 0.0).unwrap());
        let jitter = Normal::new(0.0, (p.mismatch.rotation_jitter_deg * RAD_PER_DEG).max(0.0))
            .unwrap_or(Normal::new(0.0, 0.0).unwrap());
        // Eq (5) coefficients per axis (heading, roll, pitch): random directions with norm = amplitude.
        let lf_amp = p.low_frequency_deg * RAD_PER_DEG;
        let lf: Vec<[f64; 5]> = (0..3)
            .map(|_| {
                let v: [f64; 5] = core::array::from_fn(|_| rng.gen_range(-1.0..1.0));
                let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt().max(1e-9);
                core::array::from_fn(|i| v[i] / norm * lf_amp)
            })
            .collect();
        let w_lf = EARTH_RATE_RAD_PER_S * (1.0 + p.mismatch.low_frequency_rate_error);
        let gm_tau = 60.0;
        let gm_sigma = arcsec_to_rad(p.mismatch.coloured_noise_arcsec);
        let gm_a = (-p.sample_interval_s / gm_tau).exp();
        let gm_drive = Normal::new(0.0, (gm_sigma * (1.0 - gm_a * gm_a).sqrt()).max(0.0))
            .unwrap_or(Normal::new(0.0, 0.0).unwrap());
        let mut gm = [0.0f64; 3];
        if gm_sigma > 0.0 {
            let init = Normal::new(0.0, gm_sigma).unwrap_or(Normal::new(0.0, 0.0).unwrap());
            for g in &mut gm {
                *g = init.sample(&mut rng);
            }
        }
        Samples {
            p,
            rng,
            white,
            jitter,
            lf,
            w_lf,
            gm_sigma,
            gm_a,
            gm_drive,
            gm,
            period_s: p.rotation_period_s * (1.0 + p.mismatch.rotation_period_error),
            north_rate_rad_s: p.speed_m_s * (p.course_deg * RAD_PER_DEG).cos() / EARTH_RADIUS_M,
            gyro_tilt_rad: [0.0; 2],
            k: 0,
            n: (p.duration_s / p.sample_interval_s).floor() as usize,
        }
    }

    /// Number of rows still to come.
    pub fn len(&self) -> usize {
        self.n - self.k
    }

    /// Whether no rows are left to come.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl Samples<'_> {
    /// The rotation angle applied at `t` and the one the log reports, rad (the angle jitter drawn).
    fn rotation_rad(&mut self, t: f64) -> (f64, f64) {
        let p = self.p;
        // The angle actually applied: the scheme at the true period, plus the angle jitter. Eq (2)
        // is evaluated at it and the log reports it.
        let jitter = self.jitter.sample(&mut self.rng);
        let rho = p.rotation_phase_deg * RAD_PER_DEG + p.scheme.rho_rad(t, self.period_s) + jitter;
        // What the log reports: the angle measured the latency before, off by the encoder's zero.
        let logged_rho =
            if p.mismatch.angle_latency_s == 0.0 && p.mismatch.encoder_offset_deg == 0.0 {
                rho
            } else {
                p.rotation_phase_deg * RAD_PER_DEG
                    + p.scheme
                        .rho_rad(t - p.mismatch.angle_latency_s, self.period_s)
                    + jitter
                    + p.mismatch.encoder_offset_deg * RAD_PER_DEG
            };
        (rho, logged_rho)
    }

    /// The roll and pitch tilt the rotating gyro bias has given so far, rad; then adds this
    /// sample's, at the rotation angle `rho`.
    fn advance_gyro_tilt(&mut self, rho: f64) -> [f64; 2] {
        let p = self.p;
        let gyro_tilt = self.gyro_tilt_rad;
        if p.mismatch.rotating_gyro_bias_deg_h != 0.0 {
            let b_rad_s = p.mismatch.rotating_gyro_bias_deg_h * RAD_PER_DEG / 3600.0;
            self.gyro_tilt_rad[0] += b_rad_s * rho.cos() * p.sample_interval_s;
            self.gyro_tilt_rad[1] += b_rad_s * rho.sin() * p.sample_interval_s;
        }
        gyro_tilt
    }

    /// The attitude the RINS outputs at `t` (heading, roll, pitch), deg: the true attitude plus
    /// the oscillation of eq (2) (`osc`, rad), the low-frequency errors of eq (5), the white and
    /// coloured noise (drawn) and the gyro bias's tilt.
    fn output_attitude_deg(
        &mut self,
        t: f64,
        true_att: &[f64; 3],
        osc: &[f64; 3],
        gyro_tilt: [f64; 2],
    ) -> [f64; 3] {
        let we = self.w_lf * t;
        let mut out = [0.0; 3];
        for axis in 0..3 {
            let a = &self.lf[axis];
            let low = a[0]
                + a[1] * we.sin()
                + a[2] * we.cos()
                + a[3] * (2.0 * we).sin()
                + a[4] * (2.0 * we).cos();
            if self.gm_sigma > 0.0 {
                self.gm[axis] = self.gm_a * self.gm[axis] + self.gm_drive.sample(&mut self.rng);
            }
            let tilt = match axis {
                1 => gyro_tilt[0],
                2 => gyro_tilt[1],
                _ => 0.0,
            };
            let err_rad = osc[axis] + low + self.white.sample(&mut self.rng) + self.gm[axis] + tilt;
            out[axis] = true_att[axis] + err_rad / RAD_PER_DEG;
        }
        out
    }
}

/// The installation errors in force at `t`, arcsec: the step's once it has come, drifting under
/// a mismatch.
fn errors_at(p: &ScenarioParams, t: f64) -> [f64; 4] {
    let drift = p.mismatch.error_drift_arcsec_per_day * t / 86_400.0;
    let base = match p.errors_step {
        Some(step) if t >= step.at_s => step.errors_after_arcsec,
        _ => p.errors_arcsec,
    };
    core::array::from_fn(|i| base[i] + drift)
}

/// The true attitude at `t` (heading, roll, pitch), deg: the sway, the heading's weave and turns
/// with their heel, and the ship's slow motions.
fn true_attitude_deg(p: &ScenarioParams, t: f64) -> [f64; 3] {
    let (weave_deg, weave_rate_deg_s) = weave(p.heading_weave_rate_deg_s, t);
    let turn = turns(p.mismatch.heel_in_turns_deg, t);
    let mut true_att = [
        p.heading_deg + weave_deg + turn.heading_deg + sway(&p.heading_sway, t),
        sway(&p.roll_sway, t) + turn.heel_deg,
        sway(&p.pitch_sway, t),
    ];
    if !p.ship_motion.is_none() {
        let (roll_deg, pitch_deg) = p
            .ship_motion
            .roll_pitch_deg(t, weave_rate_deg_s + turn.rate_deg_s);
        true_att[1] += roll_deg;
        true_att[2] += pitch_deg;
    }
    true_att
}

impl Iterator for Samples<'_> {
    type Item = (Row, RowTruth);

    fn next(&mut self) -> Option<(Row, RowTruth)> {
        if self.k >= self.n {
            return None;
        }
        let p = self.p;
        let t = self.k as f64 * p.sample_interval_s;
        self.k += 1;
        let x_arcsec = errors_at(p, t);
        let x: [f64; 4] = core::array::from_fn(|i| arcsec_to_rad(x_arcsec[i]));
        let (rho, logged_rho) = self.rotation_rad(t);
        let gyro_tilt = self.advance_gyro_tilt(rho);
        let s = p.platform_phase_deg * RAD_PER_DEG + EARTH_RATE_RAD_PER_S * t;
        let lat = p.latitude_deg * RAD_PER_DEG + self.north_rate_rad_s * t;
        let true_att = true_attitude_deg(p, t);
        let osc = oscillation_rad(&x, rho, s, lat);
        let out = self.output_attitude_deg(t, &true_att, &osc, gyro_tilt);
        let row = Row {
            time_s: t,
            rotation_deg: (logged_rho / RAD_PER_DEG).rem_euclid(360.0),
            platform_deg: (s / RAD_PER_DEG).rem_euclid(360.0),
            latitude_deg: lat / RAD_PER_DEG,
            heading_deg: out[0].rem_euclid(360.0),
            roll_deg: out[1],
            pitch_deg: out[2],
        };
        let truth = RowTruth {
            true_attitude_deg: true_att,
            oscillation_deg: [
                osc[0] / RAD_PER_DEG,
                osc[1] / RAD_PER_DEG,
                osc[2] / RAD_PER_DEG,
            ],
            errors_arcsec: x_arcsec,
        };
        Some((row, truth))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.len(), Some(self.len()))
    }
}
