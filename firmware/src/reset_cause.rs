//! Why the chip last reset, from what the board can see: a cause the firmware left itself before
//! resetting (a clock failure, mps2-an386's watchdog warning; `board/reset_mark.rs`), else the
//! STM32F405's reset flags (RCC_CSR, RM0090 7.3.21).
//!
//! The flags are not exclusive: the NRST pin's flag (PINRSTF) is set by every reset, since the
//! chip drives its own pin low while it resets, and a power-on sets the brown-out flag too
//! (BORRSTF: "set by hardware when a POR/PDR or BOR reset occurs"). So the order matters: the
//! watchdog first, then power-on, then brown-out alone, then software, then the pin alone.

use link_protocol::ResetCause;

/// RCC_CSR's reset flags.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ResetFlags {
    /// IWDGRSTF: the independent watchdog.
    pub watchdog: bool,
    /// PORRSTF: power-on or power-down.
    pub power_on: bool,
    /// BORRSTF: brown-out (also set with a power-on).
    pub brown_out: bool,
    /// SFTRSTF: the firmware (`SCB::sys_reset`).
    pub software: bool,
    /// PINRSTF: the NRST pin (also set with every other reset).
    pub pin: bool,
}

/// The cause of the last reset: `mark`, the one the firmware left, if any, else the flags'.
pub fn reset_cause(mark: Option<ResetCause>, flags: ResetFlags) -> ResetCause {
    if let Some(cause) = mark {
        return cause;
    }
    if flags.watchdog {
        ResetCause::Watchdog
    } else if flags.power_on {
        ResetCause::PowerOn
    } else if flags.brown_out {
        ResetCause::BrownOut
    } else if flags.software {
        ResetCause::Software
    } else if flags.pin {
        ResetCause::Pin
    } else {
        ResetCause::PowerOn
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PIN: ResetFlags = ResetFlags {
        watchdog: false,
        power_on: false,
        brown_out: false,
        software: false,
        pin: true,
    };

    #[test]
    fn each_reset_with_the_flags_the_chip_sets_for_it() {
        // Every reset drives NRST, so PINRSTF comes along; a power-on sets BORRSTF too.
        let cases = [
            (
                ResetFlags {
                    power_on: true,
                    brown_out: true,
                    ..PIN
                },
                ResetCause::PowerOn,
            ),
            (
                ResetFlags {
                    brown_out: true,
                    ..PIN
                },
                ResetCause::BrownOut,
            ),
            (
                ResetFlags {
                    watchdog: true,
                    ..PIN
                },
                ResetCause::Watchdog,
            ),
            (
                ResetFlags {
                    software: true,
                    ..PIN
                },
                ResetCause::Software,
            ),
            (PIN, ResetCause::Pin),
            (ResetFlags::default(), ResetCause::PowerOn),
        ];
        for (flags, cause) in cases {
            assert_eq!(reset_cause(None, flags), cause, "{flags:?}");
        }
    }

    #[test]
    fn the_firmware_s_own_mark_comes_first() {
        // A clock failure resets through SCB::sys_reset: the flags say software, the mark says why.
        let flags = ResetFlags {
            software: true,
            ..PIN
        };
        assert_eq!(
            reset_cause(Some(ResetCause::ClockFailure), flags),
            ResetCause::ClockFailure
        );
    }
}
