//! `host-sim flash-life`: the firmware's own checkpoint store on a model of the board's flash. On
//! the STM32F405's layout with the default settings, eight days of samples wear every sector
//! alike, a save that only programs stalls the CPU within 50 ms typical and 250 ms worst (the
//! datasheet's program times), and the flash lasts at least 10 years at 10,000 cycles.

use crate::common::host_sim_ok;

/// The number before `unit` on the line starting with `prefix`.
fn number_before(out: &str, prefix: &str, unit: &str) -> f64 {
    let line = out
        .lines()
        .find(|l| l.starts_with(prefix))
        .unwrap_or_else(|| panic!("no `{prefix}` line in:\n{out}"));
    let at = line
        .find(unit)
        .unwrap_or_else(|| panic!("no `{unit}` in {line}"));
    line[..at]
        .split_whitespace()
        .last()
        .unwrap()
        .parse()
        .unwrap_or_else(|_| panic!("{line}"))
}

#[test]
fn stm32f405_default_settings_last_ten_years_and_spread_the_wear() {
    let out = host_sim_ok(&["flash-life", "--board", "stm32f405", "--days", "8"]);
    println!("{out}");
    assert!(out.contains("checkpoint: 900 bytes"), "{out}");
    let years = number_before(&out, "flash life:", "years at 10000 cycles");
    assert!(years >= 10.0, "{years} years");
    // Every sector erased, none more than once more than another.
    let line = out
        .lines()
        .find(|l| l.starts_with("erases per sector:"))
        .unwrap();
    let erases: Vec<u64> = line
        .split(", ")
        .map(|part| part.rsplit(' ').next().unwrap().parse().unwrap())
        .collect();
    assert_eq!(erases.len(), 7, "{line}");
    assert!(
        erases.iter().min().unwrap() >= &1
            && erases.iter().max().unwrap() - erases.iter().min().unwrap() <= 1,
        "{line}"
    );
    // A save that only programs: at most 50 ms typical, 250 ms worst.
    let stall = out
        .lines()
        .find(|l| l.starts_with("stall of a save"))
        .unwrap();
    let typical = number_before(stall, "stall of a save", "ms typical");
    let worst = number_before(stall, "stall of a save", "ms worst when it only programs");
    assert!(typical <= 50.0 && worst <= 250.0, "{stall}");
}

#[test]
fn mps2_an386_and_bad_settings() {
    let out = host_sim_ok(&["flash-life", "--board", "mps2-an386", "--days", "1"]);
    assert!(
        out.contains("checkpoint: 900 bytes") && out.contains("flash life:"),
        "{out}"
    );
    let years = number_before(&out, "flash life:", "years at 10000 cycles");
    assert!(years >= 10.0, "{years} years");
    for bad in [["--days", "-1"], ["--interval-s", "0"]] {
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_host-sim"))
            .args(["flash-life", "--board", "mps2-an386"])
            .args(bad)
            .output()
            .unwrap();
        assert!(!status.status.success(), "{bad:?} accepted");
        assert!(
            String::from_utf8_lossy(&status.stderr).contains(&bad[0][2..]),
            "{bad:?}: {}",
            String::from_utf8_lossy(&status.stderr)
        );
    }
}
