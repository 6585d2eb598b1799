//! Shared by the `qemu_*` tests: builds the firmware ELF with the workspace's `firmware` profile,
//! insists that QEMU is installed (a missing QEMU fails the test, it is never skipped), and makes
//! scratch directories.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host-sim sits in the workspace")
        .to_path_buf()
}

/// Builds `firmware` for thumbv7em-none-eabihf with `--profile firmware` and `features` (on top
/// of its defaults), and returns the path cargo wrote the ELF to.
fn build_firmware(features: &[&str]) -> PathBuf {
    build_firmware_with_env(features, &[])
}

/// [`build_firmware`] with build-time environment variables (e.g. `RINS_CHECKPOINT_INTERVAL_S`).
fn build_firmware_with_env(features: &[&str], env: &[(&str, &str)]) -> PathBuf {
    require_qemu();
    let root = workspace_root();
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let mut command = Command::new(&cargo);
    command
        .current_dir(&root)
        .args(["build", "-p", "firmware", "--target", "thumbv7em-none-eabihf", "--profile", "firmware"]);
    if !features.is_empty() {
        command.args(["--features", &features.join(",")]);
    }
    command.envs(env.iter().copied());
    let status = command.status().expect("cannot run cargo to build the firmware");
    assert!(
        status.success(),
        "building the firmware with features {features:?} failed ({status}): see cargo's output above (a missing target needs `rustup target add thumbv7em-none-eabihf`)"
    );
    let target_dir = std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| root.join("target"));
    let target_dir = if target_dir.is_absolute() { target_dir } else { root.join(target_dir) };
    let elf = target_dir.join("thumbv7em-none-eabihf").join("firmware").join("firmware");
    assert!(elf.is_file(), "{} missing after the build", elf.display());
    elf
}

/// The default firmware ELF (checkpoints in flash included), built once per test binary.
pub fn firmware_elf() -> PathBuf {
    static ELF: OnceLock<PathBuf> = OnceLock::new();
    ELF.get_or_init(|| build_firmware(&[])).clone()
}

/// The default firmware built with build-time environment `env`, copied to
/// `target/qemu-tests/NAME.elf`, where no later build overwrites it.
pub fn firmware_elf_with_env(name: &str, env: &[(&str, &str)]) -> PathBuf {
    let built = build_firmware_with_env(&[], env);
    let copy = workspace_root().join("target").join("qemu-tests").join(format!("{name}.elf"));
    std::fs::create_dir_all(copy.parent().expect("a parent")).expect("create target/qemu-tests");
    std::fs::copy(&built, &copy).expect("copy the firmware ELF");
    copy
}

/// Generates the paper scenario (default seed) for `duration_s` into `dir/paper.csv` and its truth
/// file; returns the log's path.
pub fn paper_log(dir: &Path, duration_s: u32) -> PathBuf {
    let log = dir.join("paper.csv");
    host_sim(&["generate", "--scenario", "paper", "--duration", &duration_s.to_string(), "--out", log.to_str().unwrap()]);
    log
}

/// Fails (never skips) when QEMU is missing: CI installs it, and a skipped test would hide that.
pub fn require_qemu() {
    let qemu = host_sim::stream::qemu::qemu_binary();
    match Command::new(&qemu).arg("--version").output() {
        Ok(o) if o.status.success() => {}
        _ => panic!("{qemu} is not installed: these tests boot the firmware in QEMU (Debian: apt-get install -y qemu-system-arm)"),
    }
}

/// A fresh scratch directory under the target directory, removed when dropped unless the test
/// failed (then it is kept for a look).
pub fn scratch(name: &str) -> Scratch {
    let dir = workspace_root()
        .join("target")
        .join("qemu-tests")
        .join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    Scratch(dir)
}

/// See [`scratch`].
pub struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Runs the host-sim binary; returns stdout; panics with its stderr if it fails.
pub fn host_sim(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("run host-sim");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "host-sim {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// `(max, mean)` from the `step cost: max N instructions, mean M instructions` line.
pub fn step_cost(stdout: &str) -> (f64, f64) {
    let line = stdout
        .lines()
        .find(|l| l.starts_with("step cost: "))
        .unwrap_or_else(|| panic!("no step cost line in:\n{stdout}"));
    let words: Vec<&str> = line.split_whitespace().collect();
    assert_eq!(words.len(), 8, "{line}");
    assert_eq!(
        (words[2], words[4], words[7]),
        ("max", "instructions,", "instructions"),
        "{line}"
    );
    (words[3].parse().expect(line), words[6].parse().expect(line))
}
