//! The C API as a C program uses it, called through its `extern "C"` functions:
//! - a run through `rins_estimator_step` equals the core's `Estimator::step` bit for bit and finds
//!   known installation errors;
//! - bad memory, bad configurations, null and foreign handles are refused and nothing is written;
//! - a rejected sample says why, carries the held estimate and leaves the estimator untouched;
//! - a checkpoint restored into another estimator reports the same estimate at once, refills its
//!   window and converges with the uninterrupted run; a damaged image is refused and changes
//!   nothing;
//! - the header's memory constants hold.

use estimator_core::synthetic::oscillation;
use estimator_core::units::{arcsec_to_rad, rad_to_arcsec, EARTH_RATE_RAD_PER_S, RAD_PER_DEG};
use estimator_core::{Config, Estimator, Sample};
use estimator_ffi::*;
use std::f64::consts::TAU;
use std::mem::MaybeUninit;
use std::ptr::{null, null_mut};

const X_ARCSEC: [f64; 4] = [200.0, -150.0, 300.0, -250.0];

/// Memory for an estimator, aligned as the header asks.
struct Block(Vec<u64>);

impl Block {
    fn new(fill: u8) -> Block {
        Block(vec![u64::from_ne_bytes([fill; 8]); RINS_ESTIMATOR_SIZE / 8])
    }
    fn ptr(&mut self) -> *mut std::ffi::c_void {
        self.0.as_mut_ptr().cast()
    }
}

fn defaults() -> RinsConfig {
    let mut c = MaybeUninit::uninit();
    // SAFETY: a writable config.
    assert_eq!(
        unsafe { rins_config_default(c.as_mut_ptr()) },
        RinsError::Ok
    );
    // SAFETY: written above.
    unsafe { c.assume_init() }
}

fn init(block: &mut Block, config: &RinsConfig) -> *mut RinsEstimator {
    let mut handle = null_mut();
    // SAFETY: a block of RINS_ESTIMATOR_SIZE bytes aligned to 8, a readable config, a writable handle.
    assert_eq!(
        unsafe { rins_estimator_init(block.ptr(), RINS_ESTIMATOR_SIZE, config, &mut handle) },
        RinsError::Ok
    );
    assert_eq!(handle.cast(), block.ptr());
    handle
}

/// The log row at `t_s` of a ship swaying 3 deg (8 s) in roll and 1 deg (11 s) in pitch at 30 deg
/// latitude, on a one-way rotation of 480 s at 1 Hz, with eq (2)'s oscillation of [`X_ARCSEC`].
fn row(t_s: f64) -> RinsSample {
    let rotation_deg = 360.0 * t_s / 480.0;
    let platform_deg = (EARTH_RATE_RAD_PER_S * t_s) / RAD_PER_DEG;
    let latitude_deg = 30.0;
    let d = oscillation(
        &X_ARCSEC.map(arcsec_to_rad),
        rotation_deg * RAD_PER_DEG,
        platform_deg * RAD_PER_DEG,
        latitude_deg * RAD_PER_DEG,
    );
    RinsSample {
        time_s: t_s,
        rotation_deg,
        platform_deg,
        latitude_deg,
        heading_deg: 45.0 + d[0] / RAD_PER_DEG,
        roll_deg: 3.0 * (TAU * t_s / 8.0).sin() + d[1] / RAD_PER_DEG,
        pitch_deg: (TAU * t_s / 11.0).sin() + d[2] / RAD_PER_DEG,
    }
}

fn step(handle: *mut RinsEstimator, sample: &RinsSample) -> (RinsError, RinsOutput) {
    let mut out = MaybeUninit::<RinsOutput>::uninit();
    // SAFETY: an initialised handle, a readable sample, a writable output.
    let e = unsafe { rins_estimator_step(handle, sample, out.as_mut_ptr()) };
    assert!(
        e == RinsError::Ok || e == RinsError::SampleRejected,
        "{e:?}"
    );
    // SAFETY: both results write the output.
    (e, unsafe { out.assume_init() })
}

fn checkpoint(handle: *const RinsEstimator) -> Vec<u8> {
    let mut image = vec![0u8; RINS_CHECKPOINT_LEN];
    let mut written = 0;
    // SAFETY: an initialised handle, RINS_CHECKPOINT_LEN writable bytes, a writable size.
    assert_eq!(
        unsafe { rins_estimator_checkpoint(handle, image.as_mut_ptr(), image.len(), &mut written) },
        RinsError::Ok
    );
    assert_eq!(written, RINS_CHECKPOINT_LEN);
    image
}

