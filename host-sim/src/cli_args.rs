//! Command-line argument groups shared by several subcommands.

use crate::sim::recorder::RecorderSettings;
use crate::sim::rotation_scheme::RotationScheme;
use crate::sim::scenario::{ErrorsStep, ScenarioKind, ScenarioParams, ShipMotionSettings};
use estimator_core::units::{arcsec_to_rad, RAD_PER_DEG};
use estimator_core::{Config, Method, Real};

/// `--scenario`.
// A doc comment on a variant would become its help in `--help`, which lists the names alone.
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ScenarioArg {
    Paper,
    Turntable,
    Sea,
}

impl From<ScenarioArg> for ScenarioKind {
    fn from(s: ScenarioArg) -> ScenarioKind {
        match s {
            ScenarioArg::Paper => ScenarioKind::Paper,
            ScenarioArg::Turntable => ScenarioKind::Turntable,
            ScenarioArg::Sea => ScenarioKind::Sea,
        }
    }
}

/// `--method`, named as [`Method::name`]: `windowed` (ours, the core's default), `paper` (the
/// paper's eqs (8)-(18) as printed), `traditional` (the Fig. 2 baseline).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum MethodArg {
    /// Ours: correlation channels averaged over a moving window, one 4-state filter (core default).
    #[default]
    Windowed,
    /// The paper's eqs (8), (11), (13)-(18) literally (cumulative correlation, 3-state filters).
    Paper,
    /// The paper's Fig. 2 baseline: a Kalman filter straight on raw roll and pitch.
    Traditional,
}

impl From<MethodArg> for Method {
    fn from(m: MethodArg) -> Method {
        match m {
            MethodArg::Windowed => Method::Windowed,
            MethodArg::Paper => Method::Paper,
            MethodArg::Traditional => Method::Traditional,
        }
    }
}

/// Label of a method in reports.
pub fn method_label(m: Method) -> &'static str {
    match m {
        Method::Windowed => "ours (windowed)",
        Method::Paper => "paper (literal)",
        Method::Traditional => "traditional",
    }
}

/// Estimator tuning from the command line: the traditional baseline's noise and gap bridging.
#[derive(Clone, Debug, Default, clap::Args)]
pub struct TuningArgs {
    /// Traditional baseline: 1-sigma of raw roll/pitch about eq (2), deg (default: the core's,
    /// 3/sqrt(2) deg, the RMS of a 3 deg sway).
    #[arg(long, value_name = "DEG")]
    pub traditional_sigma_deg: Option<f64>,
    /// Traditional baseline: random-walk process noise of the errors, arcsec/sqrt(s) (default 0).
    #[arg(long, value_name = "ARCSEC")]
    pub traditional_drift_arcsec_per_sqrt_s: Option<f64>,
    /// Gaps of up to this many lost samples in a row are filled from their neighbours instead of
    /// restarting the moving average (default: the core's, 2; 0 = never fill, at most 3).
    #[arg(long, value_name = "N")]
    pub max_filled_gap_samples: Option<u32>,
    /// Windowed method: the smallest step of an installation error the change detector is sized
    /// for, arcsec (default: the core's, 20; 0 turns detection off: a change of the errors is then
    /// followed only as slowly as the filter's memory allows).
    #[arg(long, value_name = "ARCSEC")]
    pub change_detection_arcsec: Option<f64>,
    /// Known values of x1..x4, arcsec (a dockside or factory calibration, or the final estimates of
    /// an earlier run): the estimator starts from them and reports them, and compensates with
    /// them, from the first row, before its first measurement; the log then refines them. Needs
    /// --prior-sigma-arcsec.
    #[arg(long, value_name = "X1,X2,X3,X4", value_delimiter = ',')]
    pub prior_arcsec: Option<Vec<f64>>,
    /// The 1-sigma of --prior-arcsec, arcsec: one value for all four errors or four values; each
    /// positive and at most 1000 arcsec.
    #[arg(long, value_name = "S or S1,S2,S3,S4", value_delimiter = ',')]
    pub prior_sigma_arcsec: Option<Vec<f64>>,
    /// How long before each row's time its rotation angle was measured, s (the attitude taken at
    /// the row's time), 0 to 1: the rotation angle is carried forward at the rotation's rate
    /// (default 0). At 0.75 deg/s a lag of 0.2 s left unset costs about 0.8 arcsec on errors of a
    /// few hundred (docs/interface.md).
    #[arg(long, value_name = "S")]
    pub angle_latency_s: Option<f64>,
}

impl TuningArgs {
    /// The configuration for `method` with this tuning.
    pub fn config(&self, method: Method) -> Config {
        let mut c = Config::with_method(method);
        if let Some(s) = self.traditional_sigma_deg {
            c.traditional_sigma_rad = (s * RAD_PER_DEG) as Real;
        }
        if let Some(d) = self.traditional_drift_arcsec_per_sqrt_s {
            c.traditional_drift_rad_per_sqrt_s = arcsec_to_rad(d) as Real;
        }
        if let Some(n) = self.max_filled_gap_samples {
            c.max_filled_gap_samples = n;
        }
        if let Some(a) = self.change_detection_arcsec {
            c.change_detection_step_rad = arcsec_to_rad(a) as Real;
        }
        if let Some(s) = self.angle_latency_s {
            c.angle_latency_s = s;
        }
        c.prior = self.prior();
        c
    }

