//! The estimator's configuration as a C struct: the core's `Config` field by field, in its units
//! (radians, seconds).

use crate::error::{code, RinsError};
use crate::pointer;
use estimator_core::estimator::DEFAULT_CAPACITY;
use estimator_core::{Config, Method, Prior, Real};

/// Which identification method runs (the value of `RinsConfig.method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum RinsMethod {
    /// Ours, the default: the four correlation channels averaged over one rotation period, fed
    /// into one 4-state Kalman filter.
    Windowed = 0,
    /// The paper's eqs (8)-(18) as published. Only in a library built with the `paper-method`
    /// feature; otherwise refused with `RINS_ERROR_INVALID_CONFIG`.
    Paper = 1,
    /// The paper's Fig. 2 baseline: a 4-state filter on raw roll and pitch.
    Traditional = 2,
}

impl From<Method> for RinsMethod {
    fn from(method: Method) -> RinsMethod {
        match method {
            Method::Windowed => RinsMethod::Windowed,
            Method::Paper => RinsMethod::Paper,
            Method::Traditional => RinsMethod::Traditional,
        }
    }
}

/// The estimator's settings. Fill it with `rins_config_default`, then change what differs.
/// Angles in radians, times in seconds. `docs/method.md` explains each; the bounds are checked by
/// `rins_config_check` (and by `rins_estimator_init`).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct RinsConfig {
    /// One of `RinsMethod`. Default `RINS_METHOD_WINDOWED`.
    pub method: u32,
    /// Period of the rotation pattern, s, 60 to 3600; 0 (the default): detected from the
    /// rotation angle.
    pub rotation_period_s: f64,
    /// Sample interval, s, 0.1 to 10; 0 (the default): learned from the time stamps.
    pub sample_interval_s: f64,
    /// Prior 1-sigma of each installation error, rad. Default 1000 arcsec.
    pub prior_sigma_rad: f32,
    /// 1-sigma of one correlation measurement, rad. Default 10/sqrt(2) arcsec.
    pub measurement_sigma_rad: f32,
    /// Random walk of the installation errors, rad/sqrt(s). Default 0.003 arcsec/sqrt(s).
    pub drift_rad_per_sqrt_s: f32,
    /// 1-sigma of raw roll or pitch for the traditional baseline, rad. Default 3 deg / sqrt(2).
    pub traditional_sigma_rad: f32,
    /// Process noise of the traditional baseline, rad/sqrt(s). Default 0.
    pub traditional_drift_rad_per_sqrt_s: f32,
    /// Start gate: estimation starts once the roll sway amplitude exceeds this, rad. Default 0:
    /// off.
    pub sway_gate_rad: f32,
    /// Gaps of up to this many lost samples in a row are filled from their neighbours. Default 2
    /// (at most 3; 0 fills none).
    pub max_filled_gap_samples: u32,
    /// An error counts as converged once its 1-sigma is below this, rad. Default 1 arcsec.
    pub converged_sigma_rad: f32,
    /// Largest relative deviation of the rotation pattern's period. Default 0.01.
    pub rotation_period_tolerance: f32,
    /// Smallest step of an installation error the change detector is sized for, rad (windowed
    /// method): a larger step is reported as `RINS_STATUS_ERRORS_CHANGED` and learned again.
    /// Default 20 arcsec; 0 turns detection off.
    pub change_detection_step_rad: f32,
    /// Known values of x1..x4, rad (a calibration, or what an earlier run learned), used when
    /// `prior_x_sigma_rad` is set: the filter starts from them and they are reported, and
    /// compensate the attitude, from the first sample. Default zeros.
    pub prior_x_rad: [f32; 4],
    /// The 1-sigma of `prior_x_rad`, rad, each positive and at most `prior_sigma_rad`; all four 0
    /// (the default): nothing known, the filter starts from zero and reports nothing before its
    /// first measurement.
    pub prior_x_sigma_rad: [f32; 4],
    /// How long before the sample's time its rotation angle was measured, s, 0 to 1 (the
    /// attitude taken at the sample's time): the angle is carried forward at the rotation's rate.
    /// Default 0.
    pub angle_latency_s: f64,
}

/// A period or interval of the C struct: 0 stands for "not pinned".
fn pinned(value_s: f64) -> Option<f64> {
    if value_s == 0.0 {
        None
    } else {
        Some(value_s)
    }
}

