//! Checkpoint and restore, end to end through the public API. An image keeps what a restart can
//! use (the filter, what was learned, counters); the window refills after it.
//!
//! - `restart_*`: run a log, checkpoint after a random sample, restore into a fresh estimator
//!   built with a *different* configuration (which the image replaces), continue: the restored
//!   estimator reports the very estimate it was checkpointed with from its first output on,
//!   holds while its window refills, rejects exactly the rows the uninterrupted run rejects and
//!   never loses its estimate. (How close it ends to the uninterrupted run depends on how much
//!   the filter still had to learn at the cut: measured on a realistic cut below.) The logs
//!   have everything a real one has (jittered stamps, lost rows in short runs that are filled and
//!   one long outage, rejected rows, a stopped rotation, a clock jump), at 1 Hz and 10 Hz, with
//!   any rotation scheme, pinned or learned interval and period, with and without the sway gate.
//! - `every_phase_is_cut_and_restored`: the same logs cut after *every* sample (the restored
//!   estimate, counters and image equal the running one's), and continued from the first cut of
//!   each phase: interval being learned, period being detected, features being learned, filled
//!   gaps waiting in the delay line, a bin being filled, a rotation fault, holding, estimating.
//! - `a_power_cut_with_lost_rows_costs_almost_nothing`: 20,000 s of a sea log, a cut, 200 s of
//!   rows lost, the rest: the end within 0.1 arcsec of the uncut run.
//! - every single-bit flip of an image is refused and changes nothing; garbage and truncations are
//!   refused; an image of the previous format version is refused with the version error.

use estimator_core::checkpoint::{crc32, CheckpointError, CHECKPOINT_LEN, HEADER_LEN, VERSION};
use estimator_core::synthetic::{Scheme, Signal};
use estimator_core::{
    Config, Estimator, Holdup, Method, Output, Real, Sample, SampleError, Status,
};
use proptest::prelude::*;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The ring of the short tests: a 180 s period at 1 Hz is binned by 3, 90 s at 10 Hz by 15.
const CAP: usize = 64;
/// Samples the gap filler waits for after a lost one (`estimator_core::gap_fill::NEIGHBOURS`).
const NEIGHBOURS: u64 = 5;

/// How a log is made.
#[derive(Clone, Copy, Debug)]
struct Plan {
    interval_s: f64,
    period_s: f64,
    scheme: Scheme,
    periods: f64,
    seed: u64,
}

/// A log and, for each row, its grid index (whole intervals since the start, before the clock jump).
struct Log {
    samples: Vec<Sample>,
    grid: Vec<u64>,
    /// Grid indices of rows lost in runs short enough to be filled.
    filled: Vec<u64>,
}

/// The `k`th number in [0, 1) of the ChaCha8 stream of `seed` (its `k`th 64-bit word pair:
/// random access, so a row's draw does not depend on which rows were asked before).
fn uniform(seed: u64, k: u64) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_word_pos(2 * u128::from(k));
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

fn log(plan: Plan) -> Log {
    let mut signal = Signal::new([200.0, -150.0, 300.0, -250.0], 40.0);
    signal.scheme = plan.scheme;
    signal.rotation_period_s = plan.period_s;
    signal.noise_arcsec = 5.0;
    let dt = plan.interval_s;
    let n = (plan.periods * plan.period_s / dt) as u64;
    let per_period = (plan.period_s / dt) as u64;
    // Events at fixed fractions of the run (after the pattern is learned, but not all of them).
    let outage = n * 45 / 100..n * 45 / 100 + 20;
    let stop = n * 70 / 100..n * 70 / 100 + per_period / 3;
    let jump_at = n * 85 / 100;
    let mut out = Log {
        samples: Vec::new(),
        grid: Vec::new(),
        filled: Vec::new(),
    };
    let mut lost_run = 0u64;
    let mut stopped_rho = None;
    for k in 0..n {
        // Short runs of 1-3 lost rows from the third period on, about 2 % of them.
        let u = uniform(plan.seed, k);
        if k > 2 * per_period && (lost_run > 0 || u < 0.007) && lost_run < 1 + (plan.seed % 3) {
            lost_run += 1;
            out.filled.push(k);
            continue;
        }
        lost_run = 0;
        if outage.contains(&k) {
            continue;
        }
        let t = k as f64 * dt;
        let mut s = signal.sample(t);
        s.time_s = 1.7e9 + t + (uniform(plan.seed ^ 1, k) - 0.5) * 0.1 * dt;
        if k >= jump_at {
            s.time_s += 2.5 * dt;
        }
        if stop.contains(&k) {
            s.rotation_rad = *stopped_rho.get_or_insert(s.rotation_rad);
        }
        out.samples.push(s);
        out.grid.push(k);
        if k % 331 == 17 {
            let mut bad = s;
            bad.attitude.roll_rad = Real::NAN; // rejected, counted
            out.samples.push(bad);
            out.grid.push(k);
        }
        if k % 509 == 100 {
            out.samples.push(s); // the same stamp again: rejected
            out.grid.push(k);
        }
    }
    out
}

