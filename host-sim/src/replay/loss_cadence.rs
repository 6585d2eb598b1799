//! Rows lost at a regular cadence: whether the holes in a log recur a fixed spacing apart.
//!
//! A hole in the window's sums (filled from its neighbours or tapered, `estimator-core`'s
//! `gap_fill`) leaves a small remainder of the sway in them. Holes at random places leave
//! remainders that average out like noise, and the residuals show them. Holes at a regular
//! cadence (a recorder that loses rows every 60, 90 or 120 s) make the weights of the sums
//! periodic, and a sway line in step with that pattern and the rotation leaves the same remainder
//! window after window: a bias the residuals cannot show, which the reported 1-sigma then leaves
//! out (docs/uncertainty.md, "Rows lost at a cadence"; docs/swell-study.md). The estimator does
//! not look for it; the replay does, and names it.

use estimator_core::time_grid::Placement;

/// Most holes remembered; a log with more is judged on its first ones.
pub const MAX_HOLES: usize = 1 << 16;
/// Holes that must recur before the cadence is named.
pub const MIN_RECURRING_HOLES: usize = 10;
/// Share of the holes that must recur, a cadence later, before the cadence is named (rows lost
/// at random as well take the rest).
pub const MIN_RECURRING_SHARE: f64 = 0.3;
/// Longest cadence looked for, samples.
pub const MAX_CADENCE_SAMPLES: u64 = 4096;

/// The holes of a log on its sample grid, as the replay places its rows.
#[derive(Clone, Debug, Default)]
pub struct LossCadence {
    /// Grid index of the first lost row of each hole (from the first accepted row, each clock step
    /// starting a new stretch far from the last), ascending.
    holes: Vec<u64>,
    /// Grid index of the last accepted row.
    index: u64,
}

/// Holes that recur at a regular cadence: what the summary names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegularLoss {
    /// Holes remembered.
    pub holes: usize,
    /// Of them, those with another hole one cadence (within a sample) after it.
    pub recurring: usize,
    /// The cadence, s.
    pub cadence_s: f64,
}

impl LossCadence {
    /// Follows an accepted row's placement on the grid.
    pub fn observe(&mut self, placement: Placement) {
        match placement {
            Placement::Learning => self.index += 1,
            Placement::OnGrid { intervals } => {
                if intervals > 1 && self.holes.len() < MAX_HOLES {
                    self.holes.push(self.index + 1);
                }
                self.index += u64::from(intervals.max(1));
            }
            // A new stretch: far enough that no hole of the last one recurs into it.
            Placement::ClockStep => self.index += 1 << 32,
        }
    }

    /// Whether the holes recur at a regular cadence on a grid of `interval_s`: the spacing (up to
    /// [`MAX_CADENCE_SAMPLES`]) at which the most holes have another hole within a sample after
    /// them, `Some` when at least [`MIN_RECURRING_HOLES`] and a share [`MIN_RECURRING_SHARE`] of
    /// the holes do.
    pub fn regular(&self, interval_s: f64) -> Option<RegularLoss> {
        if interval_s.is_nan() || interval_s <= 0.0 || self.holes.len() < MIN_RECURRING_HOLES {
            return None;
        }
        // Pairs of holes by their spacing.
        let mut pairs = vec![0usize; MAX_CADENCE_SAMPLES as usize + 2];
        for (i, &h) in self.holes.iter().enumerate() {
            for &later in &self.holes[i + 1..] {
                let lag = later - h;
                if lag > MAX_CADENCE_SAMPLES {
                    break;
                }
                pairs[lag as usize] += 1;
            }
        }
        // Pairs within a sample of `lag` (a stamp jittered across a slot boundary moves a hole by
        // one). Holes one or two apart are one longer hole's pieces, not a cadence.
        let near = |lag: usize| pairs[lag - 1] + pairs[lag] + pairs[lag + 1];
        let most = (3..=MAX_CADENCE_SAMPLES as usize).map(near).max()?;
        // Every multiple of the cadence holds about as many pairs: the shortest spacing with most
        // of them is the cadence, at its exact spacing.
        let first = (3..=MAX_CADENCE_SAMPLES as usize).find(|&lag| 5 * near(lag) >= 4 * most)?;
        let cadence = (first..=first + 1).max_by_key(|&lag| pairs[lag])? as u64;
        let recurs = |h: u64| {
            let from = self.holes.partition_point(|&x| x + 1 < h + cadence);
            self.holes.get(from).is_some_and(|&x| x <= h + cadence + 1)
        };
        let recurring = self.holes.iter().filter(|&&h| recurs(h)).count();
        let share = recurring as f64 / self.holes.len() as f64;
        if recurring < MIN_RECURRING_HOLES || share < MIN_RECURRING_SHARE {
            return None;
        }
        Some(RegularLoss {
            holes: self.holes.len(),
            recurring,
            cadence_s: cadence as f64 * interval_s,
        })
    }
}

