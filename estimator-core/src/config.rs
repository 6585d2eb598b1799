//! Estimator configuration: a plain struct whose [`Default`] reproduces the paper's setting.

pub(crate) mod checkpoint;

use crate::code::{from_code, UnknownCode};
use crate::gap_fill::MAX_FILLABLE_GAP;
use crate::units::{arcsec_to_rad, RAD_PER_DEG};
use crate::Real;

/// Rotation periods that can be pinned or are detected, s.
pub const ROTATION_PERIOD_RANGE_S: (f64, f64) = (60.0, 3600.0);
/// Sample intervals that can be pinned or are learned, s.
pub const SAMPLE_INTERVAL_RANGE_S: (f64, f64) = (0.1, 10.0);

/// Which identification method runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[repr(u8)]
pub enum Method {
    /// Ours (default): the four correlation channels averaged over a moving window of one rotation
    /// period, fed together into one 4-state filter whose measurement rows carry the x1, x2 leakage of
    /// eq (12) exactly (see [`crate::methods::windowed`]).
    #[default]
    Windowed = 0,
    /// The paper's eqs (8), (11), (13)-(18) literally: a cumulative correlation per channel, its
    /// 480 s average, and one 3-state filter (x, b1, b2) per error (see [`crate::methods::paper`]).
    Paper = 1,
    /// The paper's Fig. 2 baseline: a 4-state filter straight on raw roll and pitch with eq (2) as
    /// the measurement model, no correlation, no averaging (see [`crate::methods::traditional`]).
    Traditional = 2,
}

impl Method {
    /// Every method, in code order.
    pub const ALL: [Method; 3] = [Method::Windowed, Method::Paper, Method::Traditional];

    /// Name used on command lines and in files.
    pub fn name(&self) -> &'static str {
        match self {
            Method::Windowed => "windowed",
            Method::Paper => "paper",
            Method::Traditional => "traditional",
        }
    }
}

impl TryFrom<u8> for Method {
    type Error = UnknownCode;

    /// The method of code `code` (`method as u8`), as on the firmware link and in checkpoints.
    fn try_from(code: u8) -> Result<Method, UnknownCode> {
        from_code(&Method::ALL, "method", code)
    }
}

/// Estimator settings. All angles in radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Config {
    /// Identification method. Default: [`Method::Windowed`].
    pub method: Method,
    /// Period of the rotation pattern, s: the span of the moving average of eq (11). Default
    /// `None`: detected from the rotation angle within the first one or two cycles (see
    /// [`crate::rotation_pattern`]). Pinned: [`ROTATION_PERIOD_RANGE_S`].
    pub rotation_period_s: Option<f64>,
    /// Sample interval, s. Default `None`: learned from the time stamps (see
    /// [`crate::time_grid`]). Pinned: [`SAMPLE_INTERVAL_RANGE_S`].
    pub sample_interval_s: Option<f64>,
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
    /// following them. How closely the estimates follow drifting errors with it:
    /// docs/results.md, "Model mismatch: effects eq (2) does not contain".
    /// The windowed method applies it in full only while its residuals show a persistent bias, and
    /// none while they are noise (docs/method.md, "Learning the noise and the drift").
    pub drift_rad_per_sqrt_s: Real,
    /// 1-sigma of raw roll or pitch about eq (2) for the traditional baseline: the sway. Default
    /// 3 deg / sqrt(2), the RMS of the paper's 3 deg roll sway.
    pub traditional_sigma_rad: Real,
    /// Process noise of the traditional baseline, rad/sqrt(s). Default 0.
    pub traditional_drift_rad_per_sqrt_s: Real,
    /// Start gate: estimation starts once the roll sway amplitude exceeds this (the paper's sea test
    /// used 3 deg). Default 0: off.
    pub sway_gate_rad: Real,
    /// Gaps of up to this many lost samples in a row are filled from their neighbours; longer ones
    /// are left out of the window's sums, the samples around them weighted down, and gaps of an
    /// eighth of a rotation period or more restart the moving average (see [`crate::gap_fill`]).
    /// Default 2, at most [`crate::gap_fill::MAX_FILLABLE_GAP`]; 0 fills none.
    pub max_filled_gap_samples: u32,
    /// An error counts as converged once its 1-sigma is below this. Default 1 arcsec.
    pub converged_sigma_rad: Real,
    /// Largest relative deviation of the time between two passes of the rotation pattern through
    /// the same angle from its period (see [`crate::rotation_pattern`]). Default 0.01 (1 %).
    pub rotation_period_tolerance: Real,
    /// The smallest step of an installation error the change detector is sized for (windowed
    /// method): a step of the errors (a re-installation, a shock) at least this large is detected
    /// from the residuals, reported as [`crate::Status::ErrorsChanged`], and the errors that
    /// changed are learned again from the next window on (see
    /// [`crate::methods::windowed::change`] and docs/method.md, "Changes of the errors: what the
    /// filter does"). Default 20 arcsec; 0 turns detection off.
    pub change_detection_step_rad: Real,
    /// Known values of the installation errors (a dockside or factory calibration, or what an
    /// earlier run learned): the filter starts from them, and they are reported (and compensate
    /// the attitude) from the first sample, before the first measurement; the measurements then
    /// refine them. Default `None`: nothing known, the filter starts from zero with
    /// [`Config::prior_sigma_rad`] and there is no estimate before its first measurement.
    pub prior: Option<Prior>,
    /// How long before the row's time its rotation angle was measured, s (the attitude is taken at
    /// the row's time): the rotation angle is carried forward by this much at the rate of the
    /// last two samples on the grid, `rho + (d rho / d t) S`. At 0.75 deg/s (480 s a turn) a lag
    /// of 0.2 s left uncorrected is a phase error of 0.15 deg in eq (2)'s rotation terms. Default
    /// 0; at most [`MAX_ANGLE_LATENCY_S`].
    pub angle_latency_s: f64,
}

