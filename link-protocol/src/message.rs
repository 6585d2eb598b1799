//! The messages. Each is serialised with postcard (serde data model: enum variant = varint index,
//! `u8` = one byte, `u32` = varint, `f32`/`f64` = 4/8 bytes little-endian IEEE 754, `Option` = one
//! byte 0/1 then the value, arrays = their elements in order). The byte layout of every message is
//! in docs/link-protocol.md; the tests in this module pin it.
//!
//! Sample fields travel exactly as [`estimator_core::Sample`] holds them, so the firmware feeds its
//! core bit-identical samples to the ones the host builds with `Sample::from_degrees`; output values
//! travel exactly as [`estimator_core::Output`] holds them, so the host rebuilds the same `Output`.
//! Variants are only ever appended, never reordered.

use estimator_core::{Attitude, Estimate, Field, Output, Real, RejectReason, Sample, SampleError, Status};
use serde::{Deserialize, Serialize};

use crate::frame::FrameError;

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
}

/// [`estimator_core::Sample`], field for field.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct SampleMsg {
    pub time_s: f64,
    pub rotation_rad: Real,
    pub platform_rad: Real,
    pub latitude_rad: Real,
    pub heading_rad: Real,
    pub roll_rad: Real,
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
    pub x_rad: [Real; 4],
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

/// Bad frames by [`FrameError`] code (`as u8`) and rejected samples by [`RejectReason`] code,
/// since boot (they survive `Reset`; saturating).
#[derive(Serialize, Deserialize, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub bad_frames: [u32; FrameError::COUNT],
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
        self.bad_frames.iter().fold(0u32, |a, b| a.saturating_add(*b))
    }

    /// All rejected samples.
    pub fn rejected_samples_total(&self) -> u32 {
        self.rejected_samples.iter().fold(0u32, |a, b| a.saturating_add(*b))
    }
}

/// An accepted sample's [`estimator_core::Output`], the cost of its step and the counters.
#[derive(Serialize, Deserialize, Clone, Copy, Debug, PartialEq)]
pub struct StepReply {
    pub time_s: f64,
    /// [`Status::code`].
    pub status: u8,
    pub estimate: Option<EstimateMsg>,
    pub corrected_heading_rad: Real,
    pub corrected_roll_rad: Real,
    pub corrected_pitch_rad: Real,
    /// Ticks of the board's cost counter spent in `Estimator::step` (see
    /// [`StatusReply::cost_counter_hz`]).
    pub step_cost_ticks: u32,
    pub counters: Counters,
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
    pub step_cost_ticks: u32,
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
    pub counters: Counters,
    /// The estimator's counters: samples accepted, lost samples filled from their neighbours,
    /// window restarts.
    pub accepted: u32,
    pub filled: u32,
    pub window_restarts: u32,
    pub estimate: Option<EstimateMsg>,
    /// Frequency of the cost counter behind `step_cost_ticks` (the core clock, for SysTick).
    pub cost_counter_hz: u32,
    /// Stack high-water marks (painted stack): of the start-up (the core's `Estimator::new`), and
    /// of the service loop since then (includes a `Reset`'s if one was served); the stack's size.
    pub boot_stack_peak_bytes: u32,
    pub stack_peak_bytes: u32,
    pub stack_size_bytes: u32,
    /// Sample time of the newest checkpoint saved or restored at boot (`None`: none, or no flash).
    pub checkpoint_time_s: Option<f64>,
    /// Checkpoints saved since boot.
    pub checkpoints_saved: u32,
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
    fn a_reply_whose_codes_do_not_fit_is_no_error() {
        let ok = RejectedReply::new(1.0, &SampleError::NonFinite(Field::Roll), 0, Counters::default());
        for (reason, field) in [(0, NO_FIELD), (0, 7), (1, 5), (2, NO_FIELD), (5, NO_FIELD), (255, 0)] {
            assert_eq!(RejectedReply { reason, field, ..ok }.error(), None, "reason {reason} field {field}");
        }
    }
}
