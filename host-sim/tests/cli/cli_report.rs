//! `--report DIR` on `estimate`, `run` and `monte-carlo` (the QEMU stream's in `qemu_report.rs`):
//! the plots and one self-contained `report.html` that says what was learned and how the run
//! went, checked in a real headless browser (Debian's `chromium`, or $CHROMIUM; skipped with a
//! message where none is installed): every figure decodes from the page alone, copied away from
//! its PNGs.

use crate::common::{host_sim, host_sim_ok, path_str, temp_dir};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a headless browser saw of a page once loaded.
#[derive(Debug, PartialEq)]
struct Seen {
    images: usize,
    decoded: usize,
    tables: usize,
    title: String,
}

/// The browser to check pages with: $CHROMIUM, or `chromium` / `chromium-browser` on the PATH.
fn browser() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("CHROMIUM") {
        return Some(PathBuf::from(p));
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| ["chromium", "chromium-browser"].map(|n| d.join(n)))
        .find(|p| p.is_file())
}

/// Loads a copy of `page`, alone in a fresh directory (so only what the page embeds can load),
/// in a headless browser with a script that records how many images decoded; `None` without a
/// browser.
fn open_in_browser(page: &Path, scratch: &Path) -> Option<Seen> {
    let Some(chromium) = browser() else {
        eprintln!("skipped: no chromium installed (apt-get install chromium, or set CHROMIUM) to check {} in a browser", page.display());
        return None;
    };
    let alone = scratch.join("alone");
    std::fs::create_dir_all(&alone).unwrap();
    let script = "<script>window.addEventListener('load',()=>{const i=[...document.images];document.body.setAttribute('data-check',\
        [i.length,i.filter(x=>x.complete&&x.naturalWidth>0).length,document.querySelectorAll('table').length].join(' '));});</script>";
    let html = std::fs::read_to_string(page)
        .unwrap()
        .replace("</body>", &format!("{script}</body>"));
    let copy = alone.join("report.html");
    std::fs::write(&copy, &html).unwrap();
    // A browser that cannot load a one-line page says nothing about ours (seen on a fresh machine
    // whose chromium printed an empty DOM): the check is skipped, with what the browser said.
    let probe = scratch.join("probe.html");
    std::fs::write(&probe, "<html><body data-check=\"1 1 0\"></body></html>").unwrap();
    let (dom, stderr) = dump_dom(&chromium, &probe, &scratch.join("probe"));
    if !dom.contains("data-check=\"1 1 0\"") {
        eprintln!("skipped: {} cannot load a one-line page here, so {} is not checked in it; it printed {dom:?} and said: {stderr:.2000}", chromium.display(), page.display());
        return None;
    }
    let (dom, stderr) = dump_dom(&chromium, &copy, &scratch.join("page"));
    let check = dom
        .split("data-check=\"")
        .nth(1)
        .and_then(|r| r.split('"').next())
        .unwrap_or_else(|| {
            panic!("the page did not load: {dom:.500}\nchromium said: {stderr:.2000}")
        });
    let n: Vec<usize> = check.split(' ').map(|v| v.parse().unwrap()).collect();
    let title = dom
        .split("<title>")
        .nth(1)
        .and_then(|r| r.split("</title>").next())
        .unwrap_or_default()
        .to_string();
    Some(Seen {
        images: n[0],
        decoded: n[1],
        tables: n[2],
        title,
    })
}

