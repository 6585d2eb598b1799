//! Command-line argument groups shared by several subcommands.

use crate::scenario::{ScenarioKind, ScenarioParams};
use estimator_core::units::{arcsec_to_rad, RAD_PER_DEG};
use estimator_core::{Config, Method, Real};

/// `--scenario`.
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
#[derive(Clone, Copy, Debug, Default, clap::Args)]
pub struct TuningArgs {
    /// Traditional baseline: 1-sigma of raw roll/pitch about eq (2), deg (default: the core's,
    /// 3/sqrt(2) deg, the RMS of a 3 deg sway).
    #[arg(long, value_name = "DEG")]
    pub traditional_sigma_deg: Option<f64>,
    /// Traditional baseline: random-walk process noise of the errors, arcsec/sqrt(s) (default 0).
    #[arg(long, value_name = "ARCSEC")]
    pub traditional_drift_arcsec_per_sqrt_s: Option<f64>,
    /// Gaps of up to this many missing samples are bridged by interpolation instead of restarting
    /// the moving average (default: the core's, 0 = never bridge).
    #[arg(long, value_name = "N")]
    pub max_bridged_gap_samples: Option<u32>,
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
        if let Some(n) = self.max_bridged_gap_samples {
            c.max_bridged_gap_samples = n;
        }
        c
    }

    /// [`TuningArgs::config`], checked by the core; the error names the parameter, its value, its
    /// bound and the option that set it.
    pub fn checked_config(&self, method: Method) -> anyhow::Result<Config> {
        let c = self.config(method);
        if let Err(e) = crate::replay::HostEstimator::new(c) {
            let option = match e {
                estimator_core::ConfigError::Parameter { name: "traditional_sigma_rad", .. } => " (set by --traditional-sigma-deg, deg)",
                estimator_core::ConfigError::Parameter { name: "traditional_drift_rad_per_sqrt_s", .. } => {
                    " (set by --traditional-drift-arcsec-per-sqrt-s, arcsec/sqrt(s))"
                }
                estimator_core::ConfigError::Parameter { name: "max_bridged_gap_samples", .. } => " (set by --max-bridged-gap-samples)",
                _ => "",
            };
            anyhow::bail!("invalid estimator configuration: {e}{option}");
        }
        Ok(c)
    }
}

/// Longest log the generator is asked for, s (30 days: 2.6 million rows, about 200 MB of CSV).
pub const MAX_DURATION_S: f64 = 30.0 * 86_400.0;

/// Checks a `--duration`.
pub fn check_duration(d: f64) -> anyhow::Result<f64> {
    anyhow::ensure!(d.is_finite() && (1.0..=MAX_DURATION_S).contains(&d), "--duration must be between 1 and {MAX_DURATION_S} s, got {d}");
    Ok(d)
}

/// Parses `N` comma-separated finite numbers (negative numbers allowed).
pub fn parse_list<const N: usize>(text: &str) -> Result<[f64; N], String> {
    let parts: Vec<&str> = text.split(',').collect();
    if parts.len() != N {
        return Err(format!("expected {N} comma-separated numbers, got {}", parts.len()));
    }
    let mut out = [0.0; N];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p.trim().parse::<f64>().map_err(|_| format!("not a number: {:?}", p.trim()))?;
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
            anyhow::ensure!(l.is_finite() && l.abs() < 90.0, "--latitude must be inside (-90, 90), got {l}");
            p.latitude_deg = l;
        }
        if let Some(e) = self.errors_arcsec {
            p.errors_arcsec = e;
        }
        if let Some(n) = self.noise_arcsec {
            anyhow::ensure!(n.is_finite() && n >= 0.0, "--noise-arcsec must be >= 0");
            p.noise_arcsec = n;
        }
        if let Some(a) = self.low_frequency_deg {
            anyhow::ensure!(a.is_finite() && a >= 0.0, "--low-frequency-deg must be >= 0");
            p.low_frequency_deg = a;
        }
        Ok(p)
    }
}
