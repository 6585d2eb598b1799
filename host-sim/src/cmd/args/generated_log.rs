//! How a generated log is made, from the command line (`generate`, `run`, and the runs of
//! `monte-carlo` and `compare`): the scenario's overrides, the log's shape (rotation scheme,
//! timing, recorder), the ship's slow motions and the RINS's interface, and how a study's runs
//! are spread.

use super::{
    check_duration, parse_list, TimingArgs, GENERATED_INTERVAL_RANGE_S, SAMPLE_INTERVAL_RANGE_S,
};
use crate::sim::recorder::RecorderSettings;
use crate::sim::rotation_scheme::RotationScheme;
use crate::sim::scenario::{ErrorsStep, Mismatch, ScenarioKind, ScenarioParams};
use crate::sim::ship_motion::ShipMotionSettings;
use crate::study::monte_carlo::Draw;

/// Overrides of the scenario's fields (physics unchanged).
#[derive(Clone, Debug, Default, clap::Args)]
pub struct ScenarioOverrides {
    /// Log length, s (default: the scenario's).
    #[arg(long, value_name = "S")]
    pub duration: Option<f64>,
    /// Latitude at the start, deg (south negative: `--latitude -35`).
    #[arg(long, value_name = "DEG", allow_negative_numbers = true)]
    pub latitude: Option<f64>,
    /// Installation errors x1..x4, arcsec.
    #[arg(long, value_name = "X1,X2,X3,X4", allow_hyphen_values = true, value_parser = parse_list::<4>)]
    pub errors_arcsec: Option<[f64; 4]>,
    /// A change of the installation errors (re-installation, shock): at this time, s from the
    /// start, the errors become those of --errors-after-arcsec.
    #[arg(long, value_name = "S", requires = "errors_after_arcsec")]
    pub errors_step_at: Option<f64>,
    /// Installation errors x1..x4 from --errors-step-at on, arcsec.
    #[arg(long, value_name = "X1,X2,X3,X4", allow_hyphen_values = true, value_parser = parse_list::<4>, requires = "errors_step_at")]
    pub errors_after_arcsec: Option<[f64; 4]>,
    /// White attitude noise, 1-sigma arcsec.
    #[arg(long, value_name = "ARCSEC")]
    pub noise_arcsec: Option<f64>,
    /// Amplitude of the low-frequency errors of eq (5), deg.
    #[arg(long, value_name = "DEG")]
    pub low_frequency_deg: Option<f64>,
}

impl ScenarioOverrides {
    /// The scenario's parameters with these overrides applied.
    pub fn params(&self, kind: ScenarioKind, seed: u64) -> anyhow::Result<ScenarioParams> {
        let mut p = ScenarioParams::new(kind, seed);
        if let Some(d) = self.duration {
            p.duration_s = check_duration(d)?;
        }
        if let Some(l) = self.latitude {
            anyhow::ensure!(
                l.is_finite() && l.abs() < 90.0,
                "--latitude must be inside (-90, 90), got {l}"
            );
            p.latitude_deg = l;
        }
        if let Some(e) = self.errors_arcsec {
            p.errors_arcsec = e;
        }
        if let (Some(at_s), Some(errors_after_arcsec)) =
            (self.errors_step_at, self.errors_after_arcsec)
        {
            anyhow::ensure!(
                at_s.is_finite() && at_s > 0.0 && at_s < p.duration_s,
                "--errors-step-at must be inside the log (0, {} s), got {at_s}",
                p.duration_s
            );
            p.errors_step = Some(ErrorsStep {
                at_s,
                errors_after_arcsec,
            });
        }
        if let Some(n) = self.noise_arcsec {
            anyhow::ensure!(n.is_finite() && n >= 0.0, "--noise-arcsec must be >= 0");
            p.noise_arcsec = n;
        }
        if let Some(a) = self.low_frequency_deg {
            anyhow::ensure!(
                a.is_finite() && a >= 0.0,
                "--low-frequency-deg must be >= 0"
            );
            p.low_frequency_deg = a;
        }
        Ok(p)
    }
}