/// The largest [`Config::angle_latency_s`], s.
pub const MAX_ANGLE_LATENCY_S: f64 = 1.0;

/// Known values of the four installation errors and their 1-sigma, rad ([`Config::prior`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prior {
    /// x1..x4, rad; each at most 1 rad in size.
    pub x_rad: [Real; 4],
    /// Their 1-sigma, rad: positive, at most [`Config::prior_sigma_rad`].
    pub sigma_rad: [Real; 4],
}

impl Default for Config {
    fn default() -> Self {
        Config {
            method: Method::Windowed,
            rotation_period_s: None,
            sample_interval_s: None,
            prior_sigma_rad: arcsec_to_rad(1000.0) as Real,
            measurement_sigma_rad: arcsec_to_rad(10.0 / core::f64::consts::SQRT_2) as Real,
            drift_rad_per_sqrt_s: arcsec_to_rad(0.003) as Real,
            traditional_sigma_rad: (3.0 * RAD_PER_DEG / core::f64::consts::SQRT_2) as Real,
            traditional_drift_rad_per_sqrt_s: 0.0,
            sway_gate_rad: 0.0,
            max_filled_gap_samples: 2,
            converged_sigma_rad: arcsec_to_rad(1.0) as Real,
            rotation_period_tolerance: 0.01,
            change_detection_step_rad: arcsec_to_rad(20.0) as Real,
            prior: None,
            angle_latency_s: 0.0,
        }
    }
}

/// A configuration the estimator cannot run with: which parameter, its value and the bound it
/// breaks. Displayed on one line, e.g. `measurement_sigma_rad = -1 must be positive and finite`.
/// Values compare bit for bit, so that equality is an equivalence (a NaN value equals itself).
#[derive(Clone, Copy, Debug)]
pub enum ConfigError {
    /// A pinned `rotation_period_s` outside [`ROTATION_PERIOD_RANGE_S`] (or a ring of fewer than
    /// two entries: `value_s` is then the capacity).
    RotationPeriod {
        /// The pinned period, s (the ring's capacity, entries, for a ring too small).
        value_s: f64,
    },
    /// A pinned `sample_interval_s` outside [`SAMPLE_INTERVAL_RANGE_S`].
    SampleInterval {
        /// The pinned interval, s.
        value_s: f64,
    },
    /// A noise, tolerance, gate or filling limit out of its bound.
    Parameter {
        /// The parameter, as [`Config`] names it (`prior.x_rad[0]` for an element of the prior).
        name: &'static str,
        /// Its value, widened to `f64`.
        value: f64,
        /// The bound it breaks.
        bound: Bound,
    },
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
            (RotationPeriod { value_s: a }, RotationPeriod { value_s: b }) => {
                a.to_bits() == b.to_bits()
            }
            (SampleInterval { value_s: a }, SampleInterval { value_s: b }) => {
                a.to_bits() == b.to_bits()
            }
            (
                Parameter {
                    name: a,
                    value: b,
                    bound: c,
                },
                Parameter {
                    name: d,
                    value: e,
                    bound: f,
                },
            ) => a == d && b.to_bits() == e.to_bits() && c == f,
            (MethodUnavailable, MethodUnavailable) => true,
            _ => false,
        }
    }
}
impl Eq for ConfigError {}