    /// The prior of --prior-arcsec and --prior-sigma-arcsec, when both are given with their counts
    /// of values (4, and 1 or 4).
    fn prior(&self) -> Option<estimator_core::Prior> {
        let (x, s) = (
            self.prior_arcsec.as_ref()?,
            self.prior_sigma_arcsec.as_ref()?,
        );
        let sigma: [f64; 4] = match s.as_slice() {
            [one] => [*one; 4],
            [a, b, c, d] => [*a, *b, *c, *d],
            _ => return None,
        };
        let x: [f64; 4] = x.as_slice().try_into().ok()?;
        Some(estimator_core::Prior {
            x_rad: x.map(|v| arcsec_to_rad(v) as Real),
            sigma_rad: sigma.map(|v| arcsec_to_rad(v) as Real),
        })
    }

    /// [`TuningArgs::config`], checked by the core; the error names the parameter, its value, its
    /// bound and the option that set it.
    pub fn checked_config(&self, method: Method) -> anyhow::Result<Config> {
        match (&self.prior_arcsec, &self.prior_sigma_arcsec) {
            (Some(_), None) => anyhow::bail!(
                "--prior-arcsec needs --prior-sigma-arcsec (how well the values are known)"
            ),
            (None, Some(_)) => {
                anyhow::bail!("--prior-sigma-arcsec needs --prior-arcsec (the values it is for)")
            }
            (Some(x), _) if x.len() != 4 => anyhow::bail!(
                "--prior-arcsec takes four values, x1..x4 in arcsec, not {}",
                x.len()
            ),
            (Some(_), Some(s)) if s.len() != 1 && s.len() != 4 => anyhow::bail!(
                "--prior-sigma-arcsec takes one value for all four errors or four values, not {}",
                s.len()
            ),
            _ => {}
        }
        let c = self.config(method);
        if let Err(e) = crate::replay::HostEstimator::new(c) {
            let option = match e {
                estimator_core::ConfigError::Parameter {
                    name: "traditional_sigma_rad",
                    ..
                } => " (set by --traditional-sigma-deg, deg)",
                estimator_core::ConfigError::Parameter {
                    name: "traditional_drift_rad_per_sqrt_s",
                    ..
                } => " (set by --traditional-drift-arcsec-per-sqrt-s, arcsec/sqrt(s))",
                estimator_core::ConfigError::Parameter {
                    name: "max_filled_gap_samples",
                    ..
                } => " (set by --max-filled-gap-samples)",
                estimator_core::ConfigError::Parameter {
                    name: "change_detection_step_rad",
                    ..
                } => " (set by --change-detection-arcsec, arcsec)",
                estimator_core::ConfigError::Parameter {
                    name: "angle_latency_s",
                    ..
                } => " (set by --angle-latency-s, s)",
                estimator_core::ConfigError::Parameter { name, .. }
                    if name.starts_with("prior.") =>
                {
                    " (set by --prior-arcsec and --prior-sigma-arcsec, arcsec; shown in rad)"
                }
                _ => "",
            };
            anyhow::bail!("invalid estimator configuration: {e}{option}");
        }
        Ok(c)
    }
}

/// Lets every option of `cmd` and of its subcommands that takes a value take a negative number
/// (`--duration -100`, `--latitude -35`): the option's own check then says what is wrong with it,
/// where clap alone would take `-100` for an unknown option.
pub fn accept_negative_numbers(cmd: clap::Command) -> clap::Command {
    let names: Vec<String> = cmd
        .get_subcommands()
        .map(|c| c.get_name().to_string())
        .collect();
    let cmd = cmd.mut_args(|arg| {
        if arg.get_action().takes_values() && !arg.is_positional() {
            arg.allow_negative_numbers(true)
        } else {
            arg
        }
    });
    names.iter().fold(cmd, |cmd, name| {
        cmd.mut_subcommand(name, accept_negative_numbers)
    })
}

/// Longest log the generator is asked for, s (30 days: 2.6 million rows, about 200 MB of CSV).
pub const MAX_DURATION_S: f64 = 30.0 * 86_400.0;

/// Checks a `--duration`.
pub fn check_duration(d: f64) -> anyhow::Result<f64> {
    anyhow::ensure!(
        d.is_finite() && (1.0..=MAX_DURATION_S).contains(&d),
        "--duration must be between 1 and {MAX_DURATION_S} s, got {d}"
    );
    Ok(d)
}

/// Parses `N` comma-separated finite numbers (negative numbers allowed).
pub fn parse_list<const N: usize>(text: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != N {
        return Err(format!(
            "expected {N} comma-separated numbers, got {}",
            parts.len()
        ));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .trim()
            .parse::<f64>()
            .map_err(|_| format!("not a number: {:?}", p.trim()))?;
        if !o.is_finite() {
            return Err(format!("not finite: {:?}", p.trim()));
        }
    }
    Ok(out)
}

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

