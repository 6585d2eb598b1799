//! `stream --report DIR` through QEMU (mps2-an386): the plots of the firmware's answers and a
//! self-contained `report.html`, whose final estimate is the one `estimate --report` reports for
//! the same log (the two replays are byte-identical, `qemu_e2e.rs`).

use crate::qemu_support::*;

#[test]
fn stream_report_shows_the_firmwares_answers() {
    require_qemu();
    let elf = firmware_elf(Board::Mps2An386);
    let dir = scratch("report-stream");
    let log = paper_log(&dir, 3000);
    let (streamed, replayed) = (dir.join("stream"), dir.join("estimate"));
    let stdout = host_sim(&[
        "stream",
        "--qemu",
        elf.to_str().unwrap(),
        log.to_str().unwrap(),
        "--out",
        dir.join("s.csv").to_str().unwrap(),
        "--report",
        streamed.to_str().unwrap(),
    ]);
    assert!(stdout.contains("report in "), "{stdout}");
    host_sim(&[
        "estimate",
        log.to_str().unwrap(),
        "--out",
        dir.join("e.csv").to_str().unwrap(),
        "--report",
        replayed.to_str().unwrap(),
    ]);
    let page = std::fs::read_to_string(streamed.join("report.html")).unwrap();
    for name in ["estimates.png", "error.png", "status.png", "attitude.png"] {
        assert!(streamed.join(name).is_file(), "{name}");
        assert!(
            page.contains(&format!("<figure id=\"{name}\"><img")),
            "{name} embedded"
        );
    }
    assert!(
        !streamed.join("residuals.png").exists(),
        "the firmware sends no residuals"
    );
    assert!(
        page.contains("streamed through") && page.contains("QEMU mps2-an386"),
        "{page:.2000}"
    );
    assert!(page.contains("Accuracy against the truth"));
    // The same final estimate table as the replay's.
    let table = |html: &str| {
        html.split("<h2>Final estimate</h2>")
            .nth(1)
            .and_then(|r| r.split("</table>").next())
            .map(String::from)
    };
    assert_eq!(
        table(&page),
        table(&std::fs::read_to_string(replayed.join("report.html")).unwrap())
    );
    assert!(table(&page).unwrap().contains("<td>x4</td>"));
}