impl core::fmt::Display for ConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ConfigError::RotationPeriod { value_s } => {
                let (lo, hi) = ROTATION_PERIOD_RANGE_S;
                write!(f, "rotation_period_s = {value_s} must be from {lo} to {hi} s (or the ring capacity is below 2)")
            }
            ConfigError::SampleInterval { value_s } => {
                let (lo, hi) = SAMPLE_INTERVAL_RANGE_S;
                write!(
                    f,
                    "sample_interval_s = {value_s} must be from {lo} to {hi} s"
                )
            }
            ConfigError::Parameter { name, value, bound } => match bound {
                Bound::Positive => write!(f, "{name} = {value} must be positive and finite"),
                Bound::NonNegative => {
                    write!(f, "{name} = {value} must be zero or positive, and finite")
                }
                Bound::AtMost(limit) => write!(f, "{name} = {value} must be at most {limit}"),
                Bound::SquareUnderflows => write!(
                    f,
                    "{name} = {value} is too small: its square underflows to 0"
                ),
            },
            ConfigError::MethodUnavailable => write!(
                f,
                "method unavailable: the paper's method needs the `paper-method` feature"
            ),
        }
    }
}

impl core::error::Error for ConfigError {}

impl Config {
    /// The default configuration with another method.
    pub fn with_method(method: Method) -> Config {
        Config {
            method,
            ..Config::default()
        }
    }

    /// Checks the configuration against a ring capacity; the error names the first parameter
    /// out of bounds. The checks run in a fixed order: the method, the capacity and the pinned
    /// period and interval, the sigmas and random walks, the other limits, the known values.
    pub fn check(&self, capacity: usize) -> Result<(), ConfigError> {
        if self.method == Method::Paper && !cfg!(feature = "paper-method") {
            return Err(ConfigError::MethodUnavailable);
        }
        let within = |v: f64, (lo, hi): (f64, f64)| v >= lo && v <= hi;
        if capacity < 2 {
            return Err(ConfigError::RotationPeriod {
                value_s: capacity as f64,
            });
        }
        if let Some(t) = self
            .rotation_period_s
            .filter(|t| !within(*t, ROTATION_PERIOD_RANGE_S))
        {
            return Err(ConfigError::RotationPeriod { value_s: t });
        }
        if let Some(d) = self
            .sample_interval_s
            .filter(|d| !within(*d, SAMPLE_INTERVAL_RANGE_S))
        {
            return Err(ConfigError::SampleInterval { value_s: d });
        }
        self.check_noise()?;
        self.check_limits()?;
        self.check_prior()
    }

