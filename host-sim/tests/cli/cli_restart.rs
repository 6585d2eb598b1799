//! `estimate --restart-at`: at each time the estimator is checkpointed, dropped and restored from
//! the bytes (after the first row at or after the time), as after a power cut right after a save.
//! The estimates CSV is the uninterrupted run's up to the first restart; after each, the first row
//! carries the estimate held before it
//! (the window refilling: `holding`); and at the end our method is within the uninterrupted run's
//! 1-sigma of it.

use crate::common::{host_sim_ok, path_str, temp_dir};

/// x1..x4, sigma1..4 (arcsec) and status of an estimates row.
fn fields(line: &str) -> ([Option<f64>; 8], String) {
    let f: Vec<&str> = line.split(',').collect();
    (
        std::array::from_fn(|i| f[1 + i].parse().ok()),
        f[9].to_string(),
    )
}

#[test]
fn a_restart_continues_from_the_checkpoint() {
    let dir = temp_dir("cli-restart");
    let log = dir.join("sea.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "sea",
        "--duration",
        "6000",
        "--out",
        path_str(&log),
    ]);
    // A NaN row and a gap, so restarts also land in the held/refilling states.
    let text = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<String> = text
        .lines()
        .enumerate()
        .filter(|(i, _)| !(2500..2505).contains(i))
        .map(|(i, l)| {
            let mut f: Vec<&str> = l.split(',').collect();
            if i == 1200 {
                f[5] = "nan";
            }
            f.join(",")
        })
        .collect();
    std::fs::write(&log, lines.join("\n") + "\n").unwrap();
    let restarts = [1199.0, 2502.0, 3000.5];
    for method in ["windowed", "paper", "traditional"] {
        let plain = dir.join(format!("plain.{method}.csv"));
        let restarted = dir.join(format!("restarted.{method}.csv"));
        host_sim_ok(&[
            "estimate",
            path_str(&log),
            "--method",
            method,
            "--out",
            path_str(&plain),
        ]);
        let stdout = host_sim_ok(&[
            "estimate",
            path_str(&log),
            "--method",
            method,
            "--out",
            path_str(&restarted),
            "--restart-at",
            "1199,2502,3000.5",
        ]);
        assert!(stdout.contains("restarted from a checkpoint"), "{stdout}");
        let a = std::fs::read_to_string(&plain).unwrap();
        let b = std::fs::read_to_string(&restarted).unwrap();
        let (a, b): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
        assert_eq!(a.len(), b.len());
        let time = |l: &str| l.split(',').next().unwrap().parse::<f64>().unwrap();
        // The restart comes after the first row at or after each time.
        let at = |t: f64| {
            b.iter()
                .position(|l| !l.starts_with("time_s") && time(l) >= t)
                .unwrap()
        };
        let first = at(restarts[0]);
        assert_eq!(
            a[..=first],
            b[..=first],
            "{method}: rows up to the first restart differ"
        );
        for t in restarts {
            let k = at(t);
            let (held, _) = fields(b[k]);
            let (next, status) = fields(b[k + 1]);
            if held[0].is_some() && status != "rejected_non_finite" {
                assert_eq!(&next[..4], &held[..4], "{method}: the estimate after the restart at {t} s is not the one held before it");
                if method != "traditional" {
                    assert_eq!(status, "holding", "{method}: after the restart at {t} s");
                }
            }
        }
        if method == "windowed" {
            let (end_a, _) = fields(a.last().unwrap());
            let (end_b, _) = fields(b.last().unwrap());
            for i in 0..4 {
                let d = (end_b[i].unwrap() - end_a[i].unwrap()).abs();
                assert!(
                    d <= end_a[4 + i].unwrap(),
                    "x{}: {d} arcsec from the uninterrupted run",
                    i + 1
                );
            }
        }
    }
}