/// Configurations by number: method, pinned or learned interval and period, sway gate.
fn config(plan: &Plan, i: u8) -> Config {
    Config {
        method: Method::try_from(i % 3).unwrap(),
        sample_interval_s: (i & 4 != 0).then_some(plan.interval_s),
        rotation_period_s: (i & 8 != 0).then_some(plan.period_s),
        sway_gate_rad: if i & 16 != 0 {
            1f64.to_radians() as Real
        } else {
            0.0
        },
        ..Config::default()
    }
}

/// A configuration unlike any of the above, for the estimator an image is restored into.
fn other(config: &Config) -> Config {
    Config {
        method: if config.method == Method::Paper {
            Method::Windowed
        } else {
            Method::Paper
        },
        rotation_period_s: Some(300.0),
        sample_interval_s: Some(0.5),
        max_filled_gap_samples: 1,
        ..Config::default()
    }
}

fn image<const C: usize>(est: &Estimator<C>) -> Vec<u8> {
    let mut buf = vec![0u8; Estimator::<C>::CHECKPOINT_LEN];
    assert_eq!(est.checkpoint(&mut buf), Ok(buf.len()));
    buf
}

/// Restores `buf` into a fresh estimator of another configuration.
fn restored<const C: usize>(buf: &[u8], config: &Config) -> Estimator<C> {
    let mut resumed = Estimator::<C>::new(other(config)).unwrap();
    resumed.restore(buf).unwrap();
    resumed
}

/// The outputs of an uninterrupted run.
fn reference<const C: usize>(
    config: Config,
    samples: &[Sample],
) -> (Vec<Result<Output, SampleError>>, Estimator<C>) {
    let mut est = Estimator::<C>::new(config).unwrap();
    let out = samples.iter().map(|s| est.step(s)).collect();
    (out, est)
}

/// Cut after sample `cut`, restore into a fresh estimator of another configuration, continue (see
/// the module doc for what must hold).
fn check_cut<const C: usize>(
    config: Config,
    samples: &[Sample],
    cut: usize,
    reference: &(Vec<Result<Output, SampleError>>, Estimator<C>),
) {
    let mut first = Estimator::<C>::new(config).unwrap();
    for s in &samples[..=cut] {
        first.step(s).ok();
    }
    let buf = image(&first);
    let at_cut = first.estimate();
    let mut resumed = restored::<C>(&buf, &config);
    assert_eq!(resumed.config(), &config);
    assert_eq!(resumed.estimate(), at_cut, "cut {cut}");
    assert_eq!(resumed.counters(), first.counters(), "cut {cut}");
    assert_eq!(
        image(&resumed),
        buf,
        "cut {cut}: the restored state writes another image"
    );
    drop(first);
    let mut had_estimate = at_cut.is_some();
    for (k, s) in samples.iter().enumerate().skip(cut + 1) {
        let out = resumed.step(s);
        match (&out, &reference.0[k]) {
            (Err(a), Err(b)) => assert_eq!(
                a.reason(),
                b.reason(),
                "cut {cut}: row {k} rejected for another reason"
            ),
            (Ok(o), Ok(_)) => {
                if k == cut + 1 && had_estimate {
                    // The first answer after the restart carries the checkpoint's estimate.
                    assert_eq!(o.estimate, at_cut, "cut {cut}: row {k}");
                    assert!(
                        !matches!(o.status, Status::Estimating | Status::Converged),
                        "cut {cut}: {:?} at once",
                        o.status
                    );
                }
                assert!(
                    !had_estimate || o.estimate.is_some(),
                    "cut {cut}: row {k} lost the estimate"
                );
                had_estimate |= o.estimate.is_some();
            }
            (a, b) => panic!("cut {cut}: row {k}: {a:?} where the uncut run gives {b:?}"),
        }
    }
}

