//! The fits: the log read once, every row handed to one replay per variant, side by side (rayon),
//! a batch of rows at a time; each fit's residual and measurement sums kept a rotation period at a
//! time (see the module doc of [`crate::commission`]).

use super::{Fit, Variant, FOUND_POWER_SHARE};
use crate::commission::verdict::MIN_HEADING_PERIODS;
use crate::formats::log_csv::{self, LogError, LogLine, RowFilter};
use crate::formats::read_ahead::{read_ahead, READ_AHEAD_BATCH};
use crate::replay::replayer::{Replayer, StepView};
use crate::replay::{Replay, ReplayError};
use estimator_core::units::rad_to_arcsec;
use estimator_core::Config;
use rayon::prelude::*;
use std::path::Path;

/// One rotation period's sums of a fit's measurement and post-fit residual, rad, and of the
/// heading (unwrapped, from the period's first row, rad) against eq (2)'s heading oscillation for
/// the fit's estimate at each row, rad: `[heading, oscillation, heading x oscillation,
/// oscillation^2]`.
#[derive(Clone, Copy, Debug, Default)]
struct Period {
    z: [f64; 4],
    residual: [f64; 4],
    heading: [f64; 4],
    n: u32,
}

impl Period {
    /// The covariance of the heading with the oscillation over the period, and the variance of
    /// the oscillation, rad^2.
    fn heading_moments(&self) -> (f64, f64) {
        let k = 1.0 / f64::from(self.n.max(1));
        let [h, o, ho, oo] = self.heading.map(|v| v * k);
        (ho - h * o, oo - o * o)
    }
}

/// What a fit keeps while its replay runs: one [`Period`] a rotation period (a 30-day log at a
/// 480 s period keeps 5,400 of 104 bytes).
#[derive(Default)]
struct Accumulator {
    current: Period,
    /// The last heading seen, deg, and the heading unwrapped from the period's first row, rad.
    heading: Option<(f64, f64)>,
    periods: Vec<Period>,
}

impl Accumulator {
    fn observe(&mut self, view: &StepView) {
        let Ok(out) = view.result else {
            return;
        };
        if out.estimate.is_none() {
            return;
        }
        let est = view.estimator;
        let (Some(residual), Some(m)) = (
            view.residuals_rad(),
            est.windowed().and_then(|w| w.window().sums().measurement()),
        ) else {
            return;
        };
        let row = &view.line.row;
        let unwrapped = match self.heading {
            Some((last, from_first)) if self.current.n > 0 => {
                from_first
                    + ((row.heading_deg - last + 180.0).rem_euclid(360.0) - 180.0).to_radians()
            }
            _ => 0.0,
        };
        self.heading = Some((row.heading_deg, unwrapped));
        let x = out.estimate.map_or([0.0; 4], |e| e.x_rad.map(f64::from));
        let oscillation = crate::sim::samples::oscillation_rad(
            &x,
            row.rotation_deg.to_radians(),
            row.platform_deg.to_radians(),
            row.latitude_deg.to_radians(),
        )[0];
        let p = &mut self.current;
        p.n += 1;
        p.heading[0] += unwrapped;
        p.heading[1] += oscillation;
        p.heading[2] += unwrapped * oscillation;
        p.heading[3] += oscillation * oscillation;
        for ch in 0..4 {
            p.z[ch] += f64::from(m.z[ch]);
            p.residual[ch] += f64::from(residual[ch]);
        }
        // One period of rows (as learned or pinned; 1 until both are known).
        let rows = match (est.rotation().period_s, est.sample_interval_s()) {
            (Some(t), Some(d)) if d > 0.0 => (t / d).round().max(1.0) as u32,
            _ => 1,
        };
        if p.n >= rows {
            self.periods.push(std::mem::take(p));
        }
    }