impl From<&Config> for RinsConfig {
    fn from(c: &Config) -> RinsConfig {
        RinsConfig {
            method: RinsMethod::from(c.method) as u32,
            rotation_period_s: c.rotation_period_s.unwrap_or(0.0),
            sample_interval_s: c.sample_interval_s.unwrap_or(0.0),
            prior_sigma_rad: c.prior_sigma_rad as f32,
            measurement_sigma_rad: c.measurement_sigma_rad as f32,
            drift_rad_per_sqrt_s: c.drift_rad_per_sqrt_s as f32,
            traditional_sigma_rad: c.traditional_sigma_rad as f32,
            traditional_drift_rad_per_sqrt_s: c.traditional_drift_rad_per_sqrt_s as f32,
            sway_gate_rad: c.sway_gate_rad as f32,
            max_filled_gap_samples: c.max_filled_gap_samples,
            converged_sigma_rad: c.converged_sigma_rad as f32,
            rotation_period_tolerance: c.rotation_period_tolerance as f32,
            change_detection_step_rad: c.change_detection_step_rad as f32,
            prior_x_rad: c.prior.map_or([0.0; 4], |p| p.x_rad.map(|v| v as f32)),
            prior_x_sigma_rad: c.prior.map_or([0.0; 4], |p| p.sigma_rad.map(|v| v as f32)),
            angle_latency_s: c.angle_latency_s,
        }
    }
}

impl RinsConfig {
    /// The core's configuration, checked for the library's estimator (the same check
    /// `Estimator::new` makes). An unknown method code is an invalid configuration.
    pub fn to_core(&self) -> Result<Config, estimator_core::ConfigError> {
        let method = u8::try_from(self.method)
            .ok()
            .and_then(|m| Method::try_from(m).ok())
            .ok_or(estimator_core::ConfigError::Parameter {
                name: "method",
                value: f64::from(self.method),
                bound: estimator_core::config::Bound::AtMost((Method::ALL.len() - 1) as f64),
            })?;
        let config = Config {
            method,
            rotation_period_s: pinned(self.rotation_period_s),
            sample_interval_s: pinned(self.sample_interval_s),
            prior_sigma_rad: self.prior_sigma_rad as Real,
            measurement_sigma_rad: self.measurement_sigma_rad as Real,
            drift_rad_per_sqrt_s: self.drift_rad_per_sqrt_s as Real,
            traditional_sigma_rad: self.traditional_sigma_rad as Real,
            traditional_drift_rad_per_sqrt_s: self.traditional_drift_rad_per_sqrt_s as Real,
            sway_gate_rad: self.sway_gate_rad as Real,
            max_filled_gap_samples: self.max_filled_gap_samples,
            converged_sigma_rad: self.converged_sigma_rad as Real,
            rotation_period_tolerance: self.rotation_period_tolerance as Real,
            change_detection_step_rad: self.change_detection_step_rad as Real,
            prior: (self.prior_x_sigma_rad != [0.0; 4]).then(|| Prior {
                x_rad: self.prior_x_rad.map(|v| v as Real),
                sigma_rad: self.prior_x_sigma_rad.map(|v| v as Real),
            }),
            angle_latency_s: self.angle_latency_s,
        };
        config.check(DEFAULT_CAPACITY)?;
        Ok(config)
    }
}

/// Fills `*config` with the defaults (the paper's setting; `docs/method.md`).
///
/// # Safety
/// `config` is null (refused) or points to a writable `RinsConfig`.
#[no_mangle]
pub unsafe extern "C" fn rins_config_default(config: *mut RinsConfig) -> RinsError {
    // SAFETY: the caller's promise.
    code(unsafe { pointer::write(config, RinsConfig::from(&Config::default())) })
}

