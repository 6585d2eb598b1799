//! The firmware's checkpoint store (its library, compiled for the host) under power cuts, on a
//! model of each board's flash that tears the operation the cut lands in (`host_sim::flash_model`): the power is cut at
//! every sector erase and every programmed unit (a byte on the STM32F405, whose HAL programs at
//! x8; a 4-byte word on mps2-an386) of a save that only programs, of a save that also erases a
//! sector, and of an invalidation. After each cut the power comes back, a fresh store on the torn
//! flash restores: always the newest complete image or the one before it, byte for byte (so never
//! a torn header nor a non-finite time: the core checks every value of what it restores), or, for
//! an invalidation, the image before or nothing. Then the log takes the next save, which restores.

use estimator_core::checkpoint::CHECKPOINT_LEN;
use estimator_core::{Config, Estimator};
use firmware::checkpoint_store::{CheckpointStore, Restored, StoreBuffers};
use host_sim::flash_model::FlashModel;
use host_sim::replay::sample_of;
use host_sim::sim::samples::Samples;
use host_sim::sim::scenario::{ScenarioKind, ScenarioParams};

/// Images of a running estimator, all different (one every 10 samples of the paper scenario).
fn images(n: usize) -> Vec<Vec<u8>> {
    let params = ScenarioParams::new(ScenarioKind::Paper, 3);
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut out = Vec::new();
    for (k, (row, _)) in Samples::new(&params).enumerate() {
        est.step(&sample_of(&row)).unwrap();
        if k % 10 == 9 {
            let mut image = vec![0u8; CHECKPOINT_LEN];
            est.checkpoint(&mut image).unwrap();
            out.push(image);
            if out.len() == n {
                return out;
            }
        }
    }
    panic!("the scenario is too short for {n} images");
}

fn estimator_of(image: &[u8]) -> Estimator {
    Estimator::from_checkpoint(image).unwrap()
}

/// What a store on `flash` restores, as an image (`None`: nothing or forgotten).
fn restored<const S: usize, const W: usize>(flash: &mut FlashModel<S, W>) -> Option<Vec<u8>> {
    let mut est: Estimator = Estimator::new(Config::default()).unwrap();
    let mut buffers = StoreBuffers::new();
    let mut store = CheckpointStore::new(flash, &mut buffers).unwrap();
    match store
        .restore(&mut est)
        .expect("the store restores after a power cut")
    {
        Restored::Image { time_s } => {
            assert!(
                time_s.is_some_and(f64::is_finite),
                "restored time {time_s:?}"
            );
            let mut image = vec![0u8; CHECKPOINT_LEN];
            est.checkpoint(&mut image).unwrap();
            Some(image)
        }
        Restored::Nothing | Restored::Forgotten => None,
        Restored::Refused(e) => panic!("the store gave the core an image it refused: {e}"),
        Restored::Learned { refused, .. } => {
            panic!("the store gave the core an image of another version: {refused}")
        }
    }
}

/// What one operation on the store does.
#[derive(Clone, Copy)]
enum Op<'a> {
    Save(&'a [u8]),
    Invalidate,
}

fn apply<const S: usize, const W: usize>(
    flash: &mut FlashModel<S, W>,
    op: Op<'_>,
) -> Result<(), firmware::checkpoint_store::StoreError> {
    let mut buffers = StoreBuffers::new();
    let mut store = CheckpointStore::new(flash, &mut buffers)?;
    match op {
        Op::Save(image) => store.save(&estimator_of(image)),
        Op::Invalidate => store.invalidate(),
    }
}

/// What cutting at every operation found.
struct Cuts {
    /// Operations of the whole operation.
    operations: u64,
    /// Erases it made when it ran whole.
    erases: u64,
    /// Sectors the store erased again at start-up after a cut (torn erases).
    re_erased: u32,
}