    fn finish(self, variant: Variant, replay: Replay) -> Fit {
        let later = &self.periods[self.periods.len() / 2..];
        // The median, not the mean: a turn's transient lifts a few periods, not the log.
        let power = |of: &dyn Fn(&Period) -> [f64; 4]| -> Option<f64> {
            if later.is_empty() {
                return None;
            }
            let mut sq: Vec<f64> = later
                .iter()
                .map(|p| {
                    let k = 1.0 / f64::from(p.n.max(1));
                    of(p)
                        .iter()
                        .map(|v| rad_to_arcsec(v * k).powi(2))
                        .sum::<f64>()
                        / 4.0
                })
                .collect();
            sq.sort_by(f64::total_cmp);
            Some(sq[sq.len() / 2])
        };
        // The heading's sign does not grow with the log, as the misfit does: every period from the
        // first estimate counts.
        let moments: Vec<(f64, f64)> = self.periods.iter().map(Period::heading_moments).collect();
        let variance: f64 = moments.iter().map(|m| m.1).sum();
        // A standard error needs a few periods' coefficients.
        let heading_agreement =
            (variance > 0.0 && moments.len() >= MIN_HEADING_PERIODS).then(|| {
                let c = moments.iter().map(|m| m.0).sum::<f64>() / variance;
                // The scatter of the periods' own coefficients about it.
                let n = moments.len() as f64;
                let mean_var = variance / n;
                let spread = moments
                    .iter()
                    .map(|m| ((m.0 - c * m.1) / mean_var).powi(2))
                    .sum::<f64>()
                    / (n - 1.0).max(1.0);
                (c, (spread / n).sqrt())
            });
        Fit {
            variant,
            heading_agreement,
            oscillation_found: false,
            periods: self.periods.len(),
            residual_power_arcsec2: power(&|p| p.residual),
            measurement_power_arcsec2: power(&|p| p.z),
            replay,
        }
    }
}

/// One variant's replay as the rows come.
struct Fitting {
    variant: Variant,
    replayer: Replayer<'static>,
    acc: Accumulator,
    /// The error that ended the replay, if one did.
    failed: Option<ReplayError>,
}

impl Fitting {
    fn push_all(&mut self, batch: &[Result<LogLine, LogError>]) {
        for item in batch {
            if self.failed.is_some() {
                return;
            }
            let item = item.clone().map(|mut line| {
                self.variant.apply(&mut line.row);
                line
            });
            let acc = &mut self.acc;
            let pushed = self.replayer.push(item, &mut |_| {}, &mut |view| {
                acc.observe(view);
                Ok(())
            });
            if let Err(e) = pushed {
                self.failed = Some(e);
            }
        }
    }
}

/// Fits the log under each of `variants` (the first should be [`Variant::AsIs`]: the errors and
/// the unreadable rows are its replay's; the others see the same rows). `strict`: the first
/// unreadable row refuses the log. Errors as `estimate`'s: a log that cannot be read or is refused
/// (exit status 1), no row read ([`crate::exit_status::RunEnd::NothingRead`], 3).
pub fn fit_variants(
    log: &Path,
    config: Config,
    strict: bool,
    variants: &[Variant],
) -> anyhow::Result<Vec<Fit>> {
    let mut fits = Vec::with_capacity(variants.len());
    for &variant in variants {
        fits.push(Fitting {
            variant,
            replayer: Replayer::new(config, &[], RowFilter::new(strict))?,
            acc: Accumulator::default(),
            failed: None,
        });
    }
    let lines = log_csv::LogReader::open(log)?;
    read_ahead(lines, |items| {
        // Batches of the reader's own size: once every replay has stopped on an error, no more
        // rows are asked for than the reader has handed over (standard input held open never
        // blocks a refused log).
        let mut batch = Vec::with_capacity(READ_AHEAD_BATCH);
        loop {
            batch.clear();
            batch.extend(items.take(READ_AHEAD_BATCH));
            if batch.is_empty() {
                break;
            }
            fits.par_iter_mut().for_each(|f| f.push_all(&batch));
            if fits.iter().all(|f| f.failed.is_some()) {
                break;
            }
        }
    });
    let mut out = Vec::with_capacity(fits.len());
    for f in fits {
        if let Some(e) = f.failed {
            return Err(e.for_people(log, None));
        }
        out.push(f.acc.finish(f.variant, f.replayer.finish()));
    }
    let top = out
        .iter()
        .filter_map(|f| f.measurement_power_arcsec2)
        .fold(0.0, f64::max);
    for f in &mut out {
        f.oscillation_found = f
            .measurement_power_arcsec2
            .is_some_and(|m| top > 0.0 && m >= FOUND_POWER_SHARE * top);
    }
    if let Some(first) = out.first() {
        first.replay.check_rows_read(log)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What the docs say a fit keeps a rotation period.
    #[test]
    fn a_period_keeps_104_bytes() {
        assert_eq!(std::mem::size_of::<Period>(), 104);
    }
}
