//! The estimator's configuration in the firmware: the core's defaults, with what the build sets
//! (`firmware/build.rs`): the rotation angle's latency (`RINS_ANGLE_LATENCY_MS`) and known values
//! of the installation errors (`RINS_PRIOR_ARCSEC`, `RINS_PRIOR_SIGMA_ARCSEC`), checked there so that a
//! bad value fails the build, not the boot. A checkpoint restored at boot brings the
//! configuration it was saved with: an image built with other settings takes effect after a
//! `Reset` (or on a fresh flash).

use estimator_core::units::ARCSEC_PER_RAD;
use estimator_core::{Config, Prior, Real};

include!(concat!(env!("OUT_DIR"), "/estimator_config.rs"));

/// The configuration the firmware makes its estimator with.
pub fn config() -> Config {
    let rad = |arcsec: f64| (arcsec / ARCSEC_PER_RAD) as Real;
    Config {
        angle_latency_s: ANGLE_LATENCY_S,
        prior: PRIOR_ARCSEC.map(|(x, sigma)| Prior {
            x_rad: x.map(rad),
            sigma_rad: sigma.map(rad),
        }),
        ..Config::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the build wrote is a configuration the core accepts (the defaults unless the
    /// environment set them).
    #[test]
    fn the_build_time_configuration_is_accepted() {
        assert!(config().check(720).is_ok(), "{:?}", config());
    }
}