fn same_bits(a: &RinsOutput, b: &RinsOutput) -> bool {
    let f = |o: &RinsOutput| {
        let mut v: Vec<u32> = o
            .estimate
            .x_rad
            .iter()
            .chain(&o.estimate.sigma_rad)
            .map(|x| x.to_bits())
            .collect();
        v.extend(
            [
                o.heading_corrected_rad,
                o.roll_corrected_rad,
                o.pitch_corrected_rad,
            ]
            .map(f32::to_bits),
        );
        (
            o.time_s.to_bits(),
            o.status,
            o.rejected_field,
            o.has_estimate,
            v,
        )
    };
    f(a) == f(b)
}

#[test]
fn steps_equal_the_cores_bit_for_bit_and_find_the_errors() {
    let mut block = Block::new(0xA5);
    let handle = init(&mut block, &defaults());
    let mut core: Estimator = Estimator::new(Config::default()).unwrap();
    let mut last = None;
    for k in 0..4000 {
        let sample = row(f64::from(k));
        let (e, out) = step(handle, &sample);
        assert_eq!(e, RinsError::Ok);
        let expected = core
            .step(&Sample::from_degrees(
                sample.time_s,
                sample.rotation_deg,
                sample.platform_deg,
                sample.latitude_deg,
                sample.heading_deg,
                sample.roll_deg,
                sample.pitch_deg,
            ))
            .unwrap();
        assert!(
            same_bits(&out, &RinsOutput::accepted(&expected)),
            "{k}: {out:?} != {expected:?}"
        );
        last = Some(out);
    }
    let last = last.unwrap();
    assert_eq!(last.status, RinsStatus::Converged);
    for (i, (x_rad, truth_arcsec)) in last.estimate.x_rad.iter().zip(X_ARCSEC).enumerate() {
        let off_arcsec = rad_to_arcsec(f64::from(*x_rad)) - truth_arcsec;
        assert!(
            off_arcsec.abs() < 1.0,
            "x{}: off by {off_arcsec:.3} arcsec",
            i + 1
        );
    }
    let mut estimate = RinsEstimate::default();
    // SAFETY: an initialised handle, a writable estimate.
    assert_eq!(
        unsafe { rins_estimator_estimate(handle, &mut estimate) },
        RinsError::Ok
    );
    assert_eq!(estimate, last.estimate);
    let mut counters = RinsCounters::default();
    // SAFETY: as above.
    assert_eq!(
        unsafe { rins_estimator_counters(handle, &mut counters) },
        RinsError::Ok
    );
    assert_eq!(
        counters,
        RinsCounters {
            accepted: 4000,
            ..RinsCounters::default()
        }
    );
}

#[test]
fn init_refuses_bad_memory_and_configurations_and_writes_nothing() {
    let config = defaults();
    let mut block = Block::new(0x5A);
    let untouched = block.0.clone();
    let sentinel = 0x1234usize as *mut RinsEstimator;
    let mut handle = sentinel;
    let size = rins_estimator_size();
    assert!(size <= RINS_ESTIMATOR_SIZE);
    let mut bad_method = config;
    bad_method.method = 7;
    let mut bad_sigma = config;
    bad_sigma.converged_sigma_rad = f32::NAN;
    let mut paper = config;
    paper.method = RinsMethod::Paper as u32;
    let base = block.ptr();
    // SAFETY: every call either refuses its arguments or is given valid ones.
    let results = unsafe {
        [
            (
                rins_estimator_init(null_mut(), size, &config, &mut handle),
                RinsError::NullPointer,
            ),
            (
                rins_estimator_init(base, size, null(), &mut handle),
                RinsError::NullPointer,
            ),
            (
                rins_estimator_init(base, size, &config, null_mut()),
                RinsError::NullPointer,
            ),
            (
                rins_estimator_init(base.cast::<u8>().add(4).cast(), size, &config, &mut handle),
                RinsError::Misaligned,
            ),
            (
                rins_estimator_init(base, size - 1, &config, &mut handle),
                RinsError::BufferTooSmall,
            ),
            (
                rins_estimator_init(base, size, &bad_method, &mut handle),
                RinsError::InvalidConfig,
            ),
            (
                rins_estimator_init(base, size, &bad_sigma, &mut handle),
                RinsError::InvalidConfig,
            ),
        ]
    };
    for (i, (got, want)) in results.into_iter().enumerate() {
        assert_eq!(got, want, "case {i}");
    }
    assert_eq!(handle, sentinel);
    assert!(block.0 == untouched, "a refused init wrote into the memory");
    // The paper's method is not in the library's default build (as in the firmware); with the
    // `paper-method` feature of the core enabled in this build (the workspace's host-sim turns it
    // on) it is accepted.
    // SAFETY: valid arguments.
    let paper_result = unsafe { rins_estimator_init(base, size, &paper, &mut handle) };
    let paper_built = Config::with_method(estimator_core::Method::Paper)
        .check(estimator_core::estimator::DEFAULT_CAPACITY)
        .is_ok();
    let expected = if paper_built {
        RinsError::Ok
    } else {
        RinsError::InvalidConfig
    };
    assert_eq!(paper_result, expected);
}

