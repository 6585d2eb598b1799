//! Estimator configuration: a plain struct whose [`Default`] reproduces the paper's setting.

use crate::units::{arcsec_to_rad, RAD_PER_DEG};
use crate::Real;

/// Which identification method runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Ours (default): the four correlation channels averaged over a moving window of one rotation
    /// period, fed together into one 4-state filter whose measurement rows carry the x1, x2 leakage of
    /// eq (12) exactly (see [`crate::methods::windowed`]).
    #[default]
    Windowed,
    /// The paper's eqs (8), (11), (13)-(18) literally: a cumulative correlation per channel, its
    /// 480 s average, and one 3-state filter (x, b1, b2) per error (see [`crate::methods::paper`]).
    Paper,
    /// The paper's Fig. 2 baseline: a 4-state filter straight on raw roll and pitch with eq (2) as
    /// the measurement model, no correlation, no averaging (see [`crate::methods::traditional`]).
    Traditional,
}

impl Method {
    /// Name used on command lines and in files.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Windowed => "windowed",
            Method::Paper => "paper",
            Method::Traditional => "traditional",
        }
    }

    /// Code used on the firmware link.
    pub fn code(&self) -> u8 {
        match self {
            Method::Windowed => 0,
            Method::Paper => 1,
            Method::Traditional => 2,
        }
    }

    /// Inverse of [`Method::code`].
    pub fn from_code(code: u8) -> Option<Method> {
        match code {
            0 => Some(Method::Windowed),
            1 => Some(Method::Paper),
            2 => Some(Method::Traditional),
            _ => None,
        }
    }
}

/// Estimator settings. All angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Identification method. Default: [`Method::Windowed`].
    pub method: Method,
    /// Rotation period in samples: the length of the moving average of eq (11). Default 480
    /// (480 s at 1 Hz, the paper's). Must not exceed the estimator's ring capacity.
    pub rotation_period_samples: usize,
    /// Nominal sample interval, s. Default 1.
    pub sample_interval_s: f64,
    /// Prior 1-sigma of each installation error. Default 1000 arcsec ("a few hundred" in the paper).
    pub prior_sigma_rad: Real,
    /// 1-sigma of one correlation measurement (windowed and paper methods). Default 10/sqrt(2)
    /// arcsec: the noise of one correlation product for a white attitude noise of 10 arcsec. For a
    /// moving window read once a second this per-product value, not the (480 times smaller) variance
    /// of the window mean, is the right measurement noise; see [`crate::methods::windowed`].
    pub measurement_sigma_rad: Real,
    /// Random walk of the installation errors, rad/sqrt(s) (process noise). Default 0.003
    /// arcsec/sqrt(s), about 0.9 arcsec/sqrt(day): the errors "may gradually evolve" (the paper's
    /// reason for estimating in real time), and with no process noise at all the filter stops
    /// following them. Chosen by measurement (README, "Choosing the defaults"): it costs about
    /// 0.1 arcsec of steady-state noise and cuts the lag behind a 20 arcsec/day drift from 8 to 2 arcsec.
    pub drift_rad_per_sqrt_s: Real,
    /// 1-sigma of raw roll or pitch about eq (2) for the traditional baseline: the sway. Default
    /// 3 deg / sqrt(2), the RMS of the paper's 3 deg roll sway.
    pub traditional_sigma_rad: Real,
    /// Process noise of the traditional baseline, rad/sqrt(s). Default 0.
    pub traditional_drift_rad_per_sqrt_s: Real,
    /// Start gate: estimation starts once the roll sway amplitude exceeds this (the paper's sea test
    /// used 3 deg). Default 0: off.
    pub sway_gate_rad: Real,
    /// Gaps of up to this many missing samples are bridged by linear interpolation of every input;
    /// longer gaps restart the moving average. Default 0: every gap restarts it, which costs one
    /// rotation period of updates but no accuracy (see [`crate::estimator`] for the measured trade-off).
    pub max_bridged_gap_samples: u32,
    /// An error counts as converged once its 1-sigma is below this. Default 1 arcsec.
    pub converged_sigma_rad: Real,
    /// Largest relative deviation of the rotation rate over the last few steps (the mean over
    /// `RotationMonitor::SHORT_STEPS`) from nominal. Default 0.5: a gross check; the period itself
    /// is held to `rotation_period_tolerance` through the mean rate over one period.
    pub rotation_step_tolerance: Real,
    /// Largest relative deviation of the mean rotation rate (over about one period) from the
    /// configured period. Default 0.01 (1 %): a window then spans 360 +- 3.6 deg.
    pub rotation_period_tolerance: Real,
}

