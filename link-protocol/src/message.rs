//! The messages. Each is serialised with postcard (serde data model: enum variant = varint index,
//! `u8` = one byte, `u32` = varint, `f32`/`f64` = 4/8 bytes little-endian IEEE 754, `Option` = one
//! byte 0/1 then the value, arrays = their elements in order). The byte layout of every message is
//! in docs/link-protocol.md; the tests in this module pin it.
//!
//! Sample fields travel exactly as [`estimator_core::Sample`] holds them, so the firmware feeds its
//! core bit-identical samples to the ones the host builds with `Sample::from_degrees`; output values
//! travel exactly as [`estimator_core::Output`] holds them, so the host rebuilds the same `Output`.
//! Variants are only ever appended, never reordered; the test builds' `Hang` stays last, so that
//! every build numbers the production variants alike.

use estimator_core::{
    Attitude, Estimate, Field, Health, Output, Real, RejectReason, Sample, SampleError, Status,
    UnknownCode,
};
use serde::{Deserialize, Serialize};

use crate::frame::FrameError;

/// One frame's message with its sequence number: every frame in both directions carries one
/// (protocol 5). The host numbers its requests 1, 2, 3, ... in the order it sends them; the
/// firmware answers each with the request's number, so a host that sends without waiting
/// (`host-sim stream --push`) matches every answer to its request, and a gap in the numbers shows
/// a lost frame at either end. The firmware's unasked `Ready` carries [`UNNUMBERED`], as may a
/// request from a host that does not count (the firmware then counts no loss for it).
///
/// On the wire: `seq` as a varint (1 to 5 bytes), then the message.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct Numbered<T> {
    /// The sequence number: the request's, in its answer too; [`UNNUMBERED`] outside the numbered
    /// stream.
    pub seq: u32,
    /// The message it numbers.
    pub message: T,
}

/// The sequence number of a frame that is not part of the numbered stream (`Ready`).
pub const UNNUMBERED: u32 = 0;

/// Host to firmware.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub enum Request {
    /// (0) One RINS sample: answered by [`Response::Step`] or [`Response::Rejected`].
    Sample(SampleMsg),
    /// (1) Forget everything learnt (the estimator's `reset`; counters are kept) and invalidate
    /// the stored checkpoints, so that no restart can bring the state back: answered by
    /// [`Response::Status`].
    Reset,
    /// (2) Answered by [`Response::Status`].
    ReadStatus,
    /// (3) One sample at the navigation computer's own rate (up to 200 Hz), as it comes: the
    /// firmware averages it into the bin of its grid interval it falls in (the core's
    /// [`estimator_core::binning::Binner`]), steps the estimator with a bin once a later bin's
    /// first sample arrives, and compensates the sample with the estimate then current
    /// ([`estimator_core::Estimator::compensate`]). Answered by [`Response::Nav`], or by
    /// [`Response::Rejected`] for a sample the binner refuses (its fields, or a time not after the
    /// last one's; nothing changes).
    NavSample(SampleMsg),
    /// (4) Only for the watchdog test, and only with this crate's `test-hang` feature (which the
    /// firmware's `test-hang` feature and host-sim's tests turn on): a firmware built with it
    /// stops its main loop for good (it no longer feeds the watchdog), so the watchdog must reset
    /// it. Without the feature the variant does not exist: its bytes fail to decode, and the
    /// firmware counts them as a `message` bad frame and never answers.
    #[cfg(feature = "test-hang")]
    Hang,
}

/// Firmware to host. Exactly one response per well-formed request; none for a bad frame.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub enum Response {
    /// (0) The sample was accepted and stepped.
    Step(StepReply),
    /// (1) The core rejected the sample; the estimator is unchanged.
    Rejected(RejectedReply),
    /// (2) Answer to `ReadStatus` and `Reset`.
    Status(StatusReply),
    /// (3) Sent once, unasked, at boot, as soon as the serial port can receive: the host sends its
    /// first request only after it. (A serial port drops what arrives before it is enabled; QEMU's
    /// STM32 USART does.) A host that sees it in the middle of a stream knows the firmware restarted.
    Ready {
        /// [`crate::PROTOCOL_VERSION`] of the firmware.
        protocol_version: u8,
    },
    /// (4) Answer to `NavSample`: the sample compensated, and the step of the bin it completed.
    Nav(NavReply),
}

