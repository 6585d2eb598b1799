//! The step cost the firmware reports, in its board's cost-counter ticks, turned into instructions
//! (under QEMU) or core cycles (on a board).
//!
//! Under QEMU with `-icount shift=S`, each guest instruction takes 2^S ns of virtual time and the
//! firmware's SysTick counts at `cost_counter_hz` (25 MHz) of virtual time, so
//! `instructions = ticks * 1e9 / (2^S * cost_counter_hz)`: 40 instructions per tick for S = 0,
//! exact to one tick (the counter is read before and after the step; the reading and the call add a
//! few instructions). On a board SysTick counts core cycles: `cycles = ticks`.

/// Max and mean of the step costs, in ticks.
#[derive(Clone, Copy, Debug, Default)]
pub struct CostStats {
    /// Steps counted.
    pub steps: u64,
    /// The largest step cost, ticks.
    pub max_ticks: u32,
    /// Sum of the step costs, ticks.
    pub sum_ticks: u64,
}

impl CostStats {
    /// Counts one step that cost `ticks`.
    pub fn add(&mut self, ticks: u32) {
        self.steps += 1;
        self.max_ticks = self.max_ticks.max(ticks);
        self.sum_ticks += ticks as u64;
    }

    /// Mean step cost, ticks (0 before any step).
    pub fn mean_ticks(&self) -> f64 {
        if self.steps == 0 {
            0.0
        } else {
            self.sum_ticks as f64 / self.steps as f64
        }
    }
}

/// What a tick is worth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CostUnit {
    /// QEMU with `-icount shift`: ticks convert exactly into instructions.
    QemuInstructions {
        /// QEMU's `-icount shift`: each guest instruction takes 2^shift ns of virtual time.
        icount_shift: u32,
        /// Frequency of the firmware's cost counter, Hz of virtual time.
        counter_hz: u32,
    },
    /// A real board: ticks are core cycles.
    BoardCycles {
        /// Frequency of the cost counter, Hz: the core clock.
        counter_hz: u32,
    },
}

impl CostUnit {
    /// Instructions (QEMU) or cycles (board) per tick.
    pub fn per_tick(&self) -> f64 {
        match *self {
            CostUnit::QemuInstructions {
                icount_shift,
                counter_hz,
            } => 1e9 / ((1u64 << icount_shift) as f64 * counter_hz as f64),
            CostUnit::BoardCycles { .. } => 1.0,
        }
    }

    /// The summary line, `step cost: max N instructions, mean M instructions` (cycles on a board).
    pub fn summary(&self, stats: &CostStats) -> String {
        self.describe("step cost", stats)
    }

    /// `LABEL: max N instructions, mean M instructions` (cycles on a board, with the largest in
    /// microseconds at the core clock).
    pub fn describe(&self, label: &str, stats: &CostStats) -> String {
        let max = stats.max_ticks as f64 * self.per_tick();
        let mean = stats.mean_ticks() * self.per_tick();
        match self {
            CostUnit::QemuInstructions { .. } => {
                format!("{label}: max {max:.0} instructions, mean {mean:.0} instructions")
            }
            CostUnit::BoardCycles { counter_hz } => format!(
                "{label}: max {max:.0} cycles, mean {mean:.0} cycles (max {:.1} us at {:.1} MHz)",
                max / *counter_hz as f64 * 1e6,
                *counter_hz as f64 / 1e6
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_tick_is_forty_instructions_at_icount_shift_0_and_25_mhz() {
        let unit = CostUnit::QemuInstructions {
            icount_shift: 0,
            counter_hz: 25_000_000,
        };
        assert_eq!(unit.per_tick(), 40.0);
        let mut s = CostStats::default();
        s.add(100);
        s.add(50);
        assert_eq!(
            unit.summary(&s),
            "step cost: max 4000 instructions, mean 3000 instructions"
        );
    }
}