/// Runs headless `chromium` on `page` and returns the DOM it dumped once loaded and what it
/// printed on stderr. Everything the browser writes (profile, sockets, crash reports) stays in
/// `scratch`.
fn dump_dom(chromium: &Path, page: &Path, scratch: &Path) -> (String, String) {
    let home = scratch.join("home");
    // Chromium puts its singleton socket in $TMPDIR, and a Unix socket's path must fit in 108
    // bytes: under a deep checkout the scratch directory's is too long (Chromium then aborts
    // without a word), so its temporary files go to a short directory of their own, removed after.
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = std::env::temp_dir().join(format!("hs-chromium-{}-{run}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut child = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--disable-breakpad",
            "--disable-crash-reporter",
            "--virtual-time-budget=10000",
        ])
        .arg(format!(
            "--user-data-dir={}",
            scratch.join("profile").display()
        ))
        .env("HOME", &home)
        .env("XDG_CONFIG_HOME", home.join(".config"))
        .env("XDG_CACHE_HOME", home.join(".cache"))
        .env("TMPDIR", &tmp)
        .arg("--dump-dom")
        .arg(format!("file://{}", page.display()))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // The DOM (megabytes of embedded images) and the messages are read as they come, so that
    // neither pipe ever fills.
    let mut stdout = child.stdout.take().unwrap();
    let mut stderr = child.stderr.take().unwrap();
    let out = std::thread::spawn(move || {
        let mut dom = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut dom).map(|_| dom)
    });
    let err = std::thread::spawn(move || {
        let mut said = Vec::new();
        std::io::Read::read_to_end(&mut stderr, &mut said).map(|_| said)
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(120) {
            let _ = child.kill();
            let _ = child.wait();
            panic!("chromium did not finish in 120 s");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let dom = String::from_utf8_lossy(&out.join().unwrap().unwrap()).into_owned();
    let said = String::from_utf8_lossy(&err.join().unwrap().unwrap()).into_owned();
    let _ = std::fs::remove_dir_all(&tmp);
    (dom, format!("({status}) {said}"))
}

/// What every report page holds: the figures embedded and nothing loaded from elsewhere.
fn check_page(page: &Path, figures: usize, needles: &[&str]) -> String {
    let html = std::fs::read_to_string(page).unwrap();
    assert_eq!(
        html.matches("<img ").count(),
        figures,
        "figures in {}",
        page.display()
    );
    assert_eq!(
        html.matches("src=\"data:image/png;base64,").count(),
        figures,
        "every figure embedded"
    );
    assert!(
        !html.contains("<script")
            && !html.contains("http:")
            && !html.contains("https:")
            && !html.contains("src=\"file"),
        "self-contained"
    );
    assert!(
        html.contains(&format!("host-sim {}", env!("CARGO_PKG_VERSION"))),
        "the version"
    );
    for needle in needles {
        assert!(html.contains(needle), "{needle:?} in {}", page.display());
    }
    html
}

fn png_names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    v.sort();
    v
}

#[test]
fn estimate_report_of_a_log_with_and_without_truth_reads_in_a_browser() {
    let dir = temp_dir("cli-report-estimate");
    let log = dir.join("trial.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "sea",
        "--duration",
        "6000",
        "--drop-fraction",
        "0.01",
        "--outages",
        "1",
        "--time-offset",
        "1700000000",
        "--out",
        path_str(&log),
    ]);
    let report = dir.join("report");
    let stdout = host_sim_ok(&["estimate", path_str(&log), "--report", path_str(&report)]);
    assert!(
        stdout.contains(&format!(
            "report in {}",
            report.join("report.html").display()
        )),
        "{stdout}"
    );
    assert_eq!(
        png_names(&report),
        [
            "attitude.png",
            "error.png",
            "estimates.png",
            "residuals.png",
            "status.png"
        ]
    );
    let html = check_page(
        &report.join("report.html"),
        5,
        &[
            "host-sim estimate",
            "--report",
            // What was learned, and the times as dates (Unix stamps).
            "<dt>sample interval</dt><dd>1 s</dd>",
            "<dt>rotation period</dt><dd>480 s</dd>",
            "<dt>rotation pattern</dt><dd>one-way</dd>",
            "2023-11-14T22:13:20.000Z",
            "Accuracy against the truth",
            "1-sigma honesty, ",
            "window restarts",
            "samples lost before this row",
            "status detecting_pattern -&gt; warming_up",
        ],
    );
    assert!(
        html.contains("<dt>final status</dt><dd>converged</dd>"),
        "the final status"
    );
    if let Some(seen) = open_in_browser(&report.join("report.html"), &dir.join("browser")) {
        assert_eq!(
            seen,
            Seen {
                images: 5,
                decoded: 5,
                tables: seen.tables,
                title: format!("RINS installation errors: {}", log.display())
            }
        );
        assert!(
            seen.tables >= 4,
            "estimate, accuracy, RMS and events tables: {seen:?}"
        );
    }

    // Without the truth file: no error plot, the attitude plot says what it shows instead.
    std::fs::remove_file(dir.join("trial.truth.json")).unwrap();
    let bare = dir.join("bare");
    host_sim_ok(&[
        "estimate",
        path_str(&log),
        "--out",
        path_str(&dir.join("e.csv")),
        "--report",
        path_str(&bare),
    ]);
    assert_eq!(
        png_names(&bare),
        [
            "attitude.png",
            "estimates.png",
            "residuals.png",
            "status.png"
        ]
    );
    let html = check_page(
        &bare.join("report.html"),
        4,
        &["No truth file: the attitude error itself is unknown"],
    );
    assert!(!html.contains("Accuracy against the truth"));
}

