//! Helpers shared by the CLI tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh directory under the target's tmp dir.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir =
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs the binary.
pub fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs the binary and requires success; returns stdout.
pub fn host_sim_ok(args: &[&str]) -> String {
    let out = host_sim(args);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "host-sim {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

pub fn path_str(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A generated paper log of `duration` s in `dir` (with its truth file).
pub fn paper(dir: &Path, duration: u32) -> PathBuf {
    let log = dir.join("paper.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        &duration.to_string(),
        "--out",
        path_str(&log),
    ]);
    log
}
