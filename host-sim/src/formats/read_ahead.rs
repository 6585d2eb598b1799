//! A log read on a thread of its own, a few batches of rows ahead of the work done with them.

use crate::formats::log_csv::{LogError, LogLine, LogReader};
use std::io::Read;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, SyncSender};
use std::sync::Arc;

/// Rows parsed ahead by [`read_ahead`]'s thread, per batch: a consumer that stops at the end of
/// a batch of this many items (or of a divisor of it) never waits on rows the reader has not yet
/// handed over.
pub const READ_AHEAD_BATCH: usize = 4096;

/// Batches that may wait in [`read_ahead`]'s channel.
pub const READ_AHEAD_DEPTH: usize = 4;

/// One item of a log, as [`LogReader`] gives it.
type LogItem = Result<LogLine, LogError>;

/// Runs `reader` on a thread of its own, a few batches of rows ahead of `consume`, which gets the
/// same items in the same order: parsing the CSV and the work done with its rows then share two
/// cores. At most [`READ_AHEAD_DEPTH`] batches of [`READ_AHEAD_BATCH`] rows wait at any time, so
/// memory does not grow with the log.
///
/// However `consume` ends (it read every item, returned early, or panicked), the reader ends too,
/// and this function does not wait on it longer than it must. When `consume` stops before the end
/// of the log, the channel is hung up and the reader told to stop, which it does before its next
/// row (at once if it is waiting to hand over a batch); it is not waited for, as it may be blocked
/// in a read that returns only when its writer writes or closes (standard input): it ends then, or
/// with the process. When `consume` read every item, the reader has hung up and is joined: a panic
/// in it is raised here, so that a log is never taken for complete because its reader died.
pub fn read_ahead<R, T>(
    reader: LogReader<R>,
    consume: impl FnOnce(&mut dyn Iterator<Item = LogItem>) -> T,
) -> T
where
    R: Read + Send + 'static,
{
    let (tx, rx) = std::sync::mpsc::sync_channel::<Vec<LogItem>>(READ_AHEAD_DEPTH);
    let stop = Arc::new(AtomicBool::new(false));
    let reader_stop = stop.clone();
    let handle = std::thread::spawn(move || read_batches(reader, &tx, &reader_stop));
    let mut items = Batches {
        rx,
        batch: Vec::new().into_iter(),
        stop,
        ended: false,
    };
    let result = consume(&mut items);
    let ended = items.ended;
    // Hangs up and tells the reader to stop (also done when `consume` panics: `items` is dropped
    // then too).
    drop(items);
    if ended {
        if let Err(panic) = handle.join() {
            std::panic::resume_unwind(panic);
        }
    }
    result
}

/// [`read_ahead`]'s thread: batches of rows into `tx` until the end of the log, a hang-up, or
/// `stop`.
fn read_batches<R: Read>(
    mut reader: LogReader<R>,
    tx: &SyncSender<Vec<LogItem>>,
    stop: &AtomicBool,
) {
    loop {
        let mut batch = Vec::with_capacity(READ_AHEAD_BATCH);
        let mut end = false;
        while batch.len() < READ_AHEAD_BATCH {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            match reader.next() {
                Some(item) => batch.push(item),
                None => {
                    end = true;
                    break;
                }
            }
        }
        // A send fails as soon as the consumer hangs up, even one waiting on a full channel.
        if !batch.is_empty() && tx.send(batch).is_err() {
            return;
        }
        if end {
            return;
        }
    }
}

/// The consumer's end of [`read_ahead`]: the items of the batches in order. Dropping it hangs up
/// and tells the reader to stop.
struct Batches {
    rx: Receiver<Vec<LogItem>>,
    batch: std::vec::IntoIter<LogItem>,
    stop: Arc<AtomicBool>,
    /// The reader hung up: every item was received.
    ended: bool,
}

impl Iterator for Batches {
    type Item = LogItem;

    fn next(&mut self) -> Option<LogItem> {
        loop {
            if let Some(item) = self.batch.next() {
                return Some(item);
            }
            if self.ended {
                return None;
            }
            match self.rx.recv() {
                Ok(batch) => self.batch = batch.into_iter(),
                Err(_) => self.ended = true,
            }
        }
    }
}