#[test]
fn a_log_without_an_estimate_still_gets_its_report_and_status_4() {
    let dir = temp_dir("cli-report-none");
    let log = dir.join("short.csv");
    host_sim_ok(&[
        "generate",
        "--scenario",
        "paper",
        "--duration",
        "300",
        "--out",
        path_str(&log),
    ]);
    let report = dir.join("report");
    let out = host_sim(&["estimate", path_str(&log), "--report", path_str(&report)]);
    assert_eq!(
        out.status.code(),
        Some(4),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    check_page(
        &report.join("report.html"),
        2,
        &[
            "No estimate: rotation period not yet detected.",
            "<dt>final status</dt><dd>detecting_pattern</dd>",
        ],
    );
}

#[test]
fn run_report_holds_our_method_and_the_papers_figures() {
    let dir = temp_dir("cli-report-run");
    let report = dir.join("report");
    host_sim_ok(&[
        "run",
        "--scenario",
        "paper",
        "--duration",
        "3000",
        "--no-plots",
        "--out-dir",
        path_str(&dir.join("out")),
        "--report",
        path_str(&report),
    ]);
    assert!(
        png_names(&dir.join("out")).is_empty(),
        "--no-plots: none in the output directory"
    );
    let pngs = png_names(&report);
    for name in [
        "estimates.png",
        "fig3_correlation.png",
        "fig4_percent_error_paper.png",
        "fig7_attitude_error_before.png",
        "fig8_attitude_error_after_windowed_zoom.png",
    ] {
        assert!(pngs.iter().any(|p| p == name), "{name} in {pngs:?}");
    }
    check_page(
        &report.join("report.html"),
        pngs.len(),
        &[
            "The three methods side by side",
            "| paper (literal) |",
            "the paper's Fig. 8",
        ],
    );
}

#[test]
fn monte_carlo_report_and_json_name_the_study() {
    let dir = temp_dir("cli-report-mc");
    let (report, json) = (dir.join("report"), dir.join("mc.json"));
    host_sim_ok(&[
        "monte-carlo",
        "--scenario",
        "paper",
        "--runs",
        "3",
        "--duration",
        "5000",
        "--seed",
        "7",
        "--threads",
        "1",
        "--out",
        path_str(&json),
        "--report",
        path_str(&report),
    ]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        (
            v["scenario"].as_str(),
            v["method"].as_str(),
            v["master_seed"].as_u64()
        ),
        (Some("paper"), Some("windowed"), Some(7))
    );
    assert_eq!(v["run_seeds"].as_array().map(Vec::len), Some(3));
    assert!(
        v["command"]
            .as_str()
            .unwrap()
            .contains("monte-carlo --scenario paper --runs 3"),
        "{}",
        v["command"]
    );
    assert_eq!(
        v["times_s"],
        serde_json::json!([2000.0, 5000.0]),
        "the table's times, as before"
    );
    assert!(
        v["over_time"]["times_s"].as_array().unwrap().len() >= 80,
        "the statistics over time"
    );
    assert_eq!(png_names(&report), ["monte_carlo.png"]);
    check_page(
        &report.join("report.html"),
        1,
        &["<dt>master seed</dt><dd>7</dd>", "| 5000 | median |"],
    );
}
