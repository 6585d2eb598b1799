//! The loop's work: one request in, the core stepped, one response out. All estimation is
//! `estimator-core`'s; this file only converts messages, times the step and keeps the counters.

use estimator_core::binning::Binner;
use estimator_core::{Estimator, Output, Sample, SampleError};
use link_protocol::{
    BinOutcome, ClockSource, Counters, EstimateMsg, FrameError, LinkCounters, NavReply,
    RejectedReply, Request, ResetCause, Response, StatusReply, StepReply, PROTOCOL_VERSION,
};

use estimator_core::checkpoint::CheckpointError;
use firmware::checkpoint_store::{
    CheckpointStore, Restored, SaveSchedule, StoreBuffers, CHECKPOINT_INTERVAL_S,
};

use super::board::{CostCounter, Flash};
use super::stack;

/// Where checkpoints go, and when.
pub struct Persistence {
    store: CheckpointStore<'static, Flash>,
    schedule: SaveSchedule,
}

#[cfg_attr(not(feature = "checkpoint"), allow(dead_code))]
impl Persistence {
    /// The store on `flash`, working in `buffers` (sectors a power cut left half-erased are erased
    /// again first), with the newest checkpoint restored into `estimator`; `None` (logged) if the
    /// flash is unusable.
    pub fn open(
        flash: Flash,
        buffers: &'static mut StoreBuffers,
        estimator: &mut Estimator,
    ) -> Option<Persistence> {
        let mut store = match CheckpointStore::new(flash, buffers) {
            Ok(store) => store,
            Err(error) => {
                defmt::error!("no checkpoints: {}", error);
                return None;
            }
        };
        if store.re_erased() > 0 {
            defmt::warn!(
                "{=u32} flash sector(s) left half-erased by a power cut, erased again",
                store.re_erased()
            );
        }
        let restored = store.restore(estimator);
        match restored {
            Ok(Restored::Image { time_s: Some(t) }) => defmt::info!("restored the checkpoint of {=f64} s", t),
            Ok(Restored::Image { time_s: None }) => defmt::info!("restored a checkpoint taken before any sample"),
            Ok(Restored::Nothing) => defmt::info!("no checkpoint to restore"),
            Ok(Restored::Forgotten) => defmt::info!("no checkpoint to restore (the last one was reset)"),
            Ok(Restored::Refused(CheckpointError::Version { found, expected })) => defmt::warn!(
                "checkpoint of format version {=u16} refused (this firmware reads {=u16}), starting afresh",
                found,
                expected
            ),
            Ok(Restored::Learned { time_s, .. }) => defmt::warn!(
                "checkpoint of another version refused: started from the learned errors of {=f64} s",
                time_s
            ),
            Ok(Restored::Refused(_)) => defmt::warn!("checkpoint refused by the core (damaged or foreign), starting afresh"),
            Err(error) => defmt::error!("checkpoints unreadable, starting afresh: {}", error),
        }
        let schedule = SaveSchedule::new(f64::from(CHECKPOINT_INTERVAL_S), store.time_s());
        Some(Persistence { store, schedule })
    }
}

/// The estimator, the navigation-rate binner (bins of the estimator's 1 s grid,
/// [`estimator_core::binning::DEFAULT_BIN_INTERVAL_S`]), the cost counter, the link counters and the
/// checkpoints.
pub struct Service<'a> {
    estimator: &'a mut Estimator,
    binner: Binner,
    /// Navigation-rate samples the binner refused, by [`estimator_core::RejectReason`] code: they
    /// never reach the estimator, whose own count leaves them out.
    nav_rejected: [u32; estimator_core::RejectReason::ALL.len()],
    cost: CostCounter,
    bad_frames: Counters,
    boot_stack_peak_bytes: u32,
    persistence: Option<Persistence>,
    reset_cause: ResetCause,
    clock_source: ClockSource,
}

impl<'a> Service<'a> {
    pub fn new(
        estimator: &'a mut Estimator,
        cost: CostCounter,
        boot_stack_peak_bytes: u32,
        persistence: Option<Persistence>,
        reset_cause: ResetCause,
        clock_source: ClockSource,
    ) -> Self {
        Service {
            estimator,
            binner: Binner::default(),
            nav_rejected: [0; estimator_core::RejectReason::ALL.len()],
            cost,
            bad_frames: Counters::default(),
            boot_stack_peak_bytes,
            persistence,
            reset_cause,
            clock_source,
        }
    }