/// The answer to a [`Request::NavSample`]: the sample's attitude compensated with the current
/// estimate, and what the bin the sample completed gave the estimator.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct NavReply {
    /// The sample's time stamp, s, as received.
    pub time_s: f64,
    /// The sample's heading, roll and pitch with eq (2)'s oscillation for the current estimate
    /// removed, rad ([`estimator_core::Estimator::compensate`], after the bin's step); `None` while
    /// there is no estimate.
    pub corrected_rad: Option<[Real; 3]>,
    /// The step of the bin this sample completed (the bin before the sample's), if one did.
    pub bin: BinOutcome,
    /// Ticks of the board's cost counter spent on the sample: the binning, the bin's step when
    /// there is one, and the compensation (see [`StatusReply::cost_counter_hz`]).
    pub cost_ticks: u32,
}

/// What the bin a navigation sample completed gave the estimator.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub enum BinOutcome {
    /// (0) No bin completed: the sample opened none, or fell in the bin being filled.
    Open,
    /// (1) The bin's average was stepped: its [`StepReply`] (its time is the bin's centre).
    Step(StepReply),
    /// (2) The core rejected the bin's average (a time the estimator refuses); the estimator is
    /// unchanged.
    Rejected(RejectedReply),
}

/// [`estimator_core::Sample`], field for field.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct SampleMsg {
    /// Time stamp, s ([`Sample::time_s`]).
    pub time_s: f64,
    /// Rotation angle rho, rad ([`Sample::rotation_rad`]).
    pub rotation_rad: Real,
    /// Platform angle s, rad ([`Sample::platform_rad`]).
    pub platform_rad: Real,
    /// Latitude, rad ([`Sample::latitude_rad`]).
    pub latitude_rad: Real,
    /// Heading, rad ([`Attitude::heading_rad`] of [`Sample::attitude`]).
    pub heading_rad: Real,
    /// Roll, rad ([`Attitude::roll_rad`] of [`Sample::attitude`]).
    pub roll_rad: Real,
    /// Pitch, rad ([`Attitude::pitch_rad`] of [`Sample::attitude`]).
    pub pitch_rad: Real,
}

impl From<&Sample> for SampleMsg {
    fn from(s: &Sample) -> Self {
        SampleMsg {
            time_s: s.time_s,
            rotation_rad: s.rotation_rad,
            platform_rad: s.platform_rad,
            latitude_rad: s.latitude_rad,
            heading_rad: s.attitude.heading_rad,
            roll_rad: s.attitude.roll_rad,
            pitch_rad: s.attitude.pitch_rad,
        }
    }
}

impl From<&SampleMsg> for Sample {
    fn from(m: &SampleMsg) -> Self {
        Sample {
            time_s: m.time_s,
            rotation_rad: m.rotation_rad,
            platform_rad: m.platform_rad,
            latitude_rad: m.latitude_rad,
            attitude: Attitude {
                heading_rad: m.heading_rad,
                roll_rad: m.roll_rad,
                pitch_rad: m.pitch_rad,
            },
        }
    }
}

/// [`estimator_core::Estimate`]: x1..x4 and their 1-sigma, rad.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct EstimateMsg {
    /// x1..x4, rad.
    pub x_rad: [Real; 4],
    /// Their 1-sigma, rad.
    pub sigma_rad: [Real; 4],
}

impl From<&Estimate> for EstimateMsg {
    fn from(e: &Estimate) -> Self {
        EstimateMsg {
            x_rad: e.x_rad,
            sigma_rad: e.sigma_rad,
        }
    }
}

