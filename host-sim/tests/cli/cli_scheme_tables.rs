//! `compare` and `monte-carlo` over rotation schemes and recorder losses: well-formed tables.

use crate::common::host_sim_ok;

/// Markdown blocks of a compare output: (heading line, table lines).
fn blocks(stdout: &str) -> Vec<(String, Vec<String>)> {
    let mut out: Vec<(String, Vec<String>)> = Vec::new();
    for line in stdout.lines() {
        if line.starts_with("scheme ") {
            out.push((line.to_string(), Vec::new()));
        } else if line.starts_with("| ") || line.starts_with("|---") {
            out.last_mut()
                .expect("a heading before a table")
                .1
                .push(line.to_string());
        }
    }
    out
}

#[test]
fn compare_gives_one_table_per_scheme_with_loss_described() {
    let stdout = host_sim_ok(&[
        "compare",
        "--seeds",
        "2",
        "--duration",
        "2000",
        "--scenarios",
        "turntable",
        "--methods",
        "windowed,traditional",
        "--schemes",
        "all",
        "--drop-fraction",
        "0.02",
        "--outages",
        "3",
        "--time-jitter",
        "0.02",
        "--time-offset",
        "1.7e9",
    ]);
    let b = blocks(&stdout);
    let names = [
        "continuous",
        "reversed",
        "reciprocating",
        "four-position",
        "eight-position",
    ];
    assert_eq!(b.len(), names.len(), "{stdout}");
    for ((heading, table), name) in b.iter().zip(names) {
        assert!(heading.starts_with(&format!("scheme {name}, rotation period 480 s, a row every 1 s; recorder: 2 % of rows dropped")), "{heading}");
        assert!(
            heading.contains("3 outages of 60 s")
                && heading.contains("offset by 1700000000 s")
                && heading.contains("0.02 s"),
            "{heading}"
        );
        assert_eq!(
            table.len(),
            2 + 2,
            "{name}: header, separator, two methods:\n{stdout}"
        );
        let columns = table[0].matches('|').count();
        assert!(
            table.iter().all(|l| l.matches('|').count() == columns),
            "{name}:\n{stdout}"
        );
        // Every line counts both runs in its final statuses.
        for line in &table[2..] {
            let statuses = line.rsplit('|').nth(1).unwrap().trim();
            let counted: usize = statuses
                .split(", ")
                .map(|s| {
                    s.rsplit('(')
                        .next()
                        .unwrap()
                        .trim_end_matches(')')
                        .parse::<usize>()
                        .unwrap()
                })
                .sum();
            assert_eq!(counted, 2, "{line}");
        }
    }
    assert!(
        stdout.contains("`host-sim compare --seeds 2 --duration 2000"),
        "the command is named: {stdout}"
    );
}

#[test]
fn compare_estimates_a_reciprocating_720_s_pattern_it_learned() {
    // Nothing pinned: the estimator learns the 720 s reciprocating pattern and ends converged.
    let stdout = host_sim_ok(&[
        "compare",
        "--seeds",
        "1",
        "--duration",
        "6000",
        "--scenarios",
        "paper",
        "--methods",
        "windowed",
        "--scheme",
        "reciprocating",
        "--rotation-period",
        "720",
    ]);
    let b = blocks(&stdout);
    assert_eq!(b.len(), 1);
    assert!(b[0].0.starts_with("scheme reciprocating, rotation period 720 s, a row every 1 s, every row, exact time stamps"), "{}", b[0].0);
    assert!(b[0].1[2].contains("| converged (1) |"), "{stdout}");
}

#[test]
fn monte_carlo_runs_a_scheme_at_another_interval() {
    // Continuous at 2 s: the interval learned, 240 samples per period, converging as at 1 s.
    let stdout = host_sim_ok(&[
        "monte-carlo",
        "--scenario",
        "paper",
        "--runs",
        "2",
        "--duration",
        "5001",
        "--sample-interval",
        "2",
        "--threads",
        "1",
    ]);
    assert!(stdout.contains("scheme continuous, rotation period 480 s, a row every 2 s, every row, exact time stamps"), "{stdout}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("| 5000 | median |"))
        .expect("5000 s line");
    let medians: Vec<f64> = line
        .split('|')
        .skip(3)
        .take(4)
        .map(|v| v.trim().parse().unwrap())
        .collect();
    assert!(medians.iter().all(|e| *e < 10.0), "{line}");
    let stdout = host_sim_ok(&[
        "monte-carlo",
        "--scenario",
        "turntable",
        "--runs",
        "1",
        "--duration",
        "2001",
        "--scheme",
        "eight-position",
        "--outages",
        "2",
        "--drop-fraction",
        "0.01",
        "--threads",
        "1",
    ]);
    assert!(stdout.contains("scheme eight-position, rotation period 480 s, a row every 1 s; recorder: 1 % of rows dropped at random, 2 outages of 60 s"), "{stdout}");
    assert!(stdout.contains("| 2000 | median |"), "{stdout}");
}
