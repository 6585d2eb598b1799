//! The command-line argument groups several subcommands share, and the checks of their values:
//! the scenario and method, the estimator's tuning and timing ([`TuningArgs`], [`TimingArgs`]),
//! and, in [`generated_log`], how a generated log is made (the scenario's overrides, its shape,
//! the recorder, the ship's motion, the RINS's interface, and the spread of a study's runs).
//! A subcommand's own options are in its module of [`crate::cmd`].

pub mod generated_log;

use crate::sim::scenario::ScenarioKind;
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

/// Accepted rotation periods, s.
pub const ROTATION_PERIOD_RANGE_S: (f64, f64) = (60.0, 3600.0);
/// Accepted sample intervals, s.
pub const SAMPLE_INTERVAL_RANGE_S: (f64, f64) = (0.1, 10.0);
/// Sample intervals `generate` writes a log at, s: down to 5 ms, a navigation computer's 200 Hz,
/// for `estimate --bin-interval-s` (a log faster than [`SAMPLE_INTERVAL_RANGE_S`] is estimated
/// only binned).
pub const GENERATED_INTERVAL_RANGE_S: (f64, f64) = (0.005, 10.0);

/// Checks a `--bin-interval-s` ([`estimator_core::binning::BIN_INTERVAL_RANGE_S`]).
pub fn check_bin_interval(bin_s: f64) -> anyhow::Result<()> {
    let (lo, hi) = estimator_core::binning::BIN_INTERVAL_RANGE_S;
    anyhow::ensure!(
        bin_s.is_finite() && (lo..=hi).contains(&bin_s),
        "--bin-interval-s must be between {lo} and {hi} s, got {bin_s}"
    );
    Ok(())
}

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