    /// Saves a checkpoint when one is due after the sample at `time_s` ([`SaveSchedule`]). Out of
    /// line: one copy for the two kinds of sample.
    #[inline(never)]
    fn maybe_checkpoint(&mut self, time_s: f64) {
        let Some(p) = self.persistence.as_mut() else {
            return;
        };
        if p.schedule.due(time_s) {
            if let Err(error) = p.store.save(self.estimator) {
                defmt::error!("checkpoint at {=f64} s not saved: {}", time_s, error);
            }
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
                    Err(error) => Response::Rejected(RejectedReply::new(
                        sample.time_s,
                        &error,
                        ticks,
                        self.counters(),
                    )),
                }
            }
            Request::NavSample(msg) => self.nav_sample(&Sample::from(msg)),
            Request::Reset => {
                reset(self.estimator);
                self.binner = Binner::default();
                // Forgotten for good: a power cut must not restore the state the host asked to
                // forget. If the flash fails, the Status still shows the checkpoint's time, which
                // tells the host that the reset is incomplete.
                if let Some(p) = self.persistence.as_mut() {
                    p.schedule.restart();
                    if let Err(error) = p.store.invalidate() {
                        defmt::error!("checkpoints not invalidated by the reset: {}", error);
                    }
                }
                Response::Status(self.status(link))
            }
            Request::ReadStatus => Response::Status(self.status(link)),
            // Only the watchdog test's build has it and acts on it (main.rs); here it is no request.
            #[cfg(feature = "test-hang")]
            Request::Hang => {
                self.count_bad_frame(FrameError::Message);
                return None;
            }
        })
    }

    /// A navigation-rate sample: binned; the bin it completes, if any, stepped (and checkpointed
    /// when one is due); then the sample compensated with the estimate of that step. Out of line:
    /// the image's flash, not its speed, is what it would cost inlined into the loop.
    #[inline(never)]
    fn nav_sample(&mut self, sample: &Sample) -> Response {
        let start = self.cost.stamp();
        let completed = match self.binner.push(sample) {
            Ok(completed) => completed,
            Err(error) => {
                let ticks = self.cost.ticks_since(start);
                if let Some(n) = self.nav_rejected.get_mut(error.reason() as usize) {
                    *n = n.saturating_add(1);
                }
                return Response::Rejected(RejectedReply::new(
                    sample.time_s,
                    &error,
                    ticks,
                    self.counters(),
                ));
            }
        };
        let stepped = completed.map(|bin| (bin.time_s, step(self.estimator, &bin)));
        let corrected_rad = self
            .estimator
            .compensate(sample)
            .ok()
            .map(|a| [a.heading_rad, a.roll_rad, a.pitch_rad]);
        let cost_ticks = self.cost.ticks_since(start);
        let bin = match stepped {
            None => BinOutcome::Open,
            Some((_, Ok(output))) => {
                self.maybe_checkpoint(output.time_s);
                BinOutcome::Step(StepReply::new(&output, cost_ticks, self.counters()))
            }
            Some((time_s, Err(error))) => BinOutcome::Rejected(RejectedReply::new(
                time_s,
                &error,
                cost_ticks,
                self.counters(),
            )),
        };
        Response::Nav(NavReply {
            time_s: sample.time_s,
            corrected_rad,
            bin,
            cost_ticks,
        })
    }

    fn counters(&self) -> Counters {
        // Rejected samples: the estimator's and the binner's, each reason summed.
        let mut rejected_samples = self.estimator.rejected().0;
        for (n, nav) in rejected_samples.iter_mut().zip(self.nav_rejected) {
            *n = n.saturating_add(nav);
        }
        Counters {
            bad_frames: self.bad_frames.bad_frames,
            rejected_samples,
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
            checkpoint_time_s: self.persistence.as_ref().and_then(|p| p.store.time_s()),
            checkpoints_saved: self.persistence.as_ref().map_or(0, |p| p.store.saved()),
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
    estimator.step_default_capacity(sample)
}