impl Default for Config {
    fn default() -> Self {
        Config {
            method: Method::Windowed,
            rotation_period_samples: 480,
            sample_interval_s: 1.0,
            prior_sigma_rad: arcsec_to_rad(1000.0) as Real,
            measurement_sigma_rad: arcsec_to_rad(10.0 / core::f64::consts::SQRT_2) as Real,
            drift_rad_per_sqrt_s: arcsec_to_rad(0.003) as Real,
            traditional_sigma_rad: (3.0 * RAD_PER_DEG / core::f64::consts::SQRT_2) as Real,
            traditional_drift_rad_per_sqrt_s: 0.0,
            sway_gate_rad: 0.0,
            max_bridged_gap_samples: 0,
            converged_sigma_rad: arcsec_to_rad(1.0) as Real,
            rotation_step_tolerance: 0.5,
            rotation_period_tolerance: 0.01,
        }
    }
}

/// A configuration the estimator cannot run with: which parameter, its value and the bound it
/// breaks. Displayed on one line, e.g. `measurement_sigma_rad = -1 must be positive and finite`.
/// Values compare bit for bit, so that equality is an equivalence (a NaN value equals itself).
#[derive(Clone, Copy, Debug)]
pub enum ConfigError {
    /// `rotation_period_samples` is below 2 or above the ring capacity.
    RotationPeriod { samples: usize, capacity: usize },
    /// `sample_interval_s` is not positive and finite.
    SampleInterval { value_s: f64 },
    /// A noise, tolerance, gate or bridging limit out of its bound.
    Parameter { name: &'static str, value: f64, bound: Bound },
    /// The method is not in this build (the paper's method needs the `paper-method` feature).
    MethodUnavailable,
}

/// The bound a [`ConfigError::Parameter`] breaks.
#[derive(Clone, Copy, Debug)]
pub enum Bound {
    /// Must be positive and finite.
    Positive,
    /// Must be zero or positive, and finite.
    NonNegative,
    /// Must be at most this (1 rad for a sigma; one rotation period for bridging; 1000 times the
    /// measurement sigma for the prior; 1 rad per step for a random walk, given per sqrt(s)).
    AtMost(f64),
    /// Its square underflows to 0 in the build's float type.
    SquareUnderflows,
}

impl PartialEq for Bound {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Bound::AtMost(a), Bound::AtMost(b)) => a.to_bits() == b.to_bits(),
            (a, b) => core::mem::discriminant(a) == core::mem::discriminant(b),
        }
    }
}
impl Eq for Bound {}

impl PartialEq for ConfigError {
    fn eq(&self, other: &Self) -> bool {
        use ConfigError::*;
        match (self, other) {
            (RotationPeriod { samples: a, capacity: b }, RotationPeriod { samples: c, capacity: d }) => a == c && b == d,
            (SampleInterval { value_s: a }, SampleInterval { value_s: b }) => a.to_bits() == b.to_bits(),
            (Parameter { name: a, value: b, bound: c }, Parameter { name: d, value: e, bound: f }) => {
                a == d && b.to_bits() == e.to_bits() && c == f
            }
            (MethodUnavailable, MethodUnavailable) => true,
            _ => false,
        }
    }
}
impl Eq for ConfigError {}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ConfigError::RotationPeriod { samples, capacity } => {
                write!(f, "rotation_period_samples = {samples} must be from 2 to {capacity} (the ring capacity)")
            }
            ConfigError::SampleInterval { value_s } => write!(f, "sample_interval_s = {value_s} must be positive and finite"),
            ConfigError::Parameter { name, value, bound } => match bound {
                Bound::Positive => write!(f, "{name} = {value} must be positive and finite"),
                Bound::NonNegative => write!(f, "{name} = {value} must be zero or positive, and finite"),
                Bound::AtMost(limit) => write!(f, "{name} = {value} must be at most {limit}"),
                Bound::SquareUnderflows => write!(f, "{name} = {value} is too small: its square underflows to 0"),
            },
            ConfigError::MethodUnavailable => write!(f, "method unavailable: the paper's method needs the `paper-method` feature"),
        }
    }
}

