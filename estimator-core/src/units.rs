//! Unit conversions. Radians inside the core; degrees and arcseconds for people.

/// Arcseconds in one radian.
pub const ARCSEC_PER_RAD: f64 = 180.0 * 3600.0 / core::f64::consts::PI;
/// Radians in one degree.
pub const RAD_PER_DEG: f64 = core::f64::consts::PI / 180.0;
/// Inertial angular rate of the Earth, rad/s (the paper's omega_e).
pub const EARTH_RATE_RAD_PER_S: f64 = 7.292_115e-5;

/// Arcseconds to radians.
pub fn arcsec_to_rad(arcsec: f64) -> f64 {
    arcsec / ARCSEC_PER_RAD
}

/// Radians to arcseconds.
pub fn rad_to_arcsec(rad: f64) -> f64 {
    rad * ARCSEC_PER_RAD
}

/// Wraps an angle in degrees to [-180, 180). Non-finite input stays non-finite.
pub fn wrap_deg(angle_deg: f64) -> f64 {
    let r = angle_deg % 360.0;
    if r >= 180.0 {
        r - 360.0
    } else if r < -180.0 {
        r + 360.0
    } else {
        r
    }
}