fn plan(i: u8, seed: u64) -> Plan {
    let scheme = [
        Scheme::OneWay(1.0),
        Scheme::OneWay(-1.0),
        Scheme::Reciprocating,
        Scheme::FourPosition,
        Scheme::EightPosition,
    ][(seed % 5) as usize];
    match i % 2 {
        0 => Plan {
            interval_s: 1.0,
            period_s: 180.0,
            scheme,
            periods: 5.0,
            seed,
        },
        _ => Plan {
            interval_s: 0.1,
            period_s: 90.0,
            scheme,
            periods: 5.0,
            seed,
        },
    }
}

/// Cases per property: `n`, or `PROPTEST_CASES` from the environment for longer runs.
fn cases(n: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(n)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(48), ..ProptestConfig::default() })]

    /// 1 Hz with bins of 3 and 10 Hz with bins of 15, random scheme and configuration; one cut in
    /// four among the first samples, where the interval is learned.
    #[test]
    fn restart_short_period(
        rate in 0u8..2,
        c in 0u8..32,
        seed in any::<u64>(),
        early in any::<bool>(),
        at in 0.0f64..1.0,
    ) {
        let plan = plan(rate, seed);
        let log = log(plan);
        let config = config(&plan, c);
        let n = log.samples.len();
        let cut = if early { (at * 12.0) as usize } else { (at * (n - 1) as f64) as usize };
        let reference = reference::<CAP>(config, &log.samples);
        check_cut::<CAP>(config, &log.samples, cut, &reference);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(12), ..ProptestConfig::default() })]

    /// The default estimator (720 entries) and configuration, 1 Hz, 480 s period: five periods.
    #[test]
    fn restart_default_capacity(m in 0u8..3, seed in any::<u64>(), at in 0.0f64..1.0) {
        let plan = Plan { interval_s: 1.0, period_s: 480.0, scheme: Scheme::OneWay(1.0), periods: 5.0, seed };
        let log = log(plan);
        let config = Config::with_method(Method::try_from(m).unwrap());
        let cut = (at * (log.samples.len() - 1) as f64) as usize;
        let reference = reference::<720>(config, &log.samples);
        check_cut::<720>(config, &log.samples, cut, &reference);
    }
}

/// The phases a cut can land in, as the public API and the log show them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Phase {
    LearningInterval,
    DetectingPeriod,
    LearningFeatures,
    FilledGapPending,
    BinFilling,
    Fault,
    Holding,
    Estimating,
}

const PHASES: [Phase; 8] = [
    Phase::LearningInterval,
    Phase::DetectingPeriod,
    Phase::LearningFeatures,
    Phase::FilledGapPending,
    Phase::BinFilling,
    Phase::Fault,
    Phase::Holding,
    Phase::Estimating,
];

fn phases_of(
    est: &Estimator<CAP>,
    out: &Result<Output, SampleError>,
    log: &Log,
    row: usize,
) -> Vec<Phase> {
    let mut phases = Vec::new();
    let rotation = est.rotation();
    if est.sample_interval_s().is_none() {
        phases.push(Phase::LearningInterval);
    }
    if est.progress() == Some(Holdup::RotationPeriodNotDetected) {
        phases.push(Phase::DetectingPeriod);
    }
    if rotation.period_s.is_some() && rotation.kind.is_none() {
        phases.push(Phase::LearningFeatures);
    }
    // A lost row among the last NEIGHBOURS indices: filled once its neighbours have arrived.
    let k = log.grid[row];
    if est.sample_interval_s().is_some()
        && log.filled.iter().any(|g| *g < k && *g + NEIGHBOURS >= k)
    {
        phases.push(Phase::FilledGapPending);
    }
    // With bins, an entry is complete only every `samples_per_entry` samples: most cuts of a
    // filling or full window land in a bin being filled.
    if rotation.samples_per_entry > 1
        && matches!(est.progress(), None | Some(Holdup::WindowFilling { .. }))
    {
        phases.push(Phase::BinFilling);
    }
    match out.as_ref().map(|o| o.status) {
        Ok(Status::RotationFault(_)) => phases.push(Phase::Fault),
        Ok(Status::Holding) => phases.push(Phase::Holding),
        Ok(Status::Estimating | Status::Converged | Status::ModelMismatch) => {
            phases.push(Phase::Estimating)
        }
        _ => {}
    }
    phases
}

