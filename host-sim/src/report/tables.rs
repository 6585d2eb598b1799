//! The report in text, as the commands print it and the pages show it: the accuracy table, the
//! honesty line, the attitude RMS tables, the methods side by side.

use crate::report::accuracy::Accuracy;
use crate::report::attitude_rms::AttitudeRms;
use crate::report::honesty::{Honesty, SigmaRatio};
use crate::report::Report;
use estimator_core::Method;
use std::io::Write;

/// Label of a method in reports.
pub fn method_label(m: Method) -> &'static str {
    match m {
        Method::Windowed => "ours (windowed)",
        Method::Paper => "paper (literal)",
        Method::Traditional => "traditional",
    }
}

/// `n` with its thousands separated by commas (`19,401`).
pub fn thousands(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `1 row`, `19,401 rows`.
pub fn rows_text(n: u64) -> String {
    if n == 1 {
        "1 row".into()
    } else {
        format!("{} rows", thousands(n))
    }
}

/// A time in whole seconds with its thousands separated (`2,940 s`).
fn seconds(t: f64) -> String {
    if t.is_finite() && t >= 0.0 {
        format!("{} s", thousands(t.round() as u64))
    } else {
        format!("{t:.0} s")
    }
}

/// A share of rows in percent, with as many decimals as a share above 0 needs to show (`0.3 %`,
/// `0.01 %`); exactly `0 %` for none and `100 %` for all.
pub fn percent_of_rows(count: u64, rows: u64) -> String {
    if rows == 0 {
        return "-".into();
    }
    if count == 0 {
        return "0 %".into();
    }
    if count == rows {
        return "100 %".into();
    }
    let p = 100.0 * count as f64 / rows as f64;
    let decimals = (-p.log10()).ceil().max(1.0) as usize;
    format!("{p:.decimals$} %")
}

/// `3.4 (x3 at 2,940 s)`: the largest |error| / 1-sigma and where (with the run, over runs).
pub fn format_largest(l: &SigmaRatio) -> String {
    let run = l.run.map_or(String::new(), |r| format!("run {r}: "));
    format!(
        "{:.1} ({run}x{} at {})",
        l.ratio,
        l.error,
        seconds(l.time_s)
    )
}

/// The shares beyond 2, 3 and 5 sigma and the largest ratio:
/// `some error beyond 2 sigma on 0.3 %, beyond 3 sigma on 0.01 %, beyond 5 sigma on 0 %; largest
/// |error|/sigma 3.4 (x3 at 2,940 s)`.
pub fn format_honesty_shares(h: &Honesty) -> String {
    let mut s = format!(
        "some error beyond 2 sigma on {}, beyond 3 sigma on {}, beyond 5 sigma on {}",
        percent_of_rows(h.beyond_2_sigma_rows, h.rows),
        percent_of_rows(h.beyond_3_sigma_rows, h.rows),
        percent_of_rows(h.beyond_5_sigma_rows, h.rows),
    );
    if let Some(l) = &h.largest {
        s.push_str(&format!("; largest |error|/sigma {}", format_largest(l)));
    }
    s
}

/// The honesty line of one run (with a line more for rows left out or without an estimate).
pub fn format_honesty(h: &Honesty) -> String {
    if h.rows == 0 {
        return "1-sigma honesty: no row with an estimate to judge\n".into();
    }
    let mut s = format!(
        "1-sigma honesty, {} from the first estimate: {}\n",
        rows_text(h.rows),
        format_honesty_shares(h)
    );
    let mut notes = Vec::new();
    if let (Some([from_s, to_s]), true) = (h.left_out_s, h.rows_left_out > 0) {
        let why = match h.declared_at_s {
            Some(d) => format!("2,000 s after errors_changed at {}", seconds(d)),
            None => "never declared: 2,000 s after the change".to_string(),
        };
        notes.push(format!(
            "{} of the change of the errors left out ({} to {}: {why})",
            rows_text(h.rows_left_out),
            seconds(from_s),
            seconds(to_s),
        ));
    }
    if h.rows_without_estimate > 0 {
        notes.push(format!(
            "{} after the first estimate without one, not judged",
            rows_text(h.rows_without_estimate)
        ));
    }
    if !notes.is_empty() {
        s.push_str(&format!("  {}\n", notes.join("; ")));
    }
    s
}

fn fmt_time(t: Option<f64>) -> String {
    t.map(|t| format!("{t:.0} s"))
        .unwrap_or_else(|| "not within at end".to_string())
}

/// A table's head and rows, as text cells.
pub type Table = (Vec<String>, Vec<Vec<String>>);

/// A table as markdown, one line a row, cells followed by ` | ` as the tool prints them.
pub fn markdown(head: &[String], rows: &[Vec<String>]) -> String {
    let line = |cells: &[String]| format!("| {} |\n", cells.join(" | "));
    let mut s = line(head);
    s.push('|');
    s.push_str(&"---|".repeat(head.len()));
    s.push('\n');
    for r in rows {
        s.push_str(&line(r));
    }
    s
}

/// The accuracy table: per error, the percentage and absolute error at each report time and the
/// settling times.
pub fn accuracy_table(a: &Accuracy) -> Table {
    let mut head = vec!["x".to_string()];
    head.extend(
        a.points
            .iter()
            .map(|p| format!("{:.0} s: % / arcsec", p.time_s)),
    );
    head.push("within 0.5 % from".into());
    head.push("within 10 arcsec from".into());
    let rows = (0..4)
        .map(|i| {
            let mut row = vec![format!("x{}", i + 1)];
            for p in &a.points {
                row.push(match (p.percent, p.error_arcsec) {
                    (Some(pc), Some(e)) => match pc[i] {
                        Some(p) => format!("{p:.3} % / {:.2}", e[i].abs()),
                        None => format!("- / {:.2}", e[i].abs()),
                    },
                    _ => "no estimate".to_string(),
                });
            }
            row.push(fmt_time(a.within_percent_from_s[i]));
            row.push(fmt_time(a.within_arcsec_from_s[i]));
            row
        })
        .collect();
    (head, rows)
}

/// The accuracy table as text (markdown).
pub fn format_accuracy(a: &Accuracy) -> String {
    let (head, rows) = accuracy_table(a);
    markdown(&head, &rows)
}

/// The title of an attitude RMS table.
pub fn rms_title(label: &str, r: &AttitudeRms) -> String {
    format!(
        "attitude error of eq (2), RMS arcsec, {label} ({:.0}-{:.0} s, {} rows)",
        r.from_s, r.to_s, r.rows
    )
}

/// The attitude RMS table: before and after compensation, per axis.
pub fn rms_table(r: &AttitudeRms) -> Table {
    let head = ["", "heading", "roll", "pitch"].map(String::from).to_vec();
    let row = |name: &str, v: &[f64; 3]| {
        vec![
            name.to_string(),
            format!("{:.2}", v[0]),
            format!("{:.2}", v[1]),
            format!("{:.2}", v[2]),
        ]
    };
    (
        head,
        vec![
            row("before compensation", &r.before_arcsec),
            row("after compensation", &r.after_arcsec),
        ],
    )
}

/// The attitude RMS table as text (markdown).
pub fn format_rms(label: &str, r: &AttitudeRms) -> String {
    let (head, rows) = rms_table(r);
    format!("{}:\n{}", rms_title(label, r), markdown(&head, &rows))
}

/// Methods side by side (one line each): largest percentage error of the four at each report
/// time, settling times of all four, attitude RMS after compensation over the last quarter.
pub fn format_side_by_side(reports: &[(&str, &Report)]) -> String {
    let times: Vec<f64> = reports
        .first()
        .map(|(_, r)| r.accuracy.points.iter().map(|p| p.time_s).collect())
        .unwrap_or_default();
    let mut s = String::from("| method | ");
    for t in &times {
        s.push_str(&format!("max % at {t:.0} s | "));
    }
    s.push_str("all within 0.5 % from | all within 10 arcsec from | RMS after, last quarter (heading / roll / pitch arcsec) |\n|---|");
    s.push_str(&"---|".repeat(times.len() + 3));
    s.push('\n');
    for (name, r) in reports {
        s.push_str(&format!("| {name} | "));
        for p in &r.accuracy.points {
            match p.percent {
                Some(pc) => s.push_str(&format!(
                    "{:.3} | ",
                    pc.iter().flatten().fold(0.0f64, |m, v| m.max(*v))
                )),
                None => s.push_str("no estimate | "),
            }
        }
        let rms = r.rms_last_quarter.map_or("-".to_string(), |q| {
            let q = q.after_arcsec;
            format!("{:.2} / {:.2} / {:.2}", q[0], q[1], q[2])
        });
        s.push_str(&format!(
            "{} | {} | {rms} |\n",
            fmt_time(r.accuracy.all_within_percent_from_s()),
            fmt_time(r.accuracy.all_within_arcsec_from_s()),
        ));
    }
    s
}

/// The accuracy of a replay with `method` against the truth as `estimate` and `run` print it:
/// the table, the honesty of the 1-sigma and the attitude error's RMS.
pub fn write_report(w: &mut dyn Write, method: Method, rep: &Report) -> std::io::Result<()> {
    writeln!(w, "\naccuracy against the truth, {}:", method_label(method))?;
    write!(w, "{}", format_accuracy(&rep.accuracy))?;
    write!(w, "{}", format_honesty(&rep.accuracy.honesty))?;
    if let Some(r) = &rep.rms_from_first_estimate {
        write!(w, "{}", format_rms("from the first estimate", r))?;
    }
    if let Some(r) = &rep.rms_last_quarter {
        write!(w, "{}", format_rms("last quarter of the run", r))?;
    }
    Ok(())
}