/// Checks `*config`: `RINS_ERROR_OK`, or `RINS_ERROR_INVALID_CONFIG` with the first parameter out
/// of its bounds described in `message` (one line, e.g.
/// `measurement_sigma_rad = -1 must be positive and finite`, NUL-terminated and cut to fit
/// `capacity` bytes). `message` may be null (then `capacity` is ignored).
///
/// # Safety
/// `config` is null (refused) or points to a readable `RinsConfig`; `message` is null or points
/// to `capacity` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn rins_config_check(
    config: *const RinsConfig,
    message: *mut core::ffi::c_char,
    capacity: usize,
) -> RinsError {
    // SAFETY: the caller's promise.
    let config = match unsafe { pointer::read(config) } {
        Ok(c) => c,
        Err(e) => return e,
    };
    let Err(error) = config.to_core() else {
        return RinsError::Ok;
    };
    if !message.is_null() {
        // SAFETY: `capacity` writable bytes by the caller's promise.
        if let Ok(buffer) = unsafe { pointer::bytes_mut(message.cast::<u8>(), capacity) } {
            crate::text::write_message(buffer, format_args!("{error}"));
        }
    }
    RinsError::InvalidConfig
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::indexing_slicing)]
    use super::*;
    use core::ffi::CStr;
    use core::mem::MaybeUninit;

    fn defaults() -> RinsConfig {
        let mut c = MaybeUninit::<RinsConfig>::uninit();
        // SAFETY: a writable RinsConfig.
        assert_eq!(
            unsafe { rins_config_default(c.as_mut_ptr()) },
            RinsError::Ok
        );
        // SAFETY: written above.
        unsafe { c.assume_init() }
    }

    #[test]
    fn defaults_are_the_cores_bit_for_bit() {
        let c = defaults();
        assert_eq!(c.to_core().unwrap(), Config::default());
        assert_eq!(
            (c.rotation_period_s, c.sample_interval_s, c.method),
            (0.0, 0.0, RinsMethod::Windowed as u32)
        );
        // SAFETY: null is refused, not written.
        assert_eq!(
            unsafe { rins_config_default(core::ptr::null_mut()) },
            RinsError::NullPointer
        );
    }

    #[test]
    fn pinned_values_and_every_method_reach_the_core() {
        let mut c = defaults();
        c.rotation_period_s = 480.0;
        c.sample_interval_s = 1.0;
        c.method = RinsMethod::Traditional as u32;
        let core = c.to_core().unwrap();
        assert_eq!(
            (core.rotation_period_s, core.sample_interval_s, core.method),
            (Some(480.0), Some(1.0), Method::Traditional)
        );
        assert_eq!(RinsConfig::from(&core), c);
        for m in Method::ALL {
            assert_eq!(RinsMethod::from(m) as u32, m as u32);
        }
    }

    #[test]
    fn a_bad_configuration_is_refused_with_the_cores_message() {
        let mut c = defaults();
        c.measurement_sigma_rad = -1.0;
        let mut message = [0x55u8; 80];
        // SAFETY: a readable config and 80 writable bytes.
        let e = unsafe { rins_config_check(&c, message.as_mut_ptr().cast(), message.len()) };
        assert_eq!(e, RinsError::InvalidConfig);
        let text = CStr::from_bytes_until_nul(&message)
            .unwrap()
            .to_str()
            .unwrap();
        assert_eq!(
            text,
            "measurement_sigma_rad = -1 must be positive and finite"
        );
        // Cut to fit, still NUL-terminated; a null message is allowed.
        let mut short = [0x55u8; 8];
        // SAFETY: as above.
        assert_eq!(
            unsafe { rins_config_check(&c, short.as_mut_ptr().cast(), short.len()) },
            RinsError::InvalidConfig
        );
        assert_eq!(
            CStr::from_bytes_until_nul(&short)
                .unwrap()
                .to_str()
                .unwrap(),
            "measure"
        );
        // SAFETY: as above.
        assert_eq!(
            unsafe { rins_config_check(&c, core::ptr::null_mut(), 99) },
            RinsError::InvalidConfig
        );
        let mut unknown = defaults();
        unknown.method = 7;
        assert!(unknown.to_core().is_err());
        let mut nan = defaults();
        nan.rotation_period_s = f64::NAN;
        assert!(nan.to_core().is_err());
        // SAFETY: null is refused.
        assert_eq!(
            unsafe { rins_config_check(core::ptr::null(), core::ptr::null_mut(), 0) },
            RinsError::NullPointer
        );
        // SAFETY: a readable config.
        assert_eq!(
            unsafe { rins_config_check(&defaults(), core::ptr::null_mut(), 0) },
            RinsError::Ok
        );
    }
}