#[test]
fn foreign_and_null_handles_are_refused() {
    let mut zeroed = Block::new(0);
    let handle = zeroed.ptr().cast::<RinsEstimator>();
    let sample = row(0.0);
    let mut out = MaybeUninit::<RinsOutput>::uninit();
    let mut estimate = RinsEstimate::default();
    let mut image = vec![0u8; RINS_CHECKPOINT_LEN];
    let mut written = 0;
    // SAFETY: every call refuses its handle before it reads or writes anything else.
    unsafe {
        assert_eq!(
            rins_estimator_step(handle, &sample, out.as_mut_ptr()),
            RinsError::NotInitialised
        );
        assert_eq!(
            rins_estimator_step(null_mut(), &sample, out.as_mut_ptr()),
            RinsError::NullPointer
        );
        assert_eq!(
            rins_estimator_step(handle.cast::<u8>().add(1).cast(), &sample, out.as_mut_ptr()),
            RinsError::Misaligned
        );
        assert_eq!(
            rins_estimator_estimate(handle, &mut estimate),
            RinsError::NotInitialised
        );
        assert_eq!(rins_estimator_reset(handle), RinsError::NotInitialised);
        assert_eq!(
            rins_estimator_checkpoint(handle, image.as_mut_ptr(), image.len(), &mut written),
            RinsError::NotInitialised
        );
        assert_eq!(
            rins_estimator_restore(handle, image.as_ptr(), image.len()),
            RinsError::NotInitialised
        );
    }
    assert!(zeroed.0.iter().all(|w| *w == 0));
    // A set-up handle with a null sample or output: refused, nothing stepped.
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    let before = checkpoint(handle);
    // SAFETY: nulls are refused.
    unsafe {
        assert_eq!(
            rins_estimator_step(handle, null(), out.as_mut_ptr()),
            RinsError::NullPointer
        );
        assert_eq!(
            rins_estimator_step(handle, &sample, null_mut()),
            RinsError::NullPointer
        );
    }
    assert!(checkpoint(handle) == before);
}

