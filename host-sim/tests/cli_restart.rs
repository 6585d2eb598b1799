//! `estimate --restart-at`: checkpoint, drop, restore; the estimates CSV is byte-identical.

mod common;

use common::{host_sim_ok, path_str, temp_dir};

#[test]
fn restart_from_checkpoint_gives_byte_identical_estimates() {
    let dir = temp_dir("cli-restart");
    let log = dir.join("sea.csv");
    host_sim_ok(&["generate", "--scenario", "sea", "--duration", "6000", "--out", path_str(&log)]);
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
    for method in ["windowed", "paper", "traditional"] {
        let plain = dir.join(format!("plain.{method}.csv"));
        let restarted = dir.join(format!("restarted.{method}.csv"));
        host_sim_ok(&["estimate", path_str(&log), "--method", method, "--out", path_str(&plain)]);
        let stdout = host_sim_ok(&[
            "estimate", path_str(&log), "--method", method, "--out", path_str(&restarted),
            "--restart-at", "0,1,479,480,1199,2502,3000.5,5999",
        ]);
        assert!(stdout.contains("restarted from a checkpoint"), "{stdout}");
        let a = std::fs::read(&plain).unwrap();
        let b = std::fs::read(&restarted).unwrap();
        assert!(a.len() > 100_000);
        assert!(a == b, "{method}: estimates differ after restarts");
    }
}