/// A comma-separated list of schemes, or `all`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SchemeList(pub Vec<RotationScheme>);

/// Parses `--schemes`: scheme names separated by commas, or `all`.
pub fn parse_schemes(text: &str) -> Result<SchemeList, String> {
    if text.trim() == "all" {
        return Ok(SchemeList(RotationScheme::ALL.to_vec()));
    }
    let names: Vec<&str> = RotationScheme::ALL.iter().map(|s| s.name()).collect();
    text.split(',')
        .map(|n| {
            RotationScheme::parse(n.trim()).ok_or_else(|| {
                format!(
                    "unknown scheme {:?}: expected `all` or some of {}",
                    n.trim(),
                    names.join(", ")
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .map(SchemeList)
}

/// Accepted rotation periods, s.
pub const ROTATION_PERIOD_RANGE_S: (f64, f64) = (60.0, 3600.0);
/// Accepted sample intervals, s.
pub const SAMPLE_INTERVAL_RANGE_S: (f64, f64) = (0.1, 10.0);
/// Sample intervals `generate` writes a log at, s: down to 5 ms, a navigation computer's 200 Hz,
/// for `estimate --bin-interval-s` (a log faster than [`SAMPLE_INTERVAL_RANGE_S`] is estimated
/// only binned).
pub const GENERATED_INTERVAL_RANGE_S: (f64, f64) = (0.005, 10.0);

/// Rotation period and sample interval. They shape a generated log, and they pin the estimator's
/// configuration; this group is the one place where the command line sets the core's timing.
#[derive(Clone, Copy, Debug, Default, PartialEq, clap::Args)]
pub struct TimingArgs {
    /// Rotation period of the RINS, s (60-3600). Generating: the log's (default 480). Estimating
    /// a log (`estimate`): pins the estimator's period instead of detecting it from the rotation
    /// angle.
    #[arg(long, value_name = "S")]
    pub rotation_period: Option<f64>,
    /// Interval between the log's rows, s (0.1-10). Generating: the log's (default 1; `generate`
    /// also 0.005 to 0.1, a navigation computer's rate, for `estimate --bin-interval-s`).
    /// Estimating a log (`estimate`): pins the estimator's interval instead of learning it from
    /// the stamps.
    #[arg(long, value_name = "S")]
    pub sample_interval: Option<f64>,
}

impl TimingArgs {
    /// Checks the ranges.
    pub fn check(&self) -> anyhow::Result<()> {
        self.check_within(SAMPLE_INTERVAL_RANGE_S)
    }

    /// Checks the ranges, the sample interval against `interval_range_s`.
    pub fn check_within(&self, interval_range_s: (f64, f64)) -> anyhow::Result<()> {
        if let Some(t) = self.rotation_period {
            let (lo, hi) = ROTATION_PERIOD_RANGE_S;
            anyhow::ensure!(
                t.is_finite() && (lo..=hi).contains(&t),
                "--rotation-period must be between {lo} and {hi} s, got {t}"
            );
        }
        if let Some(d) = self.sample_interval {
            let (lo, hi) = interval_range_s;
            anyhow::ensure!(
                d.is_finite() && (lo..=hi).contains(&d),
                "--sample-interval must be between {lo} and {hi} s, got {d}"
            );
        }
        Ok(())
    }

    /// `config` with the rotation period and sample interval given pinned; what is not given keeps
    /// the configuration's value (by default: learned from the data).
    pub fn pin(&self, mut config: Config) -> Config {
        if let Some(t) = self.rotation_period {
            config.rotation_period_s = Some(t);
        }
        if let Some(d) = self.sample_interval {
            config.sample_interval_s = Some(d);
        }
        config
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schemes_parse_as_list_or_all() {
        assert_eq!(
            parse_schemes("all").unwrap().0,
            RotationScheme::ALL.to_vec()
        );
        assert_eq!(
            parse_schemes("reversed, eight-position").unwrap().0,
            vec![RotationScheme::Reversed, RotationScheme::EightPosition]
        );
        assert!(parse_schemes("continuous,spiral")
            .unwrap_err()
            .contains("spiral"));
    }

    #[test]
    fn timing_pins_period_and_interval() {
        let c = Config::default();
        assert_eq!(TimingArgs::default().pin(c), c);
        let pinned = TimingArgs {
            rotation_period: Some(360.0),
            sample_interval: Some(2.0),
        }
        .pin(c);
        assert_eq!(
            (pinned.rotation_period_s, pinned.sample_interval_s),
            (Some(360.0), Some(2.0))
        );
        let interval_only = TimingArgs {
            rotation_period: None,
            sample_interval: Some(0.5),
        }
        .pin(c);
        assert_eq!(
            (
                interval_only.rotation_period_s,
                interval_only.sample_interval_s
            ),
            (None, Some(0.5))
        );
        assert!(TimingArgs {
            rotation_period: Some(59.0),
            sample_interval: None
        }
        .check()
        .is_err());
        assert!(TimingArgs {
            rotation_period: None,
            sample_interval: Some(0.05)
        }
        .check()
        .is_err());
    }

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