#[test]
fn a_rejected_sample_says_why_and_changes_nothing() {
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    for k in 0..1500 {
        step(handle, &row(f64::from(k)));
    }
    let before = checkpoint(handle);
    let mut held = RinsEstimate::default();
    // SAFETY: an initialised handle, a writable estimate.
    assert_eq!(
        unsafe { rins_estimator_estimate(handle, &mut held) },
        RinsError::Ok
    );
    let cases = [
        (
            RinsSample {
                roll_deg: f64::NAN,
                ..row(1500.0)
            },
            RinsStatus::RejectedNonFinite,
            RinsField::Roll,
        ),
        (
            RinsSample {
                pitch_deg: 91.0,
                ..row(1500.0)
            },
            RinsStatus::RejectedAngleOutOfRange,
            RinsField::Pitch,
        ),
        (
            RinsSample {
                latitude_deg: 90.0,
                ..row(1500.0)
            },
            RinsStatus::RejectedLatitudeOutOfRange,
            RinsField::None,
        ),
        (
            row(1499.0),
            RinsStatus::RejectedTimeNotIncreasing,
            RinsField::None,
        ),
        (
            row(1499.4),
            RinsStatus::RejectedIrregularTimeStep,
            RinsField::None,
        ),
    ];
    for (sample, status, field) in cases {
        let (e, out) = step(handle, &sample);
        assert_eq!(
            (e, out.status, out.rejected_field),
            (RinsError::SampleRejected, status, field)
        );
        assert_eq!(out.time_s.to_bits(), sample.time_s.to_bits());
        assert!(out.has_estimate && out.estimate == held);
        assert!(
            out.heading_corrected_rad.is_nan()
                && out.roll_corrected_rad.is_nan()
                && out.pitch_corrected_rad.is_nan()
        );
    }
    // The image now differs in the rejection counters only: an estimator restored from the image
    // taken before the rejections gives the same output for the next sample.
    // A twin that never saw the bad samples gives the same output for the next one, bit for bit.
    let mut twin_block = Block::new(0);
    let twin = init(&mut twin_block, &defaults());
    for k in 0..1500 {
        step(twin, &row(f64::from(k)));
    }
    assert!(checkpoint(twin) == before);
    let (_, a) = step(handle, &row(1500.0));
    let (_, b) = step(twin, &row(1500.0));
    assert!(same_bits(&a, &b));
    let mut counters = RinsCounters::default();
    // SAFETY: an initialised handle, writable counters.
    assert_eq!(
        unsafe { rins_estimator_counters(handle, &mut counters) },
        RinsError::Ok
    );
    assert_eq!((counters.accepted, counters.rejected), (1501, 5));
    assert_eq!(counters.rejected_by_reason.iter().sum::<u32>(), 5);
}

#[test]
fn a_checkpoint_restored_elsewhere_keeps_the_estimate_and_converges_again() {
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    for k in 0..1500 {
        step(handle, &row(f64::from(k)));
    }
    let image = checkpoint(handle);
    let mut at_cut = RinsEstimate::default();
    // SAFETY: an initialised handle, a writable estimate.
    assert_eq!(
        unsafe { rins_estimator_estimate(handle, &mut at_cut) },
        RinsError::Ok
    );
    // Too small a buffer: refused, left as it was.
    let mut small = vec![0x77u8; RINS_CHECKPOINT_LEN - 1];
    let mut written = 0;
    // SAFETY: an initialised handle, `small.len()` writable bytes, a writable size.
    let e =
        unsafe { rins_estimator_checkpoint(handle, small.as_mut_ptr(), small.len(), &mut written) };
    assert_eq!((e, written), (RinsError::BufferTooSmall, 0));
    assert!(small.iter().all(|b| *b == 0x77));
    // Restored into an estimator made with another configuration, which the image replaces.
    let mut other = defaults();
    other.rotation_period_s = 720.0;
    let mut restored_block = Block::new(0xFF);
    let restored = init(&mut restored_block, &other);
    let fresh = checkpoint(restored);
    let mut damaged = image.clone();
    damaged[100] ^= 0x10;
    // SAFETY: an initialised handle and readable images.
    unsafe {
        assert_eq!(
            rins_estimator_restore(restored, damaged.as_ptr(), damaged.len()),
            RinsError::CheckpointCorrupt
        );
        assert_eq!(
            rins_estimator_restore(restored, image.as_ptr(), 100),
            RinsError::BufferTooSmall
        );
        assert_eq!(
            rins_estimator_restore(restored, null(), 100),
            RinsError::NullPointer
        );
    }
    assert!(
        checkpoint(restored) == fresh,
        "a refused restore changed the estimator"
    );
    // SAFETY: as above.
    assert_eq!(
        unsafe { rins_estimator_restore(restored, image.as_ptr(), image.len()) },
        RinsError::Ok
    );
    assert!(
        checkpoint(restored) == image,
        "the restored estimator's image is the one it came from"
    );
    // The estimate is reported from the first sample on while the window refills; the filter
    // updates again after one period and ends where the uninterrupted run ends, near the truth.
    let (e, first) = step(restored, &row(1500.0));
    assert_eq!(
        (e, first.status, first.has_estimate, first.estimate),
        (RinsError::Ok, RinsStatus::Holding, true, at_cut)
    );
    let (mut a, mut b) = (first, first);
    for k in 1501..4000 {
        a = step(handle, &row(f64::from(k))).1;
        b = step(restored, &row(f64::from(k))).1;
        assert!(b.has_estimate, "{k}");
    }
    assert_eq!(
        (a.status, b.status),
        (RinsStatus::Converged, RinsStatus::Converged)
    );
    for (i, truth_arcsec) in X_ARCSEC.iter().enumerate() {
        let (ua, ra) = (
            rad_to_arcsec(f64::from(a.estimate.x_rad[i])),
            rad_to_arcsec(f64::from(b.estimate.x_rad[i])),
        );
        assert!(
            (ra - truth_arcsec).abs() < 1.0 && (ra - ua).abs() < 0.5,
            "x{}: restored {ra:.3}, uninterrupted {ua:.3}",
            i + 1
        );
    }
}

