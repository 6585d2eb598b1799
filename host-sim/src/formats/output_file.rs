//! Outputs that fail safe.
//!
//! Every file the tool writes (estimates CSV, generated log and truth file, plots, report, Monte
//! Carlo summary) is written to a temporary file in the target's own directory (`.NAME.XXXXXX`,
//! through the `tempfile` crate), flushed to disk and renamed over the target only when it is
//! complete. A run that fails half-way leaves the earlier file as it was and no temporary file
//! behind (the temporary file is deleted when dropped). The rename is atomic on one file system,
//! so a reader sees the old file or the new one, never a part.
//!
//! A target that exists and is not a regular file (`/dev/null`, a named pipe, a terminal, the
//! `/dev/stdout` of a shell) is written to directly, as it is: renaming a file over it would
//! replace the device or the pipe with a file (as root, `/dev/null` itself).
//!
//! No input is ever an output: [`check_not_input`] refuses an output that is the log being read
//! or its truth file (the same file by device and inode when both exist, else the same path).

use anyhow::Context;
use std::fs::Permissions;
use std::io::{BufWriter, Write};
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use tempfile::NamedTempFile;

/// The name that stands for standard output.
pub const STDOUT: &str = "-";

/// Whether `target` exists and is not a regular file (a device, a named pipe, a socket): written
/// to directly, never replaced (see the module doc).
fn is_special(target: &Path) -> bool {
    std::fs::metadata(target).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

/// `target` opened for writing as it is (a device or a pipe: nothing created, nothing renamed).
fn open_special(target: &Path) -> anyhow::Result<std::fs::File> {
    std::fs::OpenOptions::new()
        .write(true)
        .open(target)
        .with_context(|| format!("{}:0: cannot write", target.display()))
}

/// A temporary file beside `target` (same directory, hidden name ending like the target's, so
/// that writers which go by the extension, as the PNG encoder does, see it).
pub(crate) fn temp_beside(target: &Path) -> anyhow::Result<NamedTempFile> {
    let dir = match target.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = target
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let suffix = Path::new(&name)
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    tempfile::Builder::new()
        .prefix(&format!(".{name}."))
        .suffix(&suffix)
        // As `File::create` makes files: 0666 less the umask (tempfile's own default is 0600).
        .permissions(Permissions::from_mode(0o666))
        .tempfile_in(dir)
        .with_context(|| {
            format!(
                "{}:0: cannot create a temporary file in {}",
                target.display(),
                dir.display()
            )
        })
}

/// Flushes a finished temporary file to disk and renames it over `target`.
pub(crate) fn persist(temp: NamedTempFile, target: &Path) -> anyhow::Result<()> {
    temp.as_file()
        .sync_all()
        .with_context(|| format!("{}:0: cannot write", target.display()))?;
    temp.persist(target)
        .map_err(|e| e.error)
        .with_context(|| format!("{}:0: cannot write", target.display()))?;
    Ok(())
}

/// Writes `target` through `write`, which is given the path of a temporary file beside it to
/// create and fill; renamed over `target` only if `write` succeeds.
pub fn write_via_temp(
    target: &Path,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    if is_special(target) {
        return write(target);
    }
    let temp = temp_beside(target)?;
    write(temp.path())?;
    persist(temp, target)
}

/// Writes `bytes` to `target` (see the module doc).
pub fn write_bytes(target: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    if is_special(target) {
        return open_special(target)?
            .write_all(bytes)
            .with_context(|| format!("{}:0: cannot write", target.display()));
    }
    let mut temp = temp_beside(target)?;
    temp.write_all(bytes)
        .with_context(|| format!("{}:0: cannot write", target.display()))?;
    persist(temp, target)
}

enum Sink {
    Stdout(BufWriter<std::io::StdoutLock<'static>>),
    File(BufWriter<NamedTempFile>),
    /// A device or a pipe, written as it is.
    Special(BufWriter<std::fs::File>),
}

/// An output written as it goes: standard output for `-`, else a temporary file beside the
/// target that [`OutputFile::commit`] renames over it (dropped uncommitted, it is deleted).
pub struct OutputFile {
    target: PathBuf,
    sink: Sink,
}

impl OutputFile {
    /// Opens the output; `-` is standard output.
    pub fn create(target: &Path) -> anyhow::Result<OutputFile> {
        let sink = if target.as_os_str() == STDOUT {
            Sink::Stdout(BufWriter::with_capacity(1 << 16, std::io::stdout().lock()))
        } else if is_special(target) {
            Sink::Special(BufWriter::with_capacity(1 << 16, open_special(target)?))
        } else {
            Sink::File(BufWriter::with_capacity(1 << 16, temp_beside(target)?))
        };
        Ok(OutputFile {
            target: target.to_path_buf(),
            sink,
        })
    }

    /// The output is complete: flushed, and the file renamed over the target.
    pub fn commit(self) -> anyhow::Result<()> {
        let target = self.target;
        match self.sink {
            Sink::Stdout(mut w) => w
                .flush()
                .with_context(|| "standard output: cannot write".to_string()),
            Sink::Special(mut w) => w
                .flush()
                .with_context(|| format!("{}:0: cannot write", target.display())),
            Sink::File(w) => {
                let temp = w
                    .into_inner()
                    .map_err(|e| e.into_error())
                    .with_context(|| format!("{}:0: cannot write", target.display()))?;
                persist(temp, &target)
            }
        }
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match &mut self.sink {
            Sink::Stdout(w) => w.write(buf),
            Sink::File(w) => w.write(buf),
            Sink::Special(w) => w.write(buf),
        }
    }

    fn write_all(&mut self, buf: &[u8]) -> std::io::Result<()> {
        match &mut self.sink {
            Sink::Stdout(w) => w.write_all(buf),
            Sink::File(w) => w.write_all(buf),
            Sink::Special(w) => w.write_all(buf),
        }
    }

    fn flush(&mut self) -> std::io::Result<()> {
        match &mut self.sink {
            Sink::Stdout(w) => w.flush(),
            Sink::File(w) => w.flush(),
            Sink::Special(w) => w.flush(),
        }
    }
}

/// An input of a run and what it is, for [`check_not_input`]'s message.
#[derive(Clone, Debug)]
pub struct Input {
    /// The input's path.
    pub path: PathBuf,
    /// E.g. `the log itself`, `the log's truth file`.
    pub what: &'static str,
}

/// `path` made absolute with its directory resolved (symbolic links followed), when that exists.
fn resolved(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    Some(std::fs::canonicalize(dir).ok()?.join(name))
}

/// Whether two paths name the same file: by device and inode when both exist, else by their
/// resolved paths.
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => resolved(a).is_some_and(|r| Some(r) == resolved(b)),
    }
}