/// The recorder's effects on a generated log (see [`crate::sim::recorder`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, clap::Args)]
pub struct RecorderArgs {
    /// Recorder: drop each row independently with this probability (0 <= F < 1).
    #[arg(long, value_name = "F", default_value_t = 0.0)]
    pub drop_fraction: f64,
    /// Recorder: this many outages of 60 s (rows missing) at random times, not overlapping.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub outages: usize,
    /// Recorder: added to every time stamp, s (e.g. 1.7e9 for Unix time); recorded in the truth file.
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub time_offset: f64,
    /// Recorder: each time stamp is the sample instant plus a uniform jitter in [-S, S] (below half
    /// the sample interval); the data stay those of the true instant.
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub time_jitter: f64,
    /// Recorder: lose `--gap-rows` rows in a row every S seconds (the first gap S into the log).
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub gap_every: f64,
    /// Recorder: rows lost at each regular gap (with `--gap-every`).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub gap_rows: u32,
}

impl RecorderArgs {
    /// These options as the recorder's settings (the outages not yet placed).
    pub fn settings(&self) -> RecorderSettings {
        RecorderSettings {
            drop_fraction: self.drop_fraction,
            outages: self.outages,
            time_offset_s: self.time_offset,
            time_jitter_s: self.time_jitter,
            gap_every_s: self.gap_every,
            gap_rows: self.gap_rows,
        }
    }
}

/// The ship's slow motions on an ordinary day (`generate`, `run`, `compare`, `monte-carlo`): true
/// attitude of eq (3) that the estimator must cancel, not errors.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct ShipMotionArgs {
    /// Ship: slow heel (roll) from wind, fuel and loading, amplitudes deg: each adds
    /// `A sin(2 pi t / P + phase)` to the roll, P from --slow-heel-period-s (one period per
    /// amplitude), the phase drawn from the seed.
    #[arg(
        long,
        value_name = "A1,A2,...",
        value_delimiter = ',',
        requires = "slow_heel_period_s"
    )]
    pub slow_heel_deg: Vec<f64>,
    /// Ship: periods of the slow heel's sinusoids, s (above 0; as many as --slow-heel-deg).
    #[arg(
        long,
        value_name = "P1,P2,...",
        value_delimiter = ',',
        requires = "slow_heel_deg"
    )]
    pub slow_heel_period_s: Vec<f64>,
    /// Ship: slow trim (pitch), amplitudes deg: each adds `A sin(2 pi t / P + phase)` to the
    /// pitch, P from --slow-trim-period-s, the phase drawn from the seed.
    #[arg(
        long,
        value_name = "A1,A2,...",
        value_delimiter = ',',
        requires = "slow_trim_period_s"
    )]
    pub slow_trim_deg: Vec<f64>,
    /// Ship: periods of the slow trim's sinusoids, s (above 0; as many as --slow-trim-deg).
    #[arg(
        long,
        value_name = "P1,P2,...",
        value_delimiter = ',',
        requires = "slow_trim_deg"
    )]
    pub slow_trim_period_s: Vec<f64>,
    /// Ship: heel in turns, deg: a 90 deg course change at 0.5 deg/s every hour from 2 h on,
    /// alternately to starboard and port, the ship heeling outward by this much while it turns
    /// (0: no turns).
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    pub heel_in_turns_deg: f64,
    /// Ship: heel proportional to the rate of its course (the slow heading weave and the turns,
    /// not the wave-frequency yaw), K deg of heel per deg/s: roll += -K x rate (a turn to
    /// starboard heels to port).
    #[arg(long, value_name = "DEG_PER_DEG_S", default_value_t = 0.0)]
    pub heel_per_turn_rate: f64,
    /// Sea scenario: sinusoids in each wave spectrum of the sway (roll, pitch, heading), drawn
    /// again from the seed (default: the scenario's 40). Few lines are a steady swell whose lines
    /// can stay in step with a pattern locked to the rotation for hours; thousands approach a
    /// continuous spectrum.
    #[arg(long, value_name = "N")]
    pub sway_lines: Option<usize>,
    /// How the RINS's interface departs from the model.
    #[command(flatten)]
    pub interface: InterfaceArgs,
}

