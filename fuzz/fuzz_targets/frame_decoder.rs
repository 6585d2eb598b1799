//! The link's receive path on arbitrary bytes: the frame accumulator decoding numbered `Request`s
//! byte by byte (decoded samples go through the core), and `decode_frame` of a numbered `Response`
//! on the whole input. Checks: no panic, finite core output.
#![no_main]

mod common;

use common::{assert_finite, CAP};
use estimator_core::{Config, Estimator, Sample};
use libfuzzer_sys::fuzz_target;
use link_protocol::accumulator::FrameAccumulator;
use link_protocol::frame::decode_frame;
use link_protocol::message::{Numbered, Request, Response};

fuzz_target!(|data: &[u8]| {
    let mut est = Estimator::<CAP>::new(Config { rotation_period_s: Some(60.0), sample_interval_s: Some(1.0), ..Config::default() }).expect("config");
    let mut rx = FrameAccumulator::<128>::new();
    for &b in data {
        if let Some(Ok(Numbered { message: Request::Sample(msg), .. })) = rx.push_decode::<Numbered<Request>>(b) {
            if let Ok(out) = est.step(&Sample::from(&msg)) {
                assert_finite(&out);
            }
        }
    }
    let mut copy = data.to_vec();
    let _ = decode_frame::<Numbered<Response>>(&mut copy);
});