impl From<&EstimateMsg> for Estimate {
    fn from(e: &EstimateMsg) -> Self {
        Estimate {
            x_rad: e.x_rad,
            sigma_rad: e.sigma_rad,
        }
    }
}

/// [`estimator_core::Health`]: the latched alarms and the residuals' level of a step.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct HealthMsg {
    /// Changes of the installation errors declared ([`Health::changes_detected`]).
    pub changes_detected: u32,
    /// Time stamp of the sample at which the last change was declared, s
    /// ([`Health::last_change_s`]).
    pub last_change_s: Option<f64>,
    /// Restarts of the moving average ([`Health::window_restarts`]).
    pub window_restarts: u32,
    /// Samples rejected, every reason ([`Health::rejected`]).
    pub rejected: u32,
    /// Time spent in status `model_mismatch`, s ([`Health::mismatch_s`]).
    pub mismatch_s: f64,
    /// The residual level of the pitch and the roll channel pair, rad ([`Health::residual_rad`]).
    pub residual_rad: Option<[Real; 2]>,
    /// The factor by which each pair's learned noise widens the reported 1-sigma
    /// ([`Health::noise_scale`]).
    pub noise_scale: Option<[Real; 2]>,
}

impl From<&Health> for HealthMsg {
    fn from(h: &Health) -> Self {
        HealthMsg {
            changes_detected: h.changes_detected,
            last_change_s: h.last_change_s,
            window_restarts: h.window_restarts,
            rejected: h.rejected,
            mismatch_s: h.mismatch_s,
            residual_rad: h.residual_rad,
            noise_scale: h.noise_scale,
        }
    }
}

impl From<&HealthMsg> for Health {
    fn from(h: &HealthMsg) -> Self {
        Health {
            changes_detected: h.changes_detected,
            last_change_s: h.last_change_s,
            window_restarts: h.window_restarts,
            rejected: h.rejected,
            mismatch_s: h.mismatch_s,
            residual_rad: h.residual_rad,
            noise_scale: h.noise_scale,
        }
    }
}

/// Bad frames by [`FrameError`] code (`as u8`) and rejected samples by [`RejectReason`] code,
/// since boot (they survive `Reset`; saturating).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Bad frames, indexed by [`FrameError`] code.
    pub bad_frames: [u32; FrameError::COUNT],
    /// Rejected samples, indexed by [`RejectReason`] code.
    pub rejected_samples: [u32; RejectReason::ALL.len()],
}

impl Counters {
    /// Counts one bad frame.
    pub fn count_bad_frame(&mut self, error: FrameError) {
        if let Some(slot) = self.bad_frames.get_mut(error as usize) {
            *slot = slot.saturating_add(1);
        }
    }

    /// All bad frames.
    pub fn bad_frames_total(&self) -> u32 {
        self.bad_frames
            .iter()
            .fold(0u32, |a, b| a.saturating_add(*b))
    }

    /// All rejected samples.
    pub fn rejected_samples_total(&self) -> u32 {
        self.rejected_samples
            .iter()
            .fold(0u32, |a, b| a.saturating_add(*b))
    }
}

/// An accepted sample's [`estimator_core::Output`], the cost of its step and the counters.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct StepReply {
    /// The sample's time stamp, s, as received ([`Output::time_s`]).
    pub time_s: f64,
    /// [`Status::code`].
    pub status: u8,
    /// The output's estimate, `None` while there is none ([`Output::estimate`]).
    pub estimate: Option<EstimateMsg>,
    /// The corrected heading, rad ([`Output::corrected`]).
    pub corrected_heading_rad: Real,
    /// The corrected roll, rad ([`Output::corrected`]).
    pub corrected_roll_rad: Real,
    /// The corrected pitch, rad ([`Output::corrected`]).
    pub corrected_pitch_rad: Real,
    /// Ticks of the board's cost counter spent in `Estimator::step` (see
    /// [`StatusReply::cost_counter_hz`]).
    pub step_cost_ticks: u32,
    /// The bad frames and rejected samples counted, after this sample.
    pub counters: Counters,
    /// The output's latched alarms and residuals' level.
    pub health: HealthMsg,
}