/// Refuses an output that is one of the run's inputs; `option` names how it was given (`--out`,
/// `--report`).
pub fn check_not_input(output: &Path, option: &str, inputs: &[Input]) -> anyhow::Result<()> {
    if output.as_os_str() == STDOUT {
        return Ok(());
    }
    for input in inputs {
        if input.path.as_os_str() != STDOUT && same_file(output, &input.path) {
            anyhow::bail!(
                "{}:0: {option} names {}; it is an input of this run and is never overwritten",
                output.display(),
                input.what
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("host-sim-output-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn listing(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn an_uncommitted_output_leaves_the_earlier_file_and_no_temporary_file() {
        let d = dir("uncommitted");
        let target = d.join("e.csv");
        std::fs::write(&target, "earlier\n").unwrap();
        let mut out = OutputFile::create(&target).unwrap();
        out.write_all(b"half a run").unwrap();
        assert_eq!(
            listing(&d).len(),
            2,
            "the temporary file sits beside the target"
        );
        drop(out);
        let (kept, files) = (std::fs::read_to_string(&target).unwrap(), listing(&d));
        let mut out = OutputFile::create(&target).unwrap();
        out.write_all(b"new\n").unwrap();
        out.commit().unwrap();
        let (new, after) = (std::fs::read_to_string(&target).unwrap(), listing(&d));
        let _ = std::fs::remove_dir_all(&d);
        assert_eq!(
            (kept.as_str(), files),
            ("earlier\n", vec!["e.csv".to_string()])
        );
        assert_eq!((new.as_str(), after), ("new\n", vec!["e.csv".to_string()]));
    }

    #[test]
    fn a_failed_writer_leaves_the_target_untouched() {
        let d = dir("failed");
        let target = d.join("plot.png");
        let mut seen = PathBuf::new();
        let failed = write_via_temp(&target, |p| {
            seen = p.to_path_buf();
            std::fs::write(p, b"partial")?;
            anyhow::bail!("drawing failed")
        });
        let files = listing(&d);
        write_bytes(&target, b"png").unwrap();
        let written = std::fs::read(&target).unwrap();
        let mode = std::fs::metadata(&target).unwrap().permissions().mode();
        let _ = std::fs::remove_dir_all(&d);
        assert!(failed.is_err() && files.is_empty(), "{files:?}");
        assert!(
            seen.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with(".plot.png.")
                && seen.extension().unwrap() == "png",
            "{seen:?}"
        );
        assert_eq!(written, b"png");
        assert_ne!(
            mode & 0o044,
            0,
            "readable by others as File::create makes files (umask permitting): {mode:o}"
        );
    }

    #[test]
    fn an_input_is_never_an_output() {
        let d = dir("inputs");
        let log = d.join("trial.csv");
        std::fs::write(&log, "x").unwrap();
        let inputs = [
            Input {
                path: log.clone(),
                what: "the log itself",
            },
            Input {
                path: d.join("trial.truth.json"),
                what: "the log's truth file",
            },
        ];
        let same = check_not_input(&d.join(".").join("trial.csv"), "--out", &inputs)
            .unwrap_err()
            .to_string();
        let truth = check_not_input(&d.join("trial.truth.json"), "--out", &inputs)
            .unwrap_err()
            .to_string();
        let other = check_not_input(&d.join("trial.estimates.csv"), "--out", &inputs);
        let _ = std::fs::remove_dir_all(&d);
        assert!(same.contains("--out names the log itself"), "{same}");
        assert!(
            truth.contains("--out names the log's truth file"),
            "a truth file that does not exist yet is still the log's: {truth}"
        );
        assert!(other.is_ok());
        assert!(check_not_input(Path::new("-"), "--out", &inputs).is_ok());
    }
}