#[test]
fn reset_forgets_what_was_learnt_and_keeps_the_rejections() {
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    for k in 0..1500 {
        step(handle, &row(f64::from(k)));
    }
    step(
        handle,
        &RinsSample {
            roll_deg: f64::INFINITY,
            ..row(1500.0)
        },
    );
    // SAFETY: an initialised handle.
    assert_eq!(unsafe { rins_estimator_reset(handle) }, RinsError::Ok);
    let mut estimate = RinsEstimate::default();
    let mut counters = RinsCounters::default();
    // SAFETY: an initialised handle, writable outputs.
    unsafe {
        assert_eq!(
            rins_estimator_estimate(handle, &mut estimate),
            RinsError::NoEstimate
        );
        assert_eq!(
            rins_estimator_counters(handle, &mut counters),
            RinsError::Ok
        );
    }
    assert_eq!(estimate, RinsEstimate::default());
    assert_eq!(
        counters,
        RinsCounters {
            rejected: 1,
            // The one rejection, a non-finite field, by its reason (index = code - 128).
            rejected_by_reason: [1, 0, 0, 0, 0],
            ..RinsCounters::default()
        }
    );
    // An earlier time than before the reset is a new start, not a step back.
    let (e, out) = step(handle, &row(0.0));
    assert_eq!(
        (e, out.status),
        (RinsError::Ok, RinsStatus::DetectingPattern)
    );
}

#[test]
fn the_headers_memory_constants_hold() {
    assert!(rins_estimator_size() <= RINS_ESTIMATOR_SIZE);
    assert_eq!(RINS_ESTIMATOR_ALIGN, 8);
    assert_eq!(RINS_CHECKPOINT_LEN, <Estimator>::CHECKPOINT_LEN);
    // The size in the header is the 64-bit estimator's rounded up to 512 bytes (32-bit targets
    // need less): when the estimator grows or shrinks, this says what to write there.
    if cfg!(target_pointer_width = "64") {
        assert_eq!(
            RINS_ESTIMATOR_SIZE,
            rins_estimator_size().next_multiple_of(512),
            "set RINS_ESTIMATOR_SIZE in estimator-ffi/src/estimator.rs"
        );
    }
}

fn compensate(handle: *const RinsEstimator, sample: &RinsSample) -> (RinsError, RinsAttitude) {
    let mut out = RinsAttitude {
        heading_rad: f32::MAX,
        roll_rad: f32::MAX,
        pitch_rad: f32::MAX,
    };
    // SAFETY: an initialised handle, a readable sample, a writable attitude.
    let e = unsafe { rins_estimator_compensate(handle, sample, &mut out) };
    (e, out)
}

