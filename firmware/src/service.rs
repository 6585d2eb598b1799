//! The loop's work: one request in, the core stepped, one response out. All estimation is
//! `estimator-core`'s; this file only converts messages, times the step and keeps the counters.

use estimator_core::{Estimator, Output, Sample, SampleError};
use link_protocol::{
    ClockSource, Counters, EstimateMsg, FrameError, LinkCounters, RejectedReply, Request, ResetCause, Response,
    StatusReply, StepReply, PROTOCOL_VERSION,
};

use crate::board::{CostCounter, Flash};
use crate::checkpoint_store::{CheckpointStore, IMAGE_BYTES};
use crate::stack;

// `CHECKPOINT_INTERVAL_S`: 60 s, or `RINS_CHECKPOINT_INTERVAL_S` when the firmware was built
// (checked and written by build.rs).
include!(concat!(env!("OUT_DIR"), "/checkpoint_interval.rs"));

/// Where checkpoints go: the store and the scratch image.
pub struct Persistence<'a> {
    pub store: CheckpointStore<Flash>,
    pub image: &'a mut [u8; IMAGE_BYTES],
    /// Time of the last checkpoint (or of the first sample, before there is one).
    pub last_s: Option<f64>,
}

/// The estimator, the cost counter, the link counters and the checkpoints.
pub struct Service<'a> {
    estimator: &'a mut Estimator,
    cost: CostCounter,
    bad_frames: Counters,
    boot_stack_peak_bytes: u32,
    persistence: Option<Persistence<'a>>,
    reset_cause: ResetCause,
    clock_source: ClockSource,
}

impl<'a> Service<'a> {
    pub fn new(
        estimator: &'a mut Estimator,
        cost: CostCounter,
        boot_stack_peak_bytes: u32,
        persistence: Option<Persistence<'a>>,
        reset_cause: ResetCause,
        clock_source: ClockSource,
    ) -> Self {
        Service {
            estimator,
            cost,
            bad_frames: Counters::default(),
            boot_stack_peak_bytes,
            persistence,
            reset_cause,
            clock_source,
        }
    }

    /// Saves a checkpoint when `CHECKPOINT_INTERVAL_S` of sample time has passed since the last.
    fn maybe_checkpoint(&mut self, time_s: f64) {
        let Some(p) = self.persistence.as_mut() else { return };
        match p.last_s {
            None => p.last_s = Some(time_s),
            Some(last) if time_s - last >= f64::from(CHECKPOINT_INTERVAL_S) => {
                p.last_s = Some(time_s);
                if let Err(error) = p.store.save(self.estimator, time_s, p.image) {
                    defmt::error!("checkpoint at {=f64} s not saved: {}", time_s, error);
                }
            }
            Some(_) => {}
        }
    }

    /// Counts a frame the link dropped.
    pub fn count_bad_frame(&mut self, error: FrameError) {
        self.bad_frames.count_bad_frame(error);
    }

    /// The response to one request (`None`: no answer; the request is counted as a bad frame);
    /// `link`: the receive path's counters, for the status.
    pub fn handle(&mut self, request: &Request, link: LinkCounters) -> Option<Response> {
        Some(match request {
            Request::Sample(msg) => {
                let sample = Sample::from(msg);
                let start = self.cost.stamp();
                let result = step(self.estimator, &sample);
                let ticks = self.cost.ticks_since(start);
                match result {
                    Ok(output) => {
                        // Saved before the answer: the host's next request waits for it.
                        self.maybe_checkpoint(output.time_s);
                        Response::Step(StepReply::new(&output, ticks, self.counters()))
                    }
                    Err(error) => Response::Rejected(RejectedReply::new(sample.time_s, &error, ticks, self.counters())),
                }
            }
            Request::Reset => {
                reset(self.estimator);
                // Forgotten for good: a power cut must not restore the state the host asked to
                // forget. If the flash fails, the Status still shows the checkpoint's time, which
                // tells the host that the reset is incomplete.
                if let Some(p) = self.persistence.as_mut() {
                    p.last_s = None;
                    if let Err(error) = p.store.invalidate() {
                        defmt::error!("checkpoints not invalidated by the reset: {}", error);
                    }
                }
                Response::Status(self.status(link))
            }
            Request::ReadStatus => Response::Status(self.status(link)),
            // Only a test build acts on it (main.rs); here it is no request.
            Request::Hang => {
                self.count_bad_frame(FrameError::Message);
                return None;
            }
        })
    }

    fn counters(&self) -> Counters {
        Counters {
            bad_frames: self.bad_frames.bad_frames,
            rejected_samples: self.estimator.rejected().0,
        }
    }

    fn status(&self, link: LinkCounters) -> StatusReply {
        let counters = self.estimator.counters();
        StatusReply {
            protocol_version: PROTOCOL_VERSION,
            method: self.estimator.config().method as u8,
            counters: self.counters(),
            accepted: counters.accepted,
            filled: counters.filled,
            window_restarts: counters.window_restarts,
            estimate: self.estimator.estimate().as_ref().map(EstimateMsg::from),
            cost_counter_hz: self.cost.hz(),
            boot_stack_peak_bytes: self.boot_stack_peak_bytes,
            stack_peak_bytes: stack::peak_bytes(),
            stack_size_bytes: stack::size_bytes(),
            checkpoint_time_s: self.persistence.as_ref().and_then(|p| p.store.time_s),
            checkpoints_saved: self.persistence.as_ref().map_or(0, |p| p.store.saved),
            link,
            reset_cause: self.reset_cause as u8,
            clock_source: self.clock_source as u8,
        }
    }
}

/// Out of line, so that whatever `Estimator::reset` needs (it works in place, a few hundred
/// bytes) stays out of `main`'s frame, which lives for ever.
#[inline(never)]
fn reset(estimator: &mut Estimator) {
    estimator.reset();
}

/// The timed call, kept out of line so that no work moves across the cost counter's readings.
#[inline(never)]
fn step(estimator: &mut Estimator, sample: &Sample) -> Result<Output, SampleError> {
    estimator.step(sample)
}