/// How the generated RINS's interface departs from the model (`generate`, `run`, `compare`,
/// `monte-carlo`): what docs/interface.md measures.
#[derive(Clone, Copy, Debug, Default, PartialEq, clap::Args)]
pub struct InterfaceArgs {
    /// RINS interface: the logged rotation angle was measured this long before the row's time, s
    /// (0 to 1).
    #[arg(
        long = "log-angle-latency-s",
        id = "log_angle_latency_s",
        value_name = "S",
        default_value_t = 0.0
    )]
    pub angle_latency_s: f64,
    /// RINS interface: the rotation encoder's zero is off by this much, deg (the logged angle is
    /// the true one plus this).
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    pub encoder_offset_deg: f64,
    /// RINS interface: a gyro bias fixed in the rotating sensor assembly, deg/h (horizontal; it
    /// tilts roll and pitch by its integral, an oscillation locked to the rotation angle).
    #[arg(long, value_name = "DEG_PER_H", default_value_t = 0.0)]
    pub rotating_gyro_bias_deg_h: f64,
}

impl InterfaceArgs {
    /// Puts the interface's departures into `m`, checked.
    pub fn apply(&self, m: &mut crate::sim::scenario::Mismatch) -> anyhow::Result<()> {
        anyhow::ensure!(
            (0.0..=1.0).contains(&self.angle_latency_s),
            "--log-angle-latency-s must be within 0 to 1 s, got {}",
            self.angle_latency_s
        );
        anyhow::ensure!(
            self.encoder_offset_deg.is_finite() && self.encoder_offset_deg.abs() <= 360.0,
            "--encoder-offset-deg must be within +-360 deg, got {}",
            self.encoder_offset_deg
        );
        anyhow::ensure!(
            self.rotating_gyro_bias_deg_h.is_finite()
                && self.rotating_gyro_bias_deg_h.abs() <= 10.0,
            "--rotating-gyro-bias-deg-h must be within +-10 deg/h, got {}",
            self.rotating_gyro_bias_deg_h
        );
        m.angle_latency_s = self.angle_latency_s;
        m.encoder_offset_deg = self.encoder_offset_deg;
        m.rotating_gyro_bias_deg_h = self.rotating_gyro_bias_deg_h;
        Ok(())
    }
}

impl ShipMotionArgs {
    /// The slow heel and trim and the heel per turn rate, checked (the heel in turns is a field
    /// of [`crate::sim::scenario::Mismatch`]: [`ShipMotionArgs::heel_in_turns_deg`]).
    pub fn settings(&self) -> anyhow::Result<ShipMotionSettings> {
        Ok(ShipMotionSettings::new(
            (&self.slow_heel_deg, &self.slow_heel_period_s),
            (&self.slow_trim_deg, &self.slow_trim_period_s),
            self.heel_per_turn_rate,
        )?)
    }

    /// Checks the heel in turns.
    pub fn heel_in_turns_deg(&self) -> anyhow::Result<f64> {
        let h = self.heel_in_turns_deg;
        anyhow::ensure!(
            h.is_finite(),
            "--heel-in-turns-deg must be a finite number of degrees, got {h}"
        );
        Ok(h)
    }

    /// Puts the motions into `p`, their phases drawn from `p`'s seed.
    pub fn apply(&self, p: &mut ScenarioParams) -> anyhow::Result<()> {
        if let Some(lines) = self.sway_lines {
            p.redraw_sea_sway(lines)?;
        }
        p.ship_motion = self.settings()?.motion(p.seed);
        p.mismatch.heel_in_turns_deg = self.heel_in_turns_deg()?;
        self.interface.apply(&mut p.mismatch)?;
        Ok(())
    }
}

