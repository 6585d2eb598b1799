//! Compensation across a software update: the firmware's store saves the learned errors' record
//! (a layout every later version reads) in front of each checkpoint image. A build that refuses
//! the image because another build wrote it (another format version) starts from the record: its
//! first output already carries the estimate and compensates with it. A damaged image is refused
//! as before, and an item of an older build (an image alone) restores as before.

use estimator_core::checkpoint::{crc32, CHECKPOINT_LEN, VERSION};
use estimator_core::learned::{LearnedErrors, LEARNED_LEN, LEARNED_MIN_SIGMA_RAD};
use estimator_core::units::rad_to_arcsec;
use estimator_core::{Config, Estimator};
use firmware::checkpoint_store::{restore_item, Restored};
use host_sim::replay::sample_of;
use host_sim::sim::samples::Samples;
use host_sim::sim::scenario::{ScenarioKind, ScenarioParams};

/// An estimator that has run 3,000 s of the paper scenario, and the rows after.
fn run() -> (Estimator, Vec<estimator_core::Sample>) {
    let params = ScenarioParams::new(ScenarioKind::Paper, 5);
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut rest = Vec::new();
    for (k, (row, _)) in Samples::new(&params).enumerate() {
        let s = sample_of(&row);
        if k < 3000 {
            est.step(&s).unwrap();
        } else if k < 3100 {
            rest.push(s);
        } else {
            break;
        }
    }
    (est, rest)
}

/// The store's item: the record, then the image.
fn item_of(est: &Estimator) -> (LearnedErrors, Vec<u8>) {
    let learned = est.learned_errors().expect("an estimate after 3,000 s");
    let mut item = learned.encode().to_vec();
    let mut image = vec![0u8; CHECKPOINT_LEN];
    est.checkpoint(&mut image).unwrap();
    item.extend_from_slice(&image);
    (learned, item)
}

/// The item with its image's format version set to `version` and its CRC made again: what a
/// build of that format would have saved.
fn with_image_version(item: &[u8], version: u16) -> Vec<u8> {
    let mut item = item.to_vec();
    let image = &mut item[LEARNED_LEN..];
    image[4..6].copy_from_slice(&version.to_le_bytes());
    let n = image.len();
    let crc = crc32(&image[..n - 4]);
    image[n - 4..].copy_from_slice(&crc.to_le_bytes());
    item
}

#[test]
fn an_image_of_another_version_starts_the_estimator_from_the_learned_errors() {
    let (est, rest) = run();
    let (learned, item) = item_of(&est);
    // The same build: the image itself.
    let mut same: Estimator = Estimator::new(Config::default()).unwrap();
    assert!(matches!(
        restore_item(&mut same, &item),
        Restored::Image { .. }
    ));
    assert_eq!(same.estimate(), est.estimate());
    for version in [VERSION - 1, VERSION + 1] {
        let mut next: Estimator = Estimator::new(Config::default()).unwrap();
        match restore_item(&mut next, &with_image_version(&item, version)) {
            Restored::Learned { time_s, .. } => assert_eq!(time_s, learned.time_s),
            other => panic!("version {version}: {other:?}"),
        }
        // From the first sample on: the learned values, with a 1-sigma of at least 1 arcsec,
        // compensating the attitude as the old build's estimate did.
        let out = next.step(&rest[0]).unwrap();
        let e = out.estimate.expect("an estimate at the first sample");
        assert_eq!(e.x_rad, learned.x_rad);
        assert!(e.sigma_rad.iter().all(|s| *s >= LEARNED_MIN_SIGMA_RAD));
        let mut old = est.clone();
        let out_old = old.step(&rest[0]).unwrap();
        let off_arcsec = rad_to_arcsec(f64::from(
            out.corrected.roll_rad - out_old.corrected.roll_rad,
        ));
        assert!(
            off_arcsec.abs() < 0.01,
            "compensation differs by {off_arcsec} arcsec"
        );
        // And it goes on learning: 100 samples later the estimate is still there.
        for s in &rest[1..] {
            assert!(next.step(s).unwrap().estimate.is_some());
        }
    }
    // A damaged image is not another build's: refused, the estimator unchanged.
    let mut damaged = item.clone();
    damaged[LEARNED_LEN + 100] ^= 1;
    let mut fresh: Estimator = Estimator::new(Config::default()).unwrap();
    let before = fresh.clone();
    assert!(matches!(
        restore_item(&mut fresh, &damaged),
        Restored::Refused(_)
    ));
    assert!(fresh == before);
    // An older build's item, the image alone: restored as it always was.
    let mut older: Estimator = Estimator::new(Config::default()).unwrap();
    assert!(matches!(
        restore_item(&mut older, &item[LEARNED_LEN..]),
        Restored::Image { .. }
    ));
    assert_eq!(older.estimate(), est.estimate());
}