/// Cut after every sample: the restored estimate, counters and image equal the running one's.
/// Continue from the first cut of each phase, and from one in its middle.
#[test]
fn every_phase_is_cut_and_restored() {
    for (rate, seed, c) in [(0u8, 3u64, 0u8), (1, 8, 12), (0, 7, 1), (1, 4, 17)] {
        let plan = plan(rate, seed);
        let log = log(plan);
        let config = config(&plan, c);
        let reference = reference::<CAP>(config, &log.samples);
        let mut est = Estimator::<CAP>::new(config).unwrap();
        let mut cuts: Vec<Vec<usize>> = vec![Vec::new(); PHASES.len()];
        for (row, s) in log.samples.iter().enumerate() {
            let out = est.step(s);
            let buf = image(&est);
            let back = restored::<CAP>(&buf, &config);
            assert_eq!(
                back.estimate(),
                est.estimate(),
                "{plan:?} {config:?}: row {row}"
            );
            assert_eq!(
                back.counters(),
                est.counters(),
                "{plan:?} {config:?}: row {row}"
            );
            assert_eq!(image(&back), buf, "{plan:?}: row {row}");
            for phase in phases_of(&est, &out, &log, row) {
                cuts[phase as usize].push(row);
            }
        }
        for (phase, rows) in PHASES.iter().zip(&cuts) {
            // What a configuration pins is not learned; only the windowed method bins. The
            // methods with a window hold after a gap that restarts it; the traditional one has no
            // window to refill and goes on with the first sample the gap filler passes after the
            // gap.
            let expected = match phase {
                Phase::LearningInterval => config.sample_interval_s.is_none(),
                Phase::DetectingPeriod => config.rotation_period_s.is_none(),
                Phase::BinFilling => config.method == Method::Windowed,
                Phase::Holding => config.method != Method::Traditional,
                _ => true,
            };
            assert_eq!(
                !rows.is_empty(),
                expected,
                "{plan:?} {config:?}: {phase:?} at {} rows",
                rows.len()
            );
            if let (Some(first), Some(middle)) = (rows.first(), rows.get(rows.len() / 2)) {
                check_cut::<CAP>(config, &log.samples, *first, &reference);
                check_cut::<CAP>(config, &log.samples, *middle, &reference);
            }
        }
    }
}

/// A running windowed estimator and its image (built once: the flips below are cheap).
fn source() -> &'static (Estimator<CAP>, Vec<u8>) {
    static SOURCE: std::sync::OnceLock<(Estimator<CAP>, Vec<u8>)> = std::sync::OnceLock::new();
    SOURCE.get_or_init(|| {
        let plan = plan(0, 3);
        let log = log(plan);
        let mut est = Estimator::<CAP>::new(config(&plan, 0)).unwrap();
        // Past the first estimate (a bin window starts when the four-position pattern is known,
        // after the 32 stamps the grid is learned from) and before the rotation stops.
        for s in &log.samples[..log.samples.len() * 6 / 10] {
            est.step(s).ok();
        }
        assert!(est.estimate().is_some());
        let img = image(&est);
        (est, img)
    })
}

/// Every single-bit flip anywhere in the image is refused (CRC-32 detects every single-bit error;
/// a flip in the header fields checked first gives their error instead) and the estimator it was
/// to be restored into does not change.
#[test]
fn every_bit_flip_is_refused_and_changes_nothing() {
    let (est, good) = source();
    let mut target = est.clone();
    target.reset();
    let before = target.clone();
    let mut buf = good.clone();
    for byte in 0..buf.len() {
        for bit in 0..8 {
            buf[byte] ^= 1 << bit;
            let result = target.restore(&buf);
            assert!(result.is_err(), "flip at byte {byte} bit {bit} accepted");
            if byte >= HEADER_LEN {
                assert!(
                    matches!(result, Err(CheckpointError::CrcMismatch { .. })),
                    "{result:?}"
                );
            }
            buf[byte] ^= 1 << bit;
        }
    }
    assert!(target == before);
    target.restore(good).unwrap();
    assert_eq!(image(&target), *good);
    assert_eq!(target.estimate(), est.estimate());
}