/// `rins_estimator_compensate` between steps: nothing before the first estimate; then, for a
/// sample just stepped, the step's own corrected attitude bit for bit; at 100 Hz between the
/// steps, the sway alone is left (eq (2)'s oscillation of hundreds of arcsec removed to within the
/// estimate's error); a bad sample, a null pointer or a foreign handle is refused and nothing is
/// written; the estimator is never changed.
#[test]
fn compensate_applies_the_estimate_between_steps_and_changes_nothing() {
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    let no_change = RinsAttitude {
        heading_rad: f32::MAX,
        roll_rad: f32::MAX,
        pitch_rad: f32::MAX,
    };
    assert_eq!(
        compensate(handle, &row(0.0)),
        (RinsError::NoEstimate, no_change)
    );
    let mut matched = 0;
    for k in 0..2000 {
        let sample = row(k as f64);
        let (_, out) = step(handle, &sample);
        let before = block.0.clone();
        let (e, a) = compensate(handle, &sample);
        if out.has_estimate {
            assert_eq!(e, RinsError::Ok);
            assert_eq!(
                [a.heading_rad, a.roll_rad, a.pitch_rad].map(f32::to_bits),
                [
                    out.heading_corrected_rad,
                    out.roll_corrected_rad,
                    out.pitch_corrected_rad
                ]
                .map(f32::to_bits),
                "at {k} s"
            );
            matched += 1;
        } else {
            assert_eq!((e, a), (RinsError::NoEstimate, no_change));
        }
        assert!(
            block.0 == before,
            "compensate changed the estimator at {k} s"
        );
    }
    assert!(matched > 1000, "{matched}");
    // 100 Hz between two steps: the sway is what remains.
    for i in 0..100 {
        let t = 1999.0 + 0.01 * i as f64;
        let (e, a) = compensate(handle, &row(t));
        assert_eq!(e, RinsError::Ok);
        let roll_sway_rad = 3.0 * (TAU * t / 8.0).sin() * RAD_PER_DEG;
        let pitch_sway_rad = (TAU * t / 11.0).sin() * RAD_PER_DEG;
        // Within 5 arcsec (the estimate at 2,000 s is within 1): the oscillation is hundreds.
        assert!(
            rad_to_arcsec(a.roll_rad as f64 - roll_sway_rad).abs() < 5.0,
            "{t}"
        );
        assert!(
            rad_to_arcsec(a.pitch_rad as f64 - pitch_sway_rad).abs() < 5.0,
            "{t}"
        );
    }
    let mut bad = row(2000.0);
    bad.roll_deg = 95.0;
    assert_eq!(
        compensate(handle, &bad),
        (RinsError::SampleRejected, no_change)
    );
    let mut out = no_change;
    // SAFETY: null pointers are refused before anything is read or written.
    unsafe {
        assert_eq!(
            rins_estimator_compensate(null(), &row(1.0), &mut out),
            RinsError::NullPointer
        );
        assert_eq!(
            rins_estimator_compensate(handle, null(), &mut out),
            RinsError::NullPointer
        );
        assert_eq!(
            rins_estimator_compensate(handle, &row(1.0), null_mut()),
            RinsError::NullPointer
        );
    }
    let foreign = Block::new(0x5a);
    // SAFETY: readable memory of the estimator's size that init never marked.
    let e = unsafe { rins_estimator_compensate(foreign.0.as_ptr().cast(), &row(1.0), &mut out) };
    assert_eq!((e, out), (RinsError::NotInitialised, no_change));
}

/// The learned-errors record through the C API: nothing before an estimate; after 2,000 s a
/// record that starts a fresh estimator (as a later build would after refusing the checkpoint)
/// with the same estimate at its first sample; a damaged record changes nothing.
#[test]
fn a_learned_record_starts_another_estimator_from_the_estimate() {
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    let mut record = vec![0u8; RINS_LEARNED_LEN];
    let mut written = 0;
    // SAFETY: an initialised handle, RINS_LEARNED_LEN writable bytes, a writable size.
    let e =
        unsafe { rins_estimator_learned(handle, record.as_mut_ptr(), record.len(), &mut written) };
    assert_eq!((e, written), (RinsError::NoEstimate, 0));
    for k in 0..2000 {
        step(handle, &row(k as f64));
    }
    // SAFETY: as above; then one byte short.
    unsafe {
        assert_eq!(
            rins_estimator_learned(
                handle,
                record.as_mut_ptr(),
                RINS_LEARNED_LEN - 1,
                &mut written
            ),
            RinsError::BufferTooSmall
        );
        assert_eq!(
            rins_estimator_learned(handle, record.as_mut_ptr(), record.len(), &mut written),
            RinsError::Ok
        );
    }
    assert_eq!(written, RINS_LEARNED_LEN);
    let mut estimate = RinsEstimate::default();
    // SAFETY: an initialised handle, a writable estimate.
    assert_eq!(
        unsafe { rins_estimator_estimate(handle, &mut estimate) },
        RinsError::Ok
    );
    let mut other_block = Block::new(0);
    let other = init(&mut other_block, &defaults());
    let mut damaged = record.clone();
    damaged[20] ^= 4;
    let before = other_block.0.clone();
    // SAFETY: an initialised handle, readable bytes.
    let e = unsafe { rins_estimator_start_from_learned(other, damaged.as_ptr(), damaged.len()) };
    assert_eq!(e, RinsError::CheckpointCorrupt);
    assert!(
        other_block.0 == before,
        "a damaged record changed the estimator"
    );
    // SAFETY: as above.
    let e = unsafe { rins_estimator_start_from_learned(other, record.as_ptr(), record.len()) };
    assert_eq!(e, RinsError::Ok);
    let (_, out) = step(other, &row(2000.0));
    assert!(out.has_estimate);
    assert_eq!(out.estimate.x_rad, estimate.x_rad);
    for i in 0..4 {
        let off = rad_to_arcsec(f64::from(out.estimate.x_rad[i])) - X_ARCSEC[i];
        assert!(off.abs() < 1.0, "x{} off by {off} arcsec", i + 1);
        assert!(rad_to_arcsec(f64::from(out.estimate.sigma_rad[i])) >= 1.0 - 1e-4);
    }
}

