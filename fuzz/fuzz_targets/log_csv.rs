//! host-sim's CSV log reader on arbitrary bytes; every row it accepts goes through the core.
//! Checks: no panic, the reader stops after an error of the whole file (an unreadable row is an
//! error of that row only: rows may follow it), finite core output.
#![no_main]

mod common;

use common::{assert_finite, CAP};
use estimator_core::{Config, Estimator, Sample};
use host_sim::formats::log_csv::LogReader;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let mut est = Estimator::<CAP>::new(Config { rotation_period_s: Some(60.0), sample_interval_s: Some(1.0), ..Config::default() }).expect("config");
    let reader = LogReader::new(Path::new("fuzz.csv"), std::io::Cursor::new(data));
    let mut fatal = 0;
    for line in reader.take(10_000) {
        assert_eq!(fatal, 0, "an item after an error of the whole file");
        match line {
            Ok(l) => {
                let r = l.row;
                let s = Sample::from_degrees(r.time_s, r.rotation_deg, r.platform_deg, r.latitude_deg, r.heading_deg, r.roll_deg, r.pitch_deg);
                if let Ok(out) = est.step(&s) {
                    assert_finite(&out);
                }
            }
            Err(e) if e.row => {}
            Err(_) => fatal += 1,
        }
    }
});
