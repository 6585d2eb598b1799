//! `report.html`: one self-contained page (the PNG plots embedded as `data:` URIs, no script, no
//! external file, no network), made of sections of text, key-value lists, tables and figures.
//! Text is escaped with the `html-escape` crate; the page is written through a temporary file
//! beside its target ([`crate::formats::output_file`]).

use anyhow::Context;
use base64::Engine as _;
use html_escape::{encode_double_quoted_attribute as attr, encode_text as text};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A PNG of the report and what it shows.
#[derive(Clone, Debug, PartialEq)]
pub struct Figure {
    /// The PNG file, read and embedded when the page is made.
    pub path: PathBuf,
    /// What it shows, under it and as its alternative text.
    pub caption: String,
}

/// A part of a section.
#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    /// A paragraph of text.
    Paragraph(String),
    /// Preformatted text (a command line, a markdown table as printed).
    Code(String),
    /// Name-value pairs.
    Facts(Vec<(String, String)>),
    /// A table: its head and rows.
    Table {
        /// The head's cells.
        head: Vec<String>,
        /// The rows' cells.
        rows: Vec<Vec<String>>,
    },
    /// A figure, embedded.
    Figure(Figure),
}

/// A titled part of the page.
#[derive(Clone, Debug, PartialEq)]
pub struct Section {
    /// The section's heading.
    pub title: String,
    /// Its parts, in order.
    pub blocks: Vec<Block>,
}

impl Section {
    /// An empty section titled `title`.
    pub fn new(title: impl Into<String>) -> Section {
        Section {
            title: title.into(),
            blocks: vec![],
        }
    }

    /// The section with `block` added at its end.
    pub fn with(mut self, block: Block) -> Section {
        self.blocks.push(block);
        self
    }
}

/// The whole page.
#[derive(Clone, Debug, PartialEq)]
pub struct Page {
    /// The page's title and top heading.
    pub title: String,
    /// The command line that made it.
    pub command: String,
    /// Its sections, in order.
    pub sections: Vec<Section>,
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1060px;margin:1em auto;padding:0 1em;color:#222}\
h1{font-size:1.5em}h2{font-size:1.2em;border-bottom:1px solid #ccc;margin-top:1.6em}\
table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #bbb;padding:.2em .5em;text-align:right}\
th{background:#eee}td:first-child,th:first-child{text-align:left}dl{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}\
dt{font-weight:bold}dd{margin:0}pre{background:#f4f4f4;padding:.5em;overflow-x:auto}figure{margin:1em 0}\
img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.9em;color:#444}";

impl Page {
    /// The page as HTML, the figures read from their files and embedded.
    pub fn to_html(&self) -> anyhow::Result<String> {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n<h1>{}</h1>\n",
            text(&self.title),
            text(&self.title)
        );
        let _ = writeln!(
            h,
            "<p>Made by <code>host-sim {}</code> with:</p>\n<pre>{}</pre>",
            text(env!("CARGO_PKG_VERSION")),
            text(&self.command)
        );
        for section in &self.sections {
            let _ = writeln!(h, "<h2>{}</h2>", text(&section.title));
            for block in &section.blocks {
                write_block(&mut h, block)?;
            }
        }
        h.push_str("</body>\n</html>\n");
        Ok(h)
    }

    /// Writes the page to `path`.
    pub fn write(&self, path: &Path) -> anyhow::Result<()> {
        crate::formats::output_file::write_bytes(path, self.to_html()?.as_bytes())
    }
}

fn write_block(h: &mut String, block: &Block) -> anyhow::Result<()> {
    match block {
        Block::Paragraph(p) => {
            let _ = writeln!(h, "<p>{}</p>", text(p));
        }
        Block::Code(c) => {
            let _ = writeln!(h, "<pre>{}</pre>", text(c));
        }
        Block::Facts(facts) => {
            h.push_str("<dl>\n");
            for (k, v) in facts {
                let _ = writeln!(h, "<dt>{}</dt><dd>{}</dd>", text(k), text(v));
            }
            h.push_str("</dl>\n");
        }
        Block::Table { head, rows } => {
            h.push_str("<table>\n<tr>");
            for c in head {
                let _ = write!(h, "<th>{}</th>", text(c));
            }
            h.push_str("</tr>\n");
            for row in rows {
                h.push_str("<tr>");
                for c in row {
                    let _ = write!(h, "<td>{}</td>", text(c));
                }
                h.push_str("</tr>\n");
            }
            h.push_str("</table>\n");
        }
        Block::Figure(f) => {
            let png = std::fs::read(&f.path)
                .with_context(|| format!("{}:0: cannot read the plot", f.path.display()))?;
            let name = f
                .path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let _ = writeln!(
                h,
                "<figure id=\"{}\"><img alt=\"{}\" src=\"data:image/png;base64,{}\"><figcaption>{} ({})</figcaption></figure>",
                attr(&name),
                attr(&f.caption),
                base64::engine::general_purpose::STANDARD.encode(&png),
                text(&f.caption),
                text(&name)
            );
        }
    }
    Ok(())
}

/// The command line of this run, as a shell would take it back (arguments with spaces or quotes
/// quoted).
pub fn command_line() -> String {
    let quote = |a: String| {
        if !a.is_empty()
            && a.chars()
                .all(|c| c.is_ascii_alphanumeric() || "-_./,=:+".contains(c))
        {
            a
        } else {
            format!("'{}'", a.replace('\'', "'\\''"))
        }
    };
    let mut args = std::env::args();
    let program = args
        .next()
        .map(|p| {
            Path::new(&p)
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or(p)
        })
        .unwrap_or_default();
    std::iter::once(program)
        .chain(args.map(quote))
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_is_escaped_and_figures_embedded() {
        let dir = std::env::temp_dir().join(format!("host-sim-html-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = dir.join("a.png");
        std::fs::write(&png, [0x89, b'P', b'N', b'G']).unwrap();
        let page = Page {
            title: "Log <a&b>.csv".into(),
            command: "host-sim estimate '<x>.csv'".into(),
            sections: vec![Section::new("S")
                .with(Block::Facts(vec![("k".into(), "v<".into())]))
                .with(Block::Table {
                    head: vec!["h".into()],
                    rows: vec![vec!["1 & 2".into()]],
                })
                .with(Block::Figure(Figure {
                    path: png.clone(),
                    caption: "the \"plot\"".into(),
                }))],
        };
        let html = page.to_html().unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        assert!(
            html.contains("<h1>Log &lt;a&amp;b&gt;.csv</h1>")
                && html.contains("<dd>v&lt;</dd>")
                && html.contains("<td>1 &amp; 2</td>"),
            "{html}"
        );
        assert!(
            html.contains("src=\"data:image/png;base64,iVBORw==\"")
                && html.contains("alt=\"the &quot;plot&quot;\""),
            "{html}"
        );
        assert!(
            !html.contains("<script") && !html.contains("http"),
            "self-contained, no script: {html}"
        );
    }
}