impl core::error::Error for ConfigError {}

impl Config {
    /// The default configuration with another method.
    pub fn with_method(method: Method) -> Config {
        Config { method, ..Config::default() }
    }

    /// Checks the configuration against a ring capacity; the error names the first parameter
    /// out of bounds.
    pub fn check(&self, capacity: usize) -> Result<(), ConfigError> {
        use Bound::*;
        let fail = |name: &'static str, value: Real, bound: Bound| Err(ConfigError::Parameter { name, value: value as f64, bound });
        if self.method == Method::Paper && !cfg!(feature = "paper-method") {
            return Err(ConfigError::MethodUnavailable);
        }
        if self.rotation_period_samples < 2 || self.rotation_period_samples > capacity {
            return Err(ConfigError::RotationPeriod { samples: self.rotation_period_samples, capacity });
        }
        if !(self.sample_interval_s > 0.0 && self.sample_interval_s.is_finite()) {
            return Err(ConfigError::SampleInterval { value_s: self.sample_interval_s });
        }
        let positive = [
            ("prior_sigma_rad", self.prior_sigma_rad),
            ("measurement_sigma_rad", self.measurement_sigma_rad),
            ("traditional_sigma_rad", self.traditional_sigma_rad),
            ("converged_sigma_rad", self.converged_sigma_rad),
            ("rotation_step_tolerance", self.rotation_step_tolerance),
            ("rotation_period_tolerance", self.rotation_period_tolerance),
        ];
        let non_negative = [
            ("drift_rad_per_sqrt_s", self.drift_rad_per_sqrt_s),
            ("traditional_drift_rad_per_sqrt_s", self.traditional_drift_rad_per_sqrt_s),
            ("sway_gate_rad", self.sway_gate_rad),
        ];
        if let Some((name, v)) = positive.iter().find(|(_, v)| !(*v > 0.0 && v.is_finite())) {
            return fail(name, *v, Positive);
        }
        if let Some((name, v)) = non_negative.iter().find(|(_, v)| !(*v >= 0.0 && v.is_finite())) {
            return fail(name, *v, NonNegative);
        }
        // Every sigma, and the random walk of one step, at most 1 rad: no installation error or
        // attitude noise comes near a radian, and with that bound no variance can overflow (the
        // prior plus 2^32 steps of random walk stays below 5e9 rad^2). Found by fuzzing the
        // checkpoint restore: a random walk of 9e18 rad/sqrt(s) passed a finiteness check and
        // overflowed the covariance two steps later; a sigma of 1e20 rad squared to infinity.
        let dt = self.sample_interval_s as Real;
        let sigmas = [positive[0], positive[1], positive[2], positive[3]];
        let drifts = [non_negative[0], non_negative[1]];
        for (name, s) in sigmas {
            if !(s <= 1.0) {
                return fail(name, s, AtMost(1.0));
            }
            if !(s * s > 0.0) {
                return fail(name, s, SquareUnderflows);
            }
        }
        for (name, d) in drifts {
            if !(d * d * dt <= 1.0) {
                return fail(name, d, AtMost(1.0 / libm::sqrt(self.sample_interval_s)));
            }
        }
        // In f32 a prior far wider than the measurement noise makes the first updates lose the
        // covariance's definiteness (`crate::kalman`: the variance ratio must stay well below
        // 1/eps). Prior at most 1000 times each measurement sigma (variance ratio 1e6; the
        // defaults' are 141 and 0.13).
        let widest = 1000.0 * self.measurement_sigma_rad.min(self.traditional_sigma_rad);
        if self.prior_sigma_rad > widest {
            return fail("prior_sigma_rad", self.prior_sigma_rad, AtMost(widest as f64));
        }
        // Each bridged sample is a full step's work; bridging more than a window is pointless (the
        // window would restart anyway), so a step never does more than `1 + period` steps of work.
        // Found by fuzzing the checkpoint restore (1.8e9 bridged samples: minutes for one step).
        if self.max_bridged_gap_samples as usize > self.rotation_period_samples {
            return Err(ConfigError::Parameter {
                name: "max_bridged_gap_samples",
                value: self.max_bridged_gap_samples as f64,
                bound: AtMost(self.rotation_period_samples as f64),
            });
        }
        Ok(())
    }
}
