//! `host-sim stream --port DEVICE --baud N`, the path for a real board, exercised against the
//! firmware in QEMU with its UART0 on a pseudo-terminal (`-serial pty`): the serial-port code of
//! host-sim must give the same estimates CSV as `host-sim estimate`. A second stream to the same
//! board, which now holds the first one's state, is refused; with `--reset` it is exact again.

use crate::qemu_support::*;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// QEMU, killed when dropped.
struct Guard(Child);
impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[test]
fn stream_over_a_serial_port_matches_estimate() {
    let elf = firmware_elf(Board::Mps2An386);
    let dir = scratch("port");
    let log = paper_log(&dir, 1200);
    let (est, streamed) = (dir.join("estimate.csv"), dir.join("stream.csv"));
    host_sim(&[
        "estimate",
        log.to_str().unwrap(),
        "--out",
        est.to_str().unwrap(),
    ]);

    // QEMU names the pseudo-terminal on its stdout (which also carries the defmt log):
    // "char device redirected to /dev/pts/N (label serial0)".
    let stdout_path = dir.join("qemu.stdout");
    let qemu = Command::new(host_sim::stream::qemu::qemu_binary())
        .args([
            "-machine",
            "mps2-an386",
            "-cpu",
            "cortex-m4",
            "-icount",
            "shift=0",
            "-display",
            "none",
            "-monitor",
            "none",
        ])
        .args([
            "-semihosting-config",
            "enable=on,target=native",
            "-serial",
            "pty",
            "-kernel",
        ])
        .arg(&elf)
        // QEMU's working directory holds the firmware's flash file: the scratch directory, never
        // the source tree (a flash left there would be restored by the next run).
        .current_dir(&dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&stdout_path).unwrap())
        .stderr(Stdio::null())
        .spawn()
        .expect("start QEMU");
    let _guard = Guard(qemu);
    let deadline = Instant::now() + Duration::from_secs(20);
    let pts = loop {
        let text =
            String::from_utf8_lossy(&std::fs::read(&stdout_path).unwrap_or_default()).into_owned();
        if let Some(at) = text.find("/dev/pts/") {
            let digits: String = text[at + 9..]
                .chars()
                .take_while(|c| c.is_ascii_digit())
                .collect();
            if !digits.is_empty() {
                break format!("/dev/pts/{digits}");
            }
        }
        assert!(
            Instant::now() < deadline,
            "QEMU did not report its pty: {text}"
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    let out = host_sim(&[
        "stream",
        "--port",
        &pts,
        "--baud",
        "115200",
        log.to_str().unwrap(),
        "--out",
        streamed.to_str().unwrap(),
    ]);
    println!("{out}");
    assert_eq!(
        std::fs::read(&est).unwrap(),
        std::fs::read(&streamed).unwrap(),
        "estimates over the serial port differ"
    );
    let line = out.lines().last().unwrap();
    assert!(
        line.starts_with("step cost: max ") && line.contains(" cycles"),
        "{line}"
    );

    // The board still runs and holds the first stream's state.
    let again = Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args([
            "stream",
            "--port",
            &pts,
            log.to_str().unwrap(),
            "--out",
            dir.join("again.csv").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("already holds an estimator state (1200 samples accepted"),
        "{stderr}"
    );
    let reset = dir.join("reset.csv");
    let out = host_sim(&[
        "stream",
        "--port",
        &pts,
        "--reset",
        log.to_str().unwrap(),
        "--out",
        reset.to_str().unwrap(),
    ]);
    assert!(
        out.contains("reset the firmware: it forgot 1200 samples accepted"),
        "{out}"
    );
    assert_eq!(
        std::fs::read(&est).unwrap(),
        std::fs::read(&reset).unwrap(),
        "estimates after --reset differ"
    );
}