impl Drop for Batches {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::log_csv::HEADER;
    use std::path::Path;

    /// A log of `rows` rows at 1 s, every `bad`-th row (if any) unreadable.
    fn long_log(rows: usize, bad: Option<usize>) -> Vec<u8> {
        let mut text = format!("{HEADER}\n");
        for k in 0..rows {
            if bad.is_some_and(|b| k % b == b - 1) {
                text.push_str(&format!("{k},1,x,40,4,5,6\n"));
            } else {
                text.push_str(&format!("{k},1,2,40,4,5,6\n"));
            }
        }
        text.into_bytes()
    }

    /// Bytes that count what is read of them and, at their end, wait until `release` hangs up
    /// (standard input from a writer that neither writes nor closes).
    struct Watched {
        bytes: std::io::Cursor<Vec<u8>>,
        read: Arc<std::sync::atomic::AtomicU64>,
        release: Option<Receiver<()>>,
        /// Panic at the end instead.
        panic_at_end: bool,
    }

    impl Read for Watched {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            let n = self.bytes.read(buf)?;
            if n == 0 {
                assert!(!self.panic_at_end, "the reader fails");
                if let Some(release) = &self.release {
                    let _ = release.recv();
                }
            }
            self.read.fetch_add(n as u64, Ordering::Relaxed);
            Ok(n)
        }
    }

    fn watched(bytes: Vec<u8>) -> (Watched, Arc<std::sync::atomic::AtomicU64>) {
        let read = Arc::new(std::sync::atomic::AtomicU64::new(0));
        let w = Watched {
            bytes: std::io::Cursor::new(bytes),
            read: read.clone(),
            release: None,
            panic_at_end: false,
        };
        (w, read)
    }

    /// `f` on a thread of its own; fails the test if it has not returned within 20 s (a hang).
    fn within_20_s<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let _ = tx.send(f());
        });
        rx.recv_timeout(std::time::Duration::from_secs(20))
            .expect("did not return within 20 s")
    }

    #[test]
    fn read_ahead_hands_on_every_item_in_order() {
        let bytes = long_log(20_000, Some(997));
        let plain: Vec<_> = LogReader::new(Path::new("t.csv"), bytes.as_slice()).collect();
        let (input, _) = watched(bytes);
        let ahead = within_20_s(|| {
            read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                items.collect::<Vec<_>>()
            })
        });
        assert_eq!(plain.len(), 20_000);
        assert_eq!(ahead, plain);
    }

    #[test]
    fn a_consumer_stopping_early_stops_the_reader_with_the_channel_full() {
        // Far more rows than the channel holds: the reader waits on a full channel when the
        // consumer stops at its first row.
        let bytes = long_log(300_000, None);
        let total = bytes.len() as u64;
        let (input, read) = watched(bytes);
        let first = within_20_s(|| {
            read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                items.next().map(|i| i.map(|l| l.line))
            })
        });
        assert_eq!(first, Some(Ok(2)));
        // The reader stops where it was: what it has read no longer grows.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(10);
        let mut last = u64::MAX;
        loop {
            let now = read.load(Ordering::Relaxed);
            if now == last {
                break;
            }
            assert!(
                std::time::Instant::now() < deadline,
                "the reader goes on: {now} bytes"
            );
            last = now;
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
        assert!(last < total / 2, "read {last} of {total} bytes");
    }

    #[test]
    fn a_consumer_stopping_early_does_not_wait_on_a_reader_blocked_in_a_read() {
        let (release, wait) = std::sync::mpsc::channel::<()>();
        let (mut input, _) = watched(long_log(10_000, None));
        input.release = Some(wait);
        // The first batch comes, then the reader waits for input that does not come.
        let taken = within_20_s(|| {
            read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                items.take(10).count()
            })
        });
        assert_eq!(taken, 10);
        drop(release);
    }

    #[test]
    fn a_reader_that_dies_is_not_taken_for_the_end_of_the_log() {
        let (mut input, _) = watched(long_log(10_000, None));
        input.panic_at_end = true;
        let outcome = within_20_s(|| {
            std::panic::catch_unwind(|| {
                read_ahead(LogReader::new(Path::new("t.csv"), input), |items| {
                    items.count()
                })
            })
        });
        assert!(outcome.is_err(), "{outcome:?}");
    }
}