impl RegularLoss {
    /// The limit it sets, for the summary and the report.
    pub fn describe(&self) -> String {
        format!(
            "limit: rows lost at a regular cadence ({} of {} holes have another {} s later): the \
             weights of the window's sums repeat at that cadence, and on a sea whose swell stays \
             steady for hours the sway a hole leaves in the sums does not average out; the \
             1-sigma above may understate the error several-fold (docs/uncertainty.md, \
             \"Rows lost at a cadence\")",
            self.recurring,
            self.holes,
            super::summary::significant_4(self.cadence_s),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cadence of `gap_rows` lost every `every` samples over `n` samples, plus the lost rows
    /// at `random` (indices).
    fn follow(n: u64, every: u64, gap_rows: u64, random: &[u64]) -> LossCadence {
        let mut c = LossCadence::default();
        let lost =
            |i: u64| (every > 0 && i % every < gap_rows && i >= every) || random.contains(&i);
        let mut last = 0;
        c.observe(Placement::Learning);
        for i in 1..n {
            if lost(i) {
                continue;
            }
            c.observe(Placement::OnGrid {
                intervals: (i - last) as u32,
            });
            last = i;
        }
        c
    }

    /// `n` distinct indices spread at random (a fixed xorshift) below `below`, ascending.
    fn scatter(n: usize, below: u64) -> Vec<u64> {
        let mut x = 0x2545_f491_4f6c_dd1d_u64;
        let mut v: Vec<u64> = (0..n)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x % below
            })
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    #[test]
    fn a_regular_cadence_is_named_with_its_spacing() {
        let c = follow(20_000, 120, 4, &[]);
        let regular = c.regular(1.0).expect("holes every 120 s");
        assert_eq!(regular.cadence_s, 120.0);
        assert!(regular.recurring * 10 >= regular.holes * 9, "{regular:?}");
        // At 10 Hz the cadence is in samples of 0.1 s.
        assert_eq!(
            follow(20_000, 600, 3, &[]).regular(0.1).unwrap().cadence_s,
            60.0
        );
    }

    #[test]
    fn a_cadence_under_rows_lost_at_random_is_named() {
        // About 1 % lost at random on top of 3 rows every 90 s.
        let random = scatter(400, 40_000);
        let regular = follow(40_000, 90, 3, &random)
            .regular(1.0)
            .expect("holes every 90 s");
        assert_eq!(regular.cadence_s, 90.0);
    }

    #[test]
    fn rows_lost_at_random_are_not_named() {
        // A fixed scatter of single lost rows (about 1 %, no cadence).
        let random = scatter(400, 40_000);
        assert_eq!(follow(40_000, 0, 0, &random).regular(1.0), None);
        // Too few holes, or no interval: nothing to judge.
        assert_eq!(follow(1_000, 120, 4, &[]).regular(1.0), None);
        assert_eq!(follow(20_000, 120, 4, &[]).regular(0.0), None);
    }
}