impl StepReply {
    /// Builds the reply from the core's output.
    pub fn new(output: &Output, step_cost_ticks: u32, counters: Counters) -> Self {
        StepReply {
            time_s: output.time_s,
            status: output.status.code(),
            estimate: output.estimate.as_ref().map(EstimateMsg::from),
            corrected_heading_rad: output.corrected.heading_rad,
            corrected_roll_rad: output.corrected.roll_rad,
            corrected_pitch_rad: output.corrected.pitch_rad,
            step_cost_ticks,
            counters,
            health: HealthMsg::from(&output.health),
        }
    }

    /// The core's output again; `None` if the status code is unknown.
    pub fn output(&self) -> Option<Output> {
        Some(Output {
            time_s: self.time_s,
            status: Status::try_from(self.status).ok()?,
            estimate: self.estimate.as_ref().map(Estimate::from),
            corrected: Attitude {
                heading_rad: self.corrected_heading_rad,
                roll_rad: self.corrected_roll_rad,
                pitch_rad: self.corrected_pitch_rad,
            },
            health: Health::from(&self.health),
        })
    }
}

/// A sample the core rejected, and why.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct RejectedReply {
    /// The rejected sample's time, as received.
    pub time_s: f64,
    /// The [`RejectReason`] code.
    pub reason: u8,
    /// The [`Field`] code of the field named by the error, [`NO_FIELD`] when the reason names none.
    pub field: u8,
    /// Ticks of the board's cost counter spent in `Estimator::step` (see
    /// [`StatusReply::cost_counter_hz`]).
    pub step_cost_ticks: u32,
    /// The bad frames and rejected samples counted, this rejection included.
    pub counters: Counters,
}

/// No field named.
pub const NO_FIELD: u8 = 0xFF;

impl RejectedReply {
    /// Builds the reply from the core's error.
    pub fn new(time_s: f64, error: &SampleError, step_cost_ticks: u32, counters: Counters) -> Self {
        RejectedReply {
            time_s,
            reason: error.reason() as u8,
            field: error.field().map_or(NO_FIELD, |f| f as u8),
            step_cost_ticks,
            counters,
        }
    }

    /// The core's error again; `None` for unknown codes or a field that does not fit the reason.
    pub fn error(&self) -> Option<SampleError> {
        let reason = RejectReason::try_from(self.reason).ok()?;
        let field = match self.field {
            NO_FIELD => None,
            code => Some(Field::try_from(code).ok()?),
        };
        SampleError::from_parts(reason, field)
    }
}

/// What the firmware knows about itself.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct StatusReply {
    /// [`crate::PROTOCOL_VERSION`].
    pub protocol_version: u8,
    /// The running configuration's [`estimator_core::Method`] code (`method as u8`).
    pub method: u8,
    /// The bad frames and rejected samples counted.
    pub counters: Counters,
    /// Samples the estimator accepted ([`estimator_core::Counters::accepted`]).
    pub accepted: u32,
    /// Lost samples the estimator filled from their neighbours
    /// ([`estimator_core::Counters::filled`]).
    pub filled: u32,
    /// Restarts of the estimator's moving average ([`estimator_core::Counters::window_restarts`]).
    pub window_restarts: u32,
    /// The estimator's estimate, `None` while it has none.
    pub estimate: Option<EstimateMsg>,
    /// Frequency of the cost counter behind `step_cost_ticks` (the core clock, for SysTick).
    pub cost_counter_hz: u32,
    /// Stack high-water mark (painted stack) of the start-up (the core's `Estimator::new`), bytes.
    pub boot_stack_peak_bytes: u32,
    /// Stack high-water mark of the service loop since the start-up (includes a `Reset`'s if one
    /// was served), bytes.
    pub stack_peak_bytes: u32,
    /// The stack's size, bytes.
    pub stack_size_bytes: u32,
    /// Sample time of the newest checkpoint saved or restored at boot (`None`: none, or no flash).
    pub checkpoint_time_s: Option<f64>,
    /// Checkpoints saved since boot.
    pub checkpoints_saved: u32,
    /// The receive path's counters since boot.
    pub link: LinkCounters,
    /// Why the firmware last started ([`ResetCause`] code, `as u8`).
    pub reset_cause: u8,
    /// What clocks the core ([`ClockSource`] code, `as u8`).
    pub clock_source: u8,
}