/// Running estimators of the default capacity, one per method, and their images.
fn default_sources() -> &'static [(Estimator, Vec<u8>); 3] {
    static SOURCES: std::sync::OnceLock<[(Estimator, Vec<u8>); 3]> = std::sync::OnceLock::new();
    SOURCES.get_or_init(|| {
        let log = log(Plan {
            interval_s: 1.0,
            period_s: 480.0,
            scheme: Scheme::FourPosition,
            periods: 4.5,
            seed: 5,
        });
        std::array::from_fn(|m| {
            let mut est: Estimator =
                Estimator::new(Config::with_method(Method::try_from(m as u8).unwrap())).unwrap();
            for s in &log.samples {
                est.step(s).ok();
            }
            let img = image(&est);
            (est, img)
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(256), ..ProptestConfig::default() })]

    /// The same for images of the default estimator, at random bits.
    #[test]
    fn any_bit_flip_of_a_default_image_is_refused(byte in 0usize..CHECKPOINT_LEN, bit in 0u8..8, m in 0usize..3, t in 0usize..3) {
        let mut buf = default_sources()[m].1.clone();
        buf[byte] ^= 1 << bit;
        let mut target = default_sources()[t].0.clone();
        let result = target.restore(&buf);
        prop_assert!(result.is_err(), "flip at byte {byte} bit {bit} accepted");
        if byte >= HEADER_LEN {
            prop_assert!(matches!(result, Err(CheckpointError::CrcMismatch { .. })), "{result:?}");
        }
        prop_assert!(target == default_sources()[t].0);
    }

    /// Arbitrary bytes, and a valid image's truncations, never panic and are refused.
    #[test]
    fn garbage_and_truncations_are_refused(garbage in proptest::collection::vec(any::<u8>(), 0..24_000), cut in 0usize..CHECKPOINT_LEN) {
        let mut target = default_sources()[0].0.clone();
        prop_assert!(target.restore(&garbage).is_err());
        let mut valid = default_sources()[1].1.clone();
        valid.truncate(cut);
        prop_assert!(target.restore(&valid).is_err());
        prop_assert!(target == default_sources()[0].0);
    }
}

#[test]
fn an_image_of_the_previous_format_version_is_refused_as_such() {
    let (est, good) = &default_sources()[0];
    let mut target: Estimator = Estimator::new(Config::with_method(Method::Traditional)).unwrap();
    let before = target.clone();
    let mut old = good.clone();
    old[4..6].copy_from_slice(&8u16.to_le_bytes());
    let n = old.len();
    let crc = crc32(&old[..n - 4]);
    old[n - 4..].copy_from_slice(&crc.to_le_bytes());
    let err = target.restore(&old).unwrap_err();
    assert_eq!(
        err,
        CheckpointError::Version {
            found: 8,
            expected: 9
        }
    );
    assert_eq!(VERSION, 9);
    assert!(err.to_string().contains("older firmware"), "{err}");
    assert!(target == before);
    target.restore(good).unwrap();
    assert_eq!(target.estimate(), est.estimate());
}

#[test]
fn an_image_is_at_most_2_kib_and_a_longer_buffer_is_fine() {
    const { assert!(CHECKPOINT_LEN <= 2048) };
    let est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut big = vec![0xAAu8; CHECKPOINT_LEN + 100];
    assert_eq!(est.checkpoint(&mut big), Ok(CHECKPOINT_LEN));
    // A longer buffer restores (trailing bytes are ignored).
    let mut other: Estimator = Estimator::new(Config::with_method(Method::Traditional)).unwrap();
    other.restore(&big).unwrap();
    assert!(other == est);
}

