//! Faults on the link, interleaved with a valid stream through the firmware in QEMU: garbage
//! bytes, truncated frames, corrupted CRCs, oversized frames, CRC-valid frames that are no message,
//! NaN samples and duplicated times. The firmware must resynchronise, count each fault by kind,
//! and answer every valid sample exactly as the host's own estimator does on the clean stream.
//! Then a burst of random bytes: the firmware must still be up and answering. On both boards.

use crate::qemu_support::*;
use estimator_core::{Config, Field, Output, RejectReason, SampleError};
use host_sim::formats::log_csv::read_log;
use host_sim::replay::{sample_of, HostEstimator};
use host_sim::stream::{step_remote, Target};
use link_protocol::frame::MAX_FRAME;
use link_protocol::{
    crc, encode_frame, FrameAccumulator, FrameError, Numbered, Request, Response, SampleMsg,
    MAX_REQUEST_ENCODED, UNNUMBERED,
};
use rand::{Rng as _, RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Duration;

/// ChaCha8 from a fixed seed: the faults are the same on every run.
struct Rng(ChaCha8Rng);
impl Rng {
    fn new(seed: u64) -> Rng {
        Rng(ChaCha8Rng::seed_from_u64(seed))
    }
    fn next(&mut self) -> u32 {
        self.0.next_u32()
    }
    fn nonzero_byte(&mut self) -> u8 {
        self.0.gen_range(1..=255)
    }
}

/// The frame of an unnumbered request (numbered frames are the link's own, through `step_remote`:
/// the faults must not look like lost frames).
fn frame(request: &Request) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME];
    let n = encode_frame(
        &Numbered {
            seq: UNNUMBERED,
            message: *request,
        },
        &mut out,
    )
    .unwrap();
    out[..n].to_vec()
}

/// A frame whose COBS and length are fine but whose CRC is wrong (one bit of it flipped).
fn frame_with_bad_crc(request: &Request) -> Vec<u8> {
    let f = frame(request);
    let mut body = f[1..f.len() - 1].to_vec();
    let n = cobs::decode_in_place(&mut body).unwrap();
    let mut data = body[..n].to_vec();
    *data.last_mut().unwrap() ^= 0x01;
    let mut enc = vec![0u8; cobs::max_encoding_length(data.len())];
    let n = cobs::try_encode(&data, &mut enc).unwrap();
    let mut f = vec![0];
    f.extend_from_slice(&enc[..n]);
    f.push(0);
    f
}