/// The receive path's counters since boot (they survive `Reset`; saturating), and its buffer.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkCounters {
    /// Numbered requests that never arrived intact: gaps in the sequence numbers received.
    pub lost_frames: u32,
    /// Bytes the UART itself lost: a byte completed while the previous one was still in its data
    /// register (the STM32's ORE, the CMSDK UART's RX overrun).
    pub uart_overruns: u32,
    /// Times the receive buffer overflowed: received bytes overwritten or dropped before the
    /// firmware read them (the DMA ring lapped, or the interrupt ring was full).
    pub buffer_overruns: u32,
    /// Bytes received with a framing error (no stop bit where one belongs: wrong baud rate, a
    /// break, a line fault).
    pub framing_errors: u32,
    /// Bytes received with noise (the STM32's NF: the samples of a bit disagreed).
    pub noise_errors: u32,
    /// Size of the receive buffer, bytes.
    pub rx_buffer_bytes: u32,
    /// Most bytes that were waiting in the receive buffer at once since boot.
    pub rx_peak_bytes: u32,
}

impl LinkCounters {
    /// Every error the receive path saw (lost frames, overruns of both kinds, framing, noise).
    pub fn errors_total(&self) -> u32 {
        [
            self.lost_frames,
            self.uart_overruns,
            self.buffer_overruns,
            self.framing_errors,
            self.noise_errors,
        ]
        .iter()
        .fold(0u32, |a, b| a.saturating_add(*b))
    }

    /// Overruns of either kind (UART and buffer).
    pub fn overruns(&self) -> u32 {
        self.uart_overruns.saturating_add(self.buffer_overruns)
    }
}

/// Why the firmware started, as far as the board can tell (code: `as u8`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum ResetCause {
    /// Power-on, or a board that cannot tell.
    PowerOn = 0,
    /// The watchdog: the main loop stopped feeding it.
    Watchdog = 1,
    /// The supply fell below the brown-out level.
    BrownOut = 2,
    /// The firmware reset itself after a fatal error.
    Software = 3,
    /// The reset pin (a debugger, a button).
    Pin = 4,
    /// The clock security system saw the crystal fail; the firmware reset itself to start again
    /// on what still runs.
    ClockFailure = 5,
}

impl ResetCause {
    /// Every cause, in code order.
    pub const ALL: [ResetCause; 6] = [
        ResetCause::PowerOn,
        ResetCause::Watchdog,
        ResetCause::BrownOut,
        ResetCause::Software,
        ResetCause::Pin,
        ResetCause::ClockFailure,
    ];

    /// Short name, as the host prints it.
    pub const fn name(&self) -> &'static str {
        match self {
            ResetCause::PowerOn => "power-on",
            ResetCause::Watchdog => "watchdog",
            ResetCause::BrownOut => "brown-out",
            ResetCause::Software => "software",
            ResetCause::Pin => "reset pin",
            ResetCause::ClockFailure => "clock failure",
        }
    }
}

impl TryFrom<u8> for ResetCause {
    type Error = UnknownCode;

    fn try_from(code: u8) -> Result<Self, UnknownCode> {
        Self::ALL
            .into_iter()
            .find(|c| *c as u8 == code)
            .ok_or(UnknownCode {
                what: "reset-cause",
                code,
            })
    }
}