#[test]
fn too_small_buffer_is_refused_and_left_alone() {
    let est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut small = vec![0x55u8; CHECKPOINT_LEN - 1];
    assert_eq!(
        est.checkpoint(&mut small),
        Err(CheckpointError::BufferTooSmall {
            needed: CHECKPOINT_LEN,
            available: CHECKPOINT_LEN - 1
        })
    );
    assert!(small.iter().all(|b| *b == 0x55));
}

#[test]
fn header_errors_are_typed() {
    let (est, good) = &default_sources()[0];
    let mut target: Estimator = Estimator::new(Config::with_method(Method::Paper)).unwrap();
    let before = target.clone();

    let mut b = good.clone();
    b[0] = b'X';
    assert_eq!(target.restore(&b), Err(CheckpointError::BadMagic));
    let mut b = good.clone();
    b[4..6].copy_from_slice(&(VERSION + 1).to_le_bytes());
    assert_eq!(
        target.restore(&b),
        Err(CheckpointError::Version {
            found: VERSION + 1,
            expected: VERSION
        })
    );
    let mut b = good.clone();
    b[6] = 8 / (std::mem::size_of::<Real>() as u8 / 4); // the other float width
    assert_eq!(
        target.restore(&b),
        Err(CheckpointError::RealWidthMismatch(b[6]))
    );
    let mut b = good.clone();
    b[8..12].copy_from_slice(&((CHECKPOINT_LEN - 4) as u32).to_le_bytes());
    assert_eq!(
        target.restore(&b),
        Err(CheckpointError::LengthMismatch {
            expected: CHECKPOINT_LEN,
            found: CHECKPOINT_LEN - 4
        })
    );
    let mut b = good.clone();
    let n = b.len();
    b[n - 1] ^= 0x80;
    assert!(matches!(
        target.restore(&b),
        Err(CheckpointError::CrcMismatch { .. })
    ));
    assert!(target == before);

    target.restore(good).unwrap();
    assert_eq!(target.estimate(), est.estimate());
}

/// An image fits any ring capacity: the window is not in it.
#[test]
fn an_image_of_another_ring_capacity_restores() {
    let (est, good) = &default_sources()[0];
    let mut small = Estimator::<CAP>::new(Config::default()).unwrap();
    small.restore(good).unwrap();
    // The same filter (the 1-sigma's residual check counts the window's entries, which differ).
    assert_eq!(
        small.estimate().map(|e| e.x_rad),
        est.estimate().map(|e| e.x_rad)
    );
    assert_eq!(image(&small), *good);
}

/// A realistic power cut: 20,000 s of a 1 Hz sea log with the default estimator, the checkpoint
/// of the last sample before the cut, 200 s of rows lost while the board is off (the navigation
/// computer keeps sending), then the rest of a 30,000 s log: at the end every error is within
/// 0.1 arcsec of the uncut run's, and the first answer after the restart carries the estimate.
#[test]
fn a_power_cut_with_lost_rows_costs_almost_nothing() {
    use estimator_core::units::rad_to_arcsec;
    let mut signal = Signal::new([200.0, -150.0, 300.0, -250.0], 40.0);
    signal.noise_arcsec = 5.0;
    let samples: Vec<Sample> = (0..30_000).map(|k| signal.sample(f64::from(k))).collect();
    let (_, uncut) = reference::<720>(Config::default(), &samples);
    let mut before: Estimator = Estimator::new(Config::default()).unwrap();
    for s in &samples[..20_000] {
        before.step(s).unwrap();
    }
    let buf = image(&before);
    let at_cut = before.estimate();
    drop(before);
    let mut after: Estimator = Estimator::new(Config::default()).unwrap();
    after.restore(&buf).unwrap();
    let first = after.step(&samples[20_200]).unwrap();
    assert_eq!(first.estimate, at_cut);
    assert_eq!(first.status, Status::Holding);
    for s in &samples[20_201..] {
        after.step(s).unwrap();
    }
    let (a, b) = (after.estimate().unwrap(), uncut.estimate().unwrap());
    for i in 0..4 {
        let d = rad_to_arcsec(f64::from(a.x_rad[i]) - f64::from(b.x_rad[i]));
        assert!(
            d.abs() < 0.1,
            "x{}: {d:.3} arcsec from the uncut run",
            i + 1
        );
    }
}