/// A frame with a correct CRC around bytes that are no request (variant 9).
fn frame_of_unknown_message() -> Vec<u8> {
    let mut data = vec![9u8];
    data.extend_from_slice(&crc::crc16(&[9]).to_le_bytes());
    let mut enc = vec![0u8; 8];
    let n = cobs::try_encode(&data, &mut enc).unwrap();
    let mut f = vec![0];
    f.extend_from_slice(&enc[..n]);
    f.push(0);
    f
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Fault {
    Garbage,
    Truncated,
    BadCrc,
    Oversize,
    UnknownMessage,
    Runt,
    NanSample,
    DuplicateTime,
}

const FAULTS: [Fault; 8] = [
    Fault::Garbage,
    Fault::Truncated,
    Fault::BadCrc,
    Fault::Oversize,
    Fault::UnknownMessage,
    Fault::Runt,
    Fault::NanSample,
    Fault::DuplicateTime,
];

fn key(o: &Result<Output, SampleError>) -> String {
    format!("{o:?}")
}

#[test]
fn mps2_an386_firmware_resyncs_counts_every_fault_and_answers_valid_frames_unchanged() {
    firmware_resyncs_counts_every_fault_and_answers_valid_frames_unchanged(Board::Mps2An386);
}

#[test]
fn stm32f405_firmware_resyncs_counts_every_fault_and_answers_valid_frames_unchanged() {
    firmware_resyncs_counts_every_fault_and_answers_valid_frames_unchanged(Board::Stm32f405);
}

fn firmware_resyncs_counts_every_fault_and_answers_valid_frames_unchanged(board: Board) {
    let elf = firmware_elf(board);
    let dir = scratch(&format!("faults-{}", board.name()));
    let log = paper_log(&dir, 2400);
    let lines = read_log(&log).unwrap();

    // The clean answers, from the host's own estimator.
    let mut host = HostEstimator::new(Config::default()).unwrap();
    let expected: Vec<String> = lines
        .iter()
        .map(|l| key(&host.step(&sample_of(&l.row))))
        .collect();

    let mut target = Target::boot_qemu(
        &elf,
        board.machine(),
        Some(&dir.join("defmt.bin")),
        None,
        Duration::from_secs(10),
    )
    .unwrap();
    // A shadow of the firmware's receiver, fed every byte sent, predicts its bad-frame counters.
    let mut shadow = FrameAccumulator::<MAX_REQUEST_ENCODED>::new();
    let mut predicted = [0u32; FrameError::COUNT];
    let mut shadow_feed = |bytes: &[u8], predicted: &mut [u32; FrameError::COUNT]| -> (u32, u32) {
        let (mut bad, mut good) = (0, 0);
        for &b in bytes {
            match shadow.push_decode::<Numbered<Request>>(b) {
                Some(Err(e)) => {
                    predicted[e as usize] += 1;
                    bad += 1;
                }
                Some(Ok(_)) => good += 1,
                None => {}
            }
        }
        (bad, good)
    };
    // The ReadStatus of boot went through the shadow-less path: it was valid.
    let mut rng = Rng::new(0x2545_F491);
    let mut injected = [0u32; FAULTS.len()];
    let mut pending_closing_zero = false;
    let mut previous: Option<SampleMsg> = None;
    for (i, line) in lines.iter().enumerate() {
        let msg = SampleMsg::from(&sample_of(&line.row));
        if i % 23 == 11 {
            let fault = FAULTS[(i / 23) % FAULTS.len()];
            injected[FAULTS.iter().position(|f| *f == fault).unwrap()] += 1;
            let bytes: Vec<u8> = match fault {
                Fault::Garbage => (0..1 + rng.next() % 40)
                    .map(|_| rng.nonzero_byte())
                    .collect(),
                Fault::Truncated => {
                    let f = frame(&Request::Sample(msg));
                    let cut = 2 + (rng.next() as usize) % (f.len() - 3);
                    f[..cut].to_vec()
                }
                Fault::BadCrc => frame_with_bad_crc(&Request::Sample(msg)),
                Fault::Oversize => {
                    let mut f = vec![0u8];
                    f.extend(
                        (0..MAX_REQUEST_ENCODED + 1 + (rng.next() % 200) as usize)
                            .map(|_| rng.nonzero_byte()),
                    );
                    f
                }
                Fault::UnknownMessage => frame_of_unknown_message(),
                // Valid COBS of one byte: no room for a message and its CRC.
                Fault::Runt => vec![0x00, 0x02, 0x55, 0x00],
                Fault::NanSample => frame(&Request::Sample(SampleMsg {
                    roll_rad: f32::NAN,
                    ..msg
                })),
                Fault::DuplicateTime => {
                    frame(&Request::Sample(previous.expect("not the first row")))
                }
            };
            // Faults without a closing 0x00 are closed by the next frame's leading 0x00.
            let (bad, good) = shadow_feed(&bytes, &mut predicted);
            pending_closing_zero = bytes.last() != Some(&0);
            target.link.send_raw(&bytes).unwrap();
            match fault {
                Fault::NanSample | Fault::DuplicateTime => {
                    assert_eq!((bad, good), (0, 1), "{fault:?} is a valid frame");
                    let answer = match target.link.receive().unwrap() {
                        Response::Rejected(r) => r.error(),
                        other => panic!("{fault:?} answered with {other:?}"),
                    };
                    let want = if fault == Fault::NanSample {
                        SampleError::NonFinite(Field::Roll)
                    } else {
                        SampleError::TimeNotIncreasing
                    };
                    assert_eq!(answer, Some(want), "row {i}");
                }
                Fault::Garbage | Fault::Truncated | Fault::Oversize => {
                    assert_eq!((bad, good), (0, 0), "{fault:?} is closed by the next frame")
                }
                _ => assert_eq!((bad, good), (1, 0), "{fault:?} is exactly one bad frame"),
            }
        }
        let f = frame(&Request::Sample(msg));
        let (bad, good) = shadow_feed(&f, &mut predicted);
        assert_eq!(
            (bad, good),
            (pending_closing_zero as u32, 1),
            "row {i}: the valid frame closes a pending fault and decodes"
        );
        pending_closing_zero = false;
        // step_remote sends this frame numbered (the shadow decodes it the same unnumbered).
        let answer = step_remote(&mut target, &msg).unwrap_or_else(|e| panic!("row {i}: {e:#}"));
        // The answer is the clean stream's but for the count of rejected samples, which holds
        // the NaN and repeated samples sent so far.
        let mut result = answer.result;
        if let Ok(o) = &mut result {
            assert_eq!(
                o.health.rejected,
                injected[6] + injected[7],
                "row {i}: rejected samples so far"
            );
            o.health.rejected = 0;
        }
        assert_eq!(
            key(&result),
            expected[i],
            "row {i}: answer differs from the clean stream's"
        );
        previous = Some(msg);
    }
    let status = target.status().unwrap();
    println!(
        "injected {injected:?}; firmware counters {:?}",
        status.counters
    );
    assert_eq!(
        status.counters.bad_frames, predicted,
        "bad frames by kind (oversize, cobs, too_short, crc, message)"
    );
    let frame_faults: u32 = injected[..6].iter().sum();
    assert_eq!(
        status.counters.bad_frames_total(),
        frame_faults,
        "one bad frame per injected frame fault"
    );
    for (kind, n) in FrameError::ALL.iter().zip(predicted) {
        assert!(n > 0, "no {} fault exercised", kind.name());
    }
    let bad = status.counters.bad_frames;
    assert_eq!(bad[FrameError::Oversize as usize], injected[3]);
    assert!(bad[FrameError::Crc as usize] >= injected[2]);
    assert_eq!(bad[FrameError::Message as usize], injected[4]);
    assert!(bad[FrameError::TooShort as usize] >= injected[5]);
    let rejected = status.counters.rejected_samples;
    assert_eq!(rejected[RejectReason::NonFinite as usize], injected[6]);
    assert_eq!(
        rejected[RejectReason::TimeNotIncreasing as usize],
        injected[7]
    );
    assert_eq!(
        status.counters.rejected_samples_total(),
        injected[6] + injected[7]
    );
    assert_eq!(status.accepted as usize, lines.len());
    // The numbered frames all arrived: the faults cost no frame but their own.
    assert_eq!(
        status.link.lost_frames, 0,
        "no numbered frame lost: {:?}",
        status.link
    );
    assert_eq!(status.link.errors_total(), 0, "{:?}", status.link);

    // Random bytes, zeros included: nothing may stop the firmware.
    let noise: Vec<u8> = (0..20_000)
        .map(|_| {
            if rng.next().is_multiple_of(29) {
                0
            } else {
                rng.nonzero_byte()
            }
        })
        .collect();
    target.link.send_raw(&noise).unwrap();
    let mut answered = false;
    target.link.send(&Request::ReadStatus).unwrap();
    for _ in 0..10 {
        if let Response::Status(s) = target.link.receive().unwrap() {
            assert!(s.counters.bad_frames_total() > status.counters.bad_frames_total());
            answered = true;
            break;
        }
    }
    assert!(
        answered,
        "the firmware answers ReadStatus after 20000 random bytes"
    );
    assert!(
        target.qemu.as_mut().unwrap().exited().is_none(),
        "QEMU still running"
    );
}