/// Cuts the power at every operation of `op` on `flash` (whose newest image is `before`), and
/// checks what restores and that the log goes on.
fn cut_everywhere<const S: usize, const W: usize>(
    flash: &FlashModel<S, W>,
    op: Op<'_>,
    before: &[u8],
    next: &[u8],
) -> Cuts {
    let mut whole = flash.clone();
    apply(&mut whole, op).unwrap();
    let start = flash.counts().operations;
    let ops = whole.counts().operations - start;
    let erases =
        whole.counts().erases.iter().sum::<u64>() - flash.counts().erases.iter().sum::<u64>();
    let after = match op {
        Op::Save(image) => Some(image.to_vec()),
        Op::Invalidate => None,
    };
    let mut re_erased = 0;
    for k in 0..ops {
        let mut cut = flash.clone();
        cut.cut_power_at(Some(start + k), k);
        assert!(
            apply(&mut cut, op).is_err(),
            "operation {k} of {ops}: the cut did not stop the operation"
        );
        assert!(cut.was_cut());
        cut.power_on();
        // What the firmware does at start-up: the store is made (torn erases erased again).
        re_erased += CheckpointStore::new(&mut cut, &mut StoreBuffers::new())
            .unwrap()
            .re_erased();
        let got = restored(&mut cut);
        assert!(
            got.as_deref() == Some(before) || got == after,
            "cut at operation {k} of {ops}: restored neither the image before nor the new one but {}",
            match &got {
                None => "nothing".to_string(),
                Some(g) => format!("an image of {} s", estimator_of(g).last_sample_time_s().unwrap_or(f64::NAN)),
            }
        );
        // The log repairs itself and takes the next save.
        apply(&mut cut, Op::Save(next))
            .unwrap_or_else(|e| panic!("cut at {k}: the next save failed: {e}"));
        assert_eq!(
            restored(&mut cut).as_deref(),
            Some(next),
            "cut at {k}: the next save does not restore"
        );
        assert_eq!(
            cut.counts().impossible_writes,
            0,
            "cut at {k}: the store asked for bits NOR flash cannot set"
        );
    }
    Cuts {
        operations: ops,
        erases,
        re_erased,
    }
}

/// Fills `flash` with `images` until the next save erases a sector; returns the index of the
/// newest image saved.
fn fill_until_the_next_save_erases<const S: usize, const W: usize>(
    flash: &mut FlashModel<S, W>,
    images: &[Vec<u8>],
) -> usize {
    for (i, image) in images.iter().enumerate() {
        let mut trial = flash.clone();
        let erases = trial.counts().erases.iter().sum::<u64>();
        apply(&mut trial, Op::Save(image)).unwrap();
        if i > 0 && trial.counts().erases.iter().sum::<u64>() > erases {
            return i - 1;
        }
        *flash = trial;
    }
    panic!("{} saves never erased a sector", images.len());
}

fn every_cut_of_every_kind_of_save<const S: usize, const W: usize>(
    mut flash: FlashModel<S, W>,
    images: &[Vec<u8>],
) {
    // A save that only programs: the log holds a few images.
    for image in &images[..3] {
        apply(&mut flash, Op::Save(image)).unwrap();
    }
    let cuts = cut_everywhere(&flash, Op::Save(&images[3]), &images[2], &images[4]);
    assert_eq!(cuts.erases, 0);
    assert!(
        cuts.operations as usize >= CHECKPOINT_LEN / W,
        "{} operations in a save",
        cuts.operations
    );
    println!(
        "program-only save: power cut at each of its {} operations",
        cuts.operations
    );
    // An invalidation.
    let cuts = cut_everywhere(&flash, Op::Invalidate, &images[2], &images[4]);
    println!(
        "invalidation: power cut at each of its {} operations",
        cuts.operations
    );
    // A save that erases: the log has gone round its sectors. A cut in its erase leaves the sector
    // torn, which the store erases again at start-up.
    let newest = fill_until_the_next_save_erases(&mut flash, &images[5..]) + 5;
    let cuts = cut_everywhere(
        &flash,
        Op::Save(&images[newest + 1]),
        &images[newest],
        &images[newest + 2],
    );
    assert!(
        cuts.erases >= 1 && cuts.re_erased >= 1,
        "{} erases, {} re-erased",
        cuts.erases,
        cuts.re_erased
    );
    println!(
        "erasing save (after {} saves): power cut at each of its {} operations, {} erase(s), torn erases re-erased at start-up",
        newest + 1,
        cuts.operations,
        cuts.erases
    );
}

#[test]
fn stm32f405_layout_every_cut_restores_the_newest_or_the_one_before() {
    // The STM32F405's flash as the store sees it (4-byte writes, programmed byte by byte at x8),
    // in three sectors of 16 KiB (the size of the chip's sectors 1-3) rather than seven of 128 KiB:
    // the log goes round in 50 saves instead of a thousand, and every cut restores in a tenth of
    // the time. The crate treats every sector alike, whatever its size.
    let images = images(80);
    every_cut_of_every_kind_of_save(FlashModel::<{ 16 * 1024 }, 4>::new(3, 1), &images);
}

#[test]
fn mps2_an386_layout_every_cut_restores_the_newest_or_the_one_before() {
    let images = images(40);
    every_cut_of_every_kind_of_save(FlashModel::<4096, 4>::new(4, 4), &images);
}