    /// The sigmas and random walks: positive (or non-negative) and finite, at most 1 rad (the
    /// random walk over the longest interval), their squares not underflowing, and the prior at
    /// most 1000 times each measurement sigma.
    fn check_noise(&self) -> Result<(), ConfigError> {
        use Bound::*;
        let positive = [
            ("prior_sigma_rad", self.prior_sigma_rad),
            ("measurement_sigma_rad", self.measurement_sigma_rad),
            ("traditional_sigma_rad", self.traditional_sigma_rad),
            ("converged_sigma_rad", self.converged_sigma_rad),
            ("rotation_period_tolerance", self.rotation_period_tolerance),
        ];
        let non_negative = [
            ("drift_rad_per_sqrt_s", self.drift_rad_per_sqrt_s),
            (
                "traditional_drift_rad_per_sqrt_s",
                self.traditional_drift_rad_per_sqrt_s,
            ),
            ("sway_gate_rad", self.sway_gate_rad),
            ("change_detection_step_rad", self.change_detection_step_rad),
        ];
        if let Some((name, v)) = positive.iter().find(|(_, v)| !(*v > 0.0 && v.is_finite())) {
            return fail(name, *v, Positive);
        }
        if let Some((name, v)) = non_negative
            .iter()
            .find(|(_, v)| !(*v >= 0.0 && v.is_finite()))
        {
            return fail(name, *v, NonNegative);
        }
        // Every sigma, and the random walk of one step, at most 1 rad: no installation error or
        // attitude noise comes near a radian, and with that bound no variance can overflow (the
        // prior plus 2^32 steps of random walk stays below 5e9 rad^2). A finiteness check alone
        // lets a random walk or a sigma through whose square or sum overflows the covariance.
        // The longest interval there can be (a learned one is not known yet).
        let interval_s = self.sample_interval_s.unwrap_or(SAMPLE_INTERVAL_RANGE_S.1);
        let dt = interval_s as Real;
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
                return fail(name, d, AtMost(1.0 / libm::sqrt(interval_s)));
            }
        }
        // In f32 a prior far wider than the measurement noise makes the first updates lose the
        // covariance's definiteness (`crate::kalman`: the variance ratio must stay well below
        // 1/eps). Prior at most 1000 times each measurement sigma (variance ratio 1e6).
        let widest = 1000.0 * self.measurement_sigma_rad.min(self.traditional_sigma_rad);
        if self.prior_sigma_rad > widest {
            return fail(
                "prior_sigma_rad",
                self.prior_sigma_rad,
                AtMost(widest as f64),
            );
        }
        Ok(())
    }

    /// The other limits: the longest gap filled, the smallest step detected, the period's
    /// tolerance and the rotation angle's latency.
    fn check_limits(&self) -> Result<(), ConfigError> {
        use Bound::*;
        // A filled sample is interpolated from its neighbours, which a longer gap does not have;
        // at most 50 % off the period, or the pattern is not the one detected.
        if self.max_filled_gap_samples > MAX_FILLABLE_GAP {
            return Err(ConfigError::Parameter {
                name: "max_filled_gap_samples",
                value: f64::from(self.max_filled_gap_samples),
                bound: AtMost(f64::from(MAX_FILLABLE_GAP)),
            });
        }
        // A step of a radian is no installation error; and its square must not overflow.
        if !(self.change_detection_step_rad <= 1.0) {
            return fail(
                "change_detection_step_rad",
                self.change_detection_step_rad,
                AtMost(1.0),
            );
        }
        if !(self.rotation_period_tolerance <= 0.5) {
            return fail(
                "rotation_period_tolerance",
                self.rotation_period_tolerance,
                AtMost(0.5),
            );
        }
        if !(self.angle_latency_s >= 0.0) {
            return fail("angle_latency_s", self.angle_latency_s as Real, NonNegative);
        }
        if !(self.angle_latency_s <= MAX_ANGLE_LATENCY_S) {
            return fail(
                "angle_latency_s",
                self.angle_latency_s as Real,
                AtMost(MAX_ANGLE_LATENCY_S),
            );
        }
        Ok(())
    }

    /// The known values ([`Config::prior`]), if any: each error at most 1 rad, each 1-sigma
    /// positive, finite, at most `prior_sigma_rad` and its square not underflowing.
    fn check_prior(&self) -> Result<(), ConfigError> {
        use Bound::*;
        if let Some(prior) = &self.prior {
            const X: [&str; 4] = [
                "prior.x_rad[0]",
                "prior.x_rad[1]",
                "prior.x_rad[2]",
                "prior.x_rad[3]",
            ];
            const SIGMA: [&str; 4] = [
                "prior.sigma_rad[0]",
                "prior.sigma_rad[1]",
                "prior.sigma_rad[2]",
                "prior.sigma_rad[3]",
            ];
            for i in 0..4 {
                if !(prior.x_rad[i].abs() <= 1.0) {
                    return fail(X[i], prior.x_rad[i], AtMost(1.0));
                }
                let s = prior.sigma_rad[i];
                if !(s > 0.0 && s.is_finite()) {
                    return fail(SIGMA[i], s, Positive);
                }
                if !(s <= self.prior_sigma_rad) {
                    return fail(SIGMA[i], s, AtMost(self.prior_sigma_rad as f64));
                }
                if !(s * s > 0.0) {
                    return fail(SIGMA[i], s, SquareUnderflows);
                }
            }
        }
        Ok(())
    }
}

/// The error for parameter `name` of value `value` out of `bound`.
fn fail(name: &'static str, value: Real, bound: Bound) -> Result<(), ConfigError> {
    Err(ConfigError::Parameter {
        name,
        value: value as f64,
        bound,
    })
}