/// What clocks the core (code: `as u8`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum ClockSource {
    /// The crystal (HSE) through the PLL, as intended.
    Crystal = 0,
    /// The internal RC oscillator (HSI, 16 MHz) alone, because the crystal did not start in
    /// time: the baud rate is within the HSI's +-1 % instead of the crystal's ppm.
    InternalFallback = 1,
    /// The board's one fixed clock (mps2-an386), or an emulator's (QEMU).
    Fixed = 2,
}

impl ClockSource {
    /// Every source, in code order.
    pub const ALL: [ClockSource; 3] = [
        ClockSource::Crystal,
        ClockSource::InternalFallback,
        ClockSource::Fixed,
    ];

    /// Short name, as the host prints it.
    pub const fn name(&self) -> &'static str {
        match self {
            ClockSource::Crystal => "crystal",
            ClockSource::InternalFallback => "internal RC (crystal failed to start)",
            ClockSource::Fixed => "fixed",
        }
    }
}

impl TryFrom<u8> for ClockSource {
    type Error = UnknownCode;

    fn try_from(code: u8) -> Result<Self, UnknownCode> {
        Self::ALL
            .into_iter()
            .find(|c| *c as u8 == code)
            .ok_or(UnknownCode {
                what: "clock-source",
                code,
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sample_survives_the_message_bit_for_bit() {
        let s = Sample::from_degrees(12345.0, 370.25, -12.5, 32.1, 359.9, -2.5, 1.25);
        let back = Sample::from(&SampleMsg::from(&s));
        assert_eq!(back.time_s.to_bits(), s.time_s.to_bits());
        assert_eq!(back, s);
    }

    #[test]
    fn sample_error_survives_the_reply() {
        let errors = [
            SampleError::NonFinite(Field::Time),
            SampleError::NonFinite(Field::Pitch),
            SampleError::LatitudeOutOfRange,
            SampleError::AngleOutOfRange(Field::Heading),
            SampleError::TimeNotIncreasing,
            SampleError::IrregularTimeStep,
        ];
        for e in errors {
            let r = RejectedReply::new(1.0, &e, 0, Counters::default());
            assert_eq!(r.error(), Some(e));
        }
    }

    #[test]
    fn reset_causes_and_clock_sources_list_their_codes_in_order() {
        for (i, c) in ResetCause::ALL.iter().enumerate() {
            assert_eq!(*c as usize, i);
            assert_eq!(ResetCause::try_from(i as u8), Ok(*c));
        }
        assert!(ResetCause::try_from(ResetCause::ALL.len() as u8).is_err());
        for (i, c) in ClockSource::ALL.iter().enumerate() {
            assert_eq!(*c as usize, i);
            assert_eq!(ClockSource::try_from(i as u8), Ok(*c));
        }
        assert!(ClockSource::try_from(ClockSource::ALL.len() as u8).is_err());
    }

    #[test]
    fn link_counters_add_up_their_errors() {
        let c = LinkCounters {
            lost_frames: 1,
            uart_overruns: 2,
            buffer_overruns: 4,
            framing_errors: 8,
            noise_errors: 16,
            rx_buffer_bytes: 1000,
            rx_peak_bytes: 500,
        };
        assert_eq!(c.errors_total(), 31);
        assert_eq!(c.overruns(), 6);
        let saturated = LinkCounters {
            lost_frames: u32::MAX,
            ..c
        };
        assert_eq!(saturated.errors_total(), u32::MAX);
    }

    #[test]
    fn a_reply_whose_codes_do_not_fit_is_no_error() {
        let ok = RejectedReply::new(
            1.0,
            &SampleError::NonFinite(Field::Roll),
            0,
            Counters::default(),
        );
        for (reason, field) in [
            (0, NO_FIELD),
            (0, 7),
            (1, 5),
            (2, NO_FIELD),
            (5, NO_FIELD),
            (255, 0),
        ] {
            assert_eq!(
                RejectedReply {
                    reason,
                    field,
                    ..ok
                }
                .error(),
                None,
                "reason {reason} field {field}"
            );
        }
    }
}
