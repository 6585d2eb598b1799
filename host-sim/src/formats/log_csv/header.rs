//! The header of a log: the first line that carries data, the separator it is split by, and the
//! columns matched by name.

use super::{COLUMNS, SEPARATORS};
use crate::formats::time_stamps::TimeColumn;
use std::io::Read;

/// How many bytes at most are looked at for the header line, to choose the separator.
const HEADER_SCAN_BYTES: usize = 1 << 16;

/// Reads the start of `reader` up to the first line that is neither blank nor a comment (or
/// [`HEADER_SCAN_BYTES`], or the end), and picks the separator from that line ([`separator_of`]).
/// Returns the separator and the bytes read, which go back in front of the rest.
pub(super) fn scan_header<R: Read>(reader: &mut R) -> std::io::Result<(u8, Vec<u8>)> {
    let mut head = Vec::new();
    let mut chunk = [0u8; 4096];
    loop {
        if let Some(line) = header_line(&head) {
            return Ok((separator_of(line), head));
        }
        if head.len() >= HEADER_SCAN_BYTES {
            return Ok((b',', head));
        }
        let n = match reader.read(&mut chunk) {
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if n == 0 {
            // The whole input is shorter: its last line may be the header, without a line end.
            let line = head
                .split(|b| *b == b'\n')
                .map(trim_line)
                .find(|l| is_content(l))
                .unwrap_or(&[]);
            return Ok((separator_of(line), head));
        }
        head.extend_from_slice(&chunk[..n]);
    }
}

/// A line without its byte-order mark, `\r` and surrounding spaces.
fn trim_line(line: &[u8]) -> &[u8] {
    let line = line.strip_prefix("\u{feff}".as_bytes()).unwrap_or(line);
    line.trim_ascii()
}

/// Whether a (trimmed) line carries data: not blank, not a `#` comment.
fn is_content(line: &[u8]) -> bool {
    !line.is_empty() && line[0] != b'#'
}

/// The first complete line of `head` that carries data, if `head` holds one.
fn header_line(head: &[u8]) -> Option<&[u8]> {
    let mut lines = head.split(|b| *b == b'\n');
    // The last piece has no line end yet: it may be incomplete.
    let complete = head.iter().filter(|b| **b == b'\n').count();
    lines
        .by_ref()
        .take(complete)
        .map(trim_line)
        .find(|l| is_content(l))
}

/// The separator of [`SEPARATORS`] that occurs most often in `line` outside double quotes (`,` on
/// a tie or when none occurs).
pub fn separator_of(line: &[u8]) -> u8 {
    let mut counts = [0usize; SEPARATORS.len()];
    let mut quoted = false;
    for &b in line {
        if b == b'"' {
            quoted = !quoted;
        } else if !quoted {
            if let Some(i) = SEPARATORS.iter().position(|s| *s == b) {
                counts[i] += 1;
            }
        }
    }
    let best =
        (0..SEPARATORS.len()).fold(0, |best, i| if counts[i] > counts[best] { i } else { best });
    SEPARATORS[best]
}

/// A header name as it is matched: trimmed, without a byte-order mark, lower case, every run of
/// spaces and underscores one underscore (`Time S`, `TIME_S` and `time  s` are `time_s`).
pub fn normalize_column_name(name: &str) -> String {
    let name = name.trim_start_matches('\u{feff}').trim().to_lowercase();
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        if c == ' ' || c == '_' {
            if !out.ends_with('_') {
                out.push('_');
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// Where the seven values of a row are: the time column and its kind, then the six angles'
/// columns in [`COLUMNS`] order; and the names as the header writes them.
#[derive(Clone, Debug)]
pub(super) struct Layout {
    /// The time column's kind.
    pub(super) time: TimeColumn,
    /// Where the time and the six angles are, in [`COLUMNS`] order.
    pub(super) index: [usize; 7],
    /// Their names as the header writes them.
    pub(super) names: [String; 7],
}

impl Layout {
    /// Finds every column in a header (see [`normalize_column_name`]).
    pub(super) fn of(header: &[String]) -> Result<Layout, String> {
        let normalized: Vec<String> = header.iter().map(|n| normalize_column_name(n)).collect();
        let find = |want: &str| -> Result<Option<usize>, String> {
            let mut found = normalized
                .iter()
                .enumerate()
                .filter(|(_, n)| *n == want)
                .map(|(i, _)| i);
            match (found.next(), found.next()) {
                (Some(_), Some(_)) => Err(format!("column {want:?} appears twice in the header")),
                (first, _) => Ok(first),
            }
        };
        let mut time = None;
        for column in TimeColumn::ALL {
            if let Some(i) = find(column.name())? {
                time.get_or_insert((column, i));
            }
        }
        let missing = |want: &str| {
            let times: Vec<String> = TimeColumn::ALL
                .iter()
                .skip(1)
                .map(|c| format!("{:?}", c.name()))
                .collect();
            let or_time = if want == COLUMNS[0] {
                format!(" (or {})", times.join(", "))
            } else {
                String::new()
            };
            let header: Vec<&str> = header
                .iter()
                .map(|n| n.trim_start_matches('\u{feff}'))
                .collect();
            format!(
                "no column {want:?}{or_time} in the header {:?} (needs {})",
                header.join(","),
                COLUMNS.join(",")
            )
        };
        let Some((time, time_index)) = time else {
            return Err(missing(COLUMNS[0]));
        };
        let mut index = [time_index; 7];
        for (k, want) in COLUMNS.iter().enumerate().skip(1) {
            index[k] = find(want)?.ok_or_else(|| missing(want))?;
        }
        let names = index.map(|i| header[i].trim_start_matches('\u{feff}').trim().to_string());
        Ok(Layout { time, index, names })
    }
}