/// How a generated log is rotated, sampled and recorded (`generate`, `run`).
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct LogShapeArgs {
    /// Rotation scheme of the RINS.
    #[arg(long, value_enum, default_value_t)]
    pub scheme: RotationScheme,
    /// Rotation period and sample interval.
    #[command(flatten)]
    pub timing: TimingArgs,
    /// The recorder's effects.
    #[command(flatten)]
    pub recorder: RecorderArgs,
}

impl LogShapeArgs {
    /// Applies scheme, timing and recorder to `p` (after its duration is set): outage start times
    /// are drawn from the scenario's seed.
    pub fn apply(&self, p: &mut ScenarioParams) -> anyhow::Result<()> {
        apply_shape(
            p,
            self.scheme,
            &self.timing,
            SAMPLE_INTERVAL_RANGE_S,
            &self.recorder.settings(),
            p.seed,
        )
    }

    /// [`LogShapeArgs::apply`] for a log only written (`generate`): its interval may be as short
    /// as [`GENERATED_INTERVAL_RANGE_S`] allows.
    pub fn apply_generated(&self, p: &mut ScenarioParams) -> anyhow::Result<()> {
        apply_shape(
            p,
            self.scheme,
            &self.timing,
            GENERATED_INTERVAL_RANGE_S,
            &self.recorder.settings(),
            p.seed,
        )
    }
}

/// Sets a scenario's scheme, timing (its interval within `interval_range_s`) and recording
/// (outages drawn from `outage_seed`), checked.
pub fn apply_shape(
    p: &mut ScenarioParams,
    scheme: RotationScheme,
    timing: &TimingArgs,
    interval_range_s: (f64, f64),
    recorder: &RecorderSettings,
    outage_seed: u64,
) -> anyhow::Result<()> {
    timing.check_within(interval_range_s)?;
    p.scheme = scheme;
    if let Some(t) = timing.rotation_period {
        p.rotation_period_s = t;
    }
    if let Some(d) = timing.sample_interval {
        p.sample_interval_s = d;
    }
    anyhow::ensure!(
        p.rotation_period_s >= scheme.min_period_s(),
        "the {} scheme needs a rotation period of at least {} s for its 15 s moves, got {}",
        scheme.name(),
        scheme.min_period_s(),
        p.rotation_period_s
    );
    anyhow::ensure!(
        p.duration_s >= p.sample_interval_s,
        "--duration ({} s) is shorter than one sample interval ({} s)",
        p.duration_s,
        p.sample_interval_s
    );
    p.recording = recorder.recording(outage_seed, p.duration_s, p.sample_interval_s)?;
    Ok(())
}

/// How Monte Carlo and compare runs are drawn beyond the scenario's defaults.
#[derive(clap::Args, Debug, Clone)]
pub struct SpreadArgs {
    /// Log length, s (default: the scenario's).
    #[arg(long, value_name = "S")]
    duration: Option<f64>,
    /// Latitudes spread uniformly in MIN,MAX deg (default: the scenario's).
    #[arg(long, value_name = "MIN,MAX", allow_hyphen_values = true, value_parser = parse_list::<2>)]
    lat_range: Option<[f64; 2]>,
    /// Roll sway amplitude uniform between the scenario's and this, deg (rougher sea).
    #[arg(long, value_name = "DEG")]
    max_roll_deg: Option<f64>,
    /// Model mismatch: relative error of the true rotation period (0.005 = 0.5 % slower).
    #[arg(
        long,
        value_name = "FRACTION",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    period_error: f64,
    /// Model mismatch: white jitter on the rotation angle, 1-sigma deg.
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    rotation_jitter_deg: f64,
    /// Model mismatch: linear drift of every installation error, arcsec per day.
    #[arg(
        long,
        value_name = "ARCSEC",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    error_drift_arcsec_per_day: f64,
    /// Model mismatch: frequency error of the low-frequency errors relative to the Earth rate (0.2 = 20 % faster).
    #[arg(
        long,
        value_name = "FRACTION",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    lowfreq_rate_error: f64,
    /// Model mismatch: coloured (Gauss-Markov, 60 s) attitude noise, 1-sigma arcsec.
    #[arg(long, value_name = "ARCSEC", default_value_t = 0.0)]
    coloured_noise_arcsec: f64,
    #[command(flatten)]
    motion: ShipMotionArgs,
    #[command(flatten)]
    timing: TimingArgs,
    #[command(flatten)]
    recorder: RecorderArgs,
}

