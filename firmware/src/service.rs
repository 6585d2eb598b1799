//! The loop's work: one request in, the core stepped, one response out. All estimation is
//! `estimator-core`'s; this file only converts messages, times the step and keeps the counters.

use estimator_core::{Estimator, Output, Sample, SampleError};
use link_protocol::{
    Counters, EstimateMsg, FrameError, RejectedReply, Request, Response, StatusReply, StepReply, PROTOCOL_VERSION,
};

use crate::board::CostCounter;
use crate::stack;

/// The estimator, the cost counter and the link counters.
pub struct Service<'a> {
    estimator: &'a mut Estimator,
    cost: CostCounter,
    bad_frames: Counters,
    boot_stack_peak_bytes: u32,
}

impl<'a> Service<'a> {
    pub fn new(estimator: &'a mut Estimator, cost: CostCounter, boot_stack_peak_bytes: u32) -> Self {
        Service {
            estimator,
            cost,
            bad_frames: Counters::default(),
            boot_stack_peak_bytes,
        }
    }

    /// Counts a frame the link dropped.
    pub fn count_bad_frame(&mut self, error: FrameError) {
        self.bad_frames.count_bad_frame(error);
    }

    /// The response to one request.
    pub fn handle(&mut self, request: &Request) -> Response {
        match request {
            Request::Sample(msg) => {
                let sample = Sample::from(msg);
                let start = self.cost.stamp();
                let result = step(self.estimator, &sample);
                let ticks = self.cost.ticks_since(start);
                match result {
                    Ok(output) => Response::Step(StepReply::new(&output, ticks, self.counters())),
                    Err(error) => Response::Rejected(RejectedReply::new(sample.time_s, &error, ticks, self.counters())),
                }
            }
            Request::Reset => {
                reset(self.estimator);
                Response::Status(self.status())
            }
            Request::ReadStatus => Response::Status(self.status()),
        }
    }

    fn counters(&self) -> Counters {
        Counters {
            bad_frames: self.bad_frames.bad_frames,
            rejected_samples: self.estimator.rejected().0,
        }
    }

    fn status(&self) -> StatusReply {
        let (accepted, bridged, window_restarts) = self.estimator.counters();
        StatusReply {
            protocol_version: PROTOCOL_VERSION,
            method: self.estimator.config().method.code(),
            counters: self.counters(),
            accepted,
            bridged,
            window_restarts,
            estimate: self.estimator.estimate().as_ref().map(EstimateMsg::from),
            cost_counter_hz: CostCounter::HZ,
            boot_stack_peak_bytes: self.boot_stack_peak_bytes,
            stack_peak_bytes: stack::peak_bytes(),
            stack_size_bytes: stack::size_bytes(),
        }
    }
}

/// Out of line: the core's `reset` builds a fresh estimator on the stack (about 27 KiB of stack
/// with `new`'s own frame); kept out of `main`'s frame, that stack is used only while it runs.
#[inline(never)]
fn reset(estimator: &mut Estimator) {
    estimator.reset();
}

/// The timed call, kept out of line so that no work moves across the cost counter's readings.
#[inline(never)]
fn step(estimator: &mut Estimator, sample: &Sample) -> Result<Output, SampleError> {
    estimator.step(sample)
}