/// Attitude at 200 Hz through `rins_binner_push` into the estimator: one averaged sample a
/// second, stepped, gives the estimates of the same samples binned by the core's `Binner` and
/// stepped as `host-sim estimate --bin-interval-s 1` steps them (bit for bit), and finds the
/// errors; a bad sample is refused and changes nothing; a binner not set up is refused.
#[test]
fn a_binner_feeds_200_hz_attitude_into_the_grid() {
    let mut binner = RinsBinner { opaque: [0; 32] };
    let (mut binned, mut ready) = (RinsSample::default(), false);
    // SAFETY: a writable binner and outputs; a readable sample.
    unsafe {
        assert_eq!(
            rins_binner_push(&mut binner, &row(0.0), &mut binned, &mut ready),
            RinsError::NotInitialised
        );
        assert_eq!(
            rins_binner_init(&mut binner, 0.01),
            RinsError::InvalidConfig
        );
        assert_eq!(rins_binner_init(&mut binner, 1.0), RinsError::Ok);
    }
    let mut block = Block::new(0);
    let handle = init(&mut block, &defaults());
    let mut core_binner = estimator_core::binning::Binner::new(1.0).unwrap();
    let mut core_est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut steps = 0;
    for k in 0..2000 * 200 {
        let t = k as f64 * 0.005;
        let sample = row(t);
        // SAFETY: as above.
        let e = unsafe { rins_binner_push(&mut binner, &sample, &mut binned, &mut ready) };
        assert_eq!(e, RinsError::Ok);
        let core_done = core_binner.push(&Sample::from_degrees(
            sample.time_s,
            sample.rotation_deg,
            sample.platform_deg,
            sample.latitude_deg,
            sample.heading_deg,
            sample.roll_deg,
            sample.pitch_deg,
        ));
        let core_done = core_done.unwrap();
        assert_eq!(ready, core_done.is_some(), "at {t} s");
        if let Some(s) = core_done {
            let [t, rotation, platform, latitude, heading, roll, pitch] = s.to_degrees();
            let expected = core_est
                .step(&Sample::from_degrees(
                    t, rotation, platform, latitude, heading, roll, pitch,
                ))
                .unwrap();
            let (_, out) = step(handle, &binned);
            assert_eq!(out.time_s, expected.time_s);
            assert_eq!(
                out.estimate.x_rad.map(f32::to_bits),
                expected
                    .estimate
                    .map_or([0.0; 4], |e| e.x_rad)
                    .map(f32::to_bits)
            );
            steps += 1;
        }
        if k == 1000 {
            // A repeated time: refused, nothing changes.
            let before = binner.opaque;
            // SAFETY: as above.
            let e = unsafe { rins_binner_push(&mut binner, &sample, &mut binned, &mut ready) };
            assert_eq!((e, ready), (RinsError::SampleRejected, false));
            assert_eq!(binner.opaque, before);
        }
    }
    assert_eq!(steps, 1999, "one sample a second, the last bin still open");
    let mut estimate = RinsEstimate::default();
    // SAFETY: an initialised handle, a writable estimate.
    assert_eq!(
        unsafe { rins_estimator_estimate(handle, &mut estimate) },
        RinsError::Ok
    );
    for i in 0..4 {
        let off = rad_to_arcsec(f64::from(estimate.x_rad[i])) - X_ARCSEC[i];
        assert!(off.abs() < 1.0, "x{} off by {off} arcsec", i + 1);
    }
    // SAFETY: as above: the last bin at the end.
    assert_eq!(
        unsafe { rins_binner_finish(&mut binner, &mut binned, &mut ready) },
        RinsError::Ok
    );
    assert!(ready);
    assert_eq!(binned.time_s, 1999.5);
}