impl SpreadArgs {
    /// How the runs of `kind` under `scheme` from master seed `seed` are drawn, checked.
    pub fn draw(
        &self,
        kind: ScenarioKind,
        scheme: RotationScheme,
        seed: u64,
    ) -> anyhow::Result<Draw> {
        self.timing.check()?;
        let mut d = Draw::new(kind, seed);
        d.scheme = scheme;
        d.rotation_period_s = self.timing.rotation_period;
        d.sample_interval_s = self.timing.sample_interval;
        d.recorder = self.recorder.settings();
        if let Some(v) = self.lat_range {
            anyhow::ensure!(
                v[0] <= v[1] && v[0] > -90.0 && v[1] < 90.0,
                "--lat-range needs MIN,MAX inside (-90, 90) with MIN <= MAX"
            );
            d.lat_range_deg = Some((v[0], v[1]));
        }
        if let Some(m) = self.max_roll_deg {
            anyhow::ensure!(
                m.is_finite() && m > 0.0 && m < 90.0,
                "--max-roll-deg must be inside (0, 90)"
            );
            d.max_roll_deg = Some(m);
        }
        if let Some(t) = self.duration {
            d.duration_s = Some(check_duration(t)?);
        }
        let finite = [
            self.period_error,
            self.rotation_jitter_deg,
            self.error_drift_arcsec_per_day,
            self.lowfreq_rate_error,
            self.coloured_noise_arcsec,
        ];
        anyhow::ensure!(
            finite.iter().all(|v| v.is_finite()),
            "mismatch switches must be finite"
        );
        anyhow::ensure!(self.period_error > -1.0, "--period-error must be above -1");
        anyhow::ensure!(
            self.rotation_jitter_deg >= 0.0 && self.coloured_noise_arcsec >= 0.0,
            "noise levels must be >= 0"
        );
        d.mismatch = Mismatch {
            rotation_period_error: self.period_error,
            rotation_jitter_deg: self.rotation_jitter_deg,
            error_drift_arcsec_per_day: self.error_drift_arcsec_per_day,
            low_frequency_rate_error: self.lowfreq_rate_error,
            coloured_noise_arcsec: self.coloured_noise_arcsec,
            heel_in_turns_deg: self.motion.heel_in_turns_deg()?,
            ..Mismatch::default()
        };
        self.motion.interface.apply(&mut d.mismatch)?;
        d.ship_motion = self.motion.settings()?;
        d.sway_lines = self.motion.sway_lines;
        d.check()?;
        Ok(d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_rejects_a_period_too_short_for_the_moves() {
        let mut p = ScenarioParams::new(ScenarioKind::Paper, 1);
        let timing = TimingArgs {
            rotation_period: Some(100.0),
            sample_interval: None,
        };
        let err = apply_shape(
            &mut p,
            RotationScheme::EightPosition,
            &timing,
            SAMPLE_INTERVAL_RANGE_S,
            &RecorderSettings::default(),
            1,
        )
        .unwrap_err();
        assert!(err.to_string().contains("at least 120 s"), "{err}");
        apply_shape(
            &mut p,
            RotationScheme::FourPosition,
            &timing,
            SAMPLE_INTERVAL_RANGE_S,
            &RecorderSettings::default(),
            1,
        )
        .unwrap();
        assert_eq!(
            (p.scheme, p.rotation_period_s),
            (RotationScheme::FourPosition, 100.0)
        );
    }
}
