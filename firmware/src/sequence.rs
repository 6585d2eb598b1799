//! Lost frames, counted from the requests' sequence numbers (link protocol 5): the host numbers
//! its requests 1, 2, 3, ...; a request whose number is ahead of the one expected shows that the
//! ones in between never arrived intact (lost on the line, cut by a buffer overrun, or dropped as
//! bad frames).
//!
//! A number behind the one expected is a host that started numbering again (a new stream) or a
//! repeated frame: nothing is counted and the count goes on from it. Unnumbered requests
//! (`UNNUMBERED`, 0) are not counted. After `u32::MAX` the host continues at 1 (0 is skipped).

use link_protocol::UNNUMBERED;

/// Counts the numbers missing from a stream of sequence numbers.
#[derive(Debug, Default)]
pub struct SequenceTracker {
    /// The number the next request should carry (none before the first numbered one).
    expected: Option<u32>,
    lost: u32,
}

/// The number after `seq` in the host's numbering (0 is skipped).
pub fn next_seq(seq: u32) -> u32 {
    match seq.wrapping_add(1) {
        UNNUMBERED => 1,
        n => n,
    }
}

impl SequenceTracker {
    /// No sequence number seen yet.
    pub const fn new() -> Self {
        SequenceTracker {
            expected: None,
            lost: 0,
        }
    }

    /// A request with number `seq` arrived; returns how many requests before it were lost.
    pub fn observe(&mut self, seq: u32) -> u32 {
        if seq == UNNUMBERED {
            return 0;
        }
        let missing = match self.expected {
            // Ahead by less than half the number space: the ones between were lost (a number
            // behind is a restart or a repeat).
            Some(expected) => {
                let ahead = seq.wrapping_sub(expected);
                let skipped_zero = u32::from(expected > seq && ahead < 1 << 31);
                if ahead < 1 << 31 {
                    ahead - skipped_zero
                } else {
                    0
                }
            }
            None => 0,
        };
        self.lost = self.lost.saturating_add(missing);
        self.expected = Some(next_seq(seq));
        missing
    }

    /// Requests lost since boot (saturating).
    pub fn lost(&self) -> u32 {
        self.lost
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn consecutive_numbers_lose_nothing_and_gaps_count_what_is_missing() {
        let mut t = SequenceTracker::new();
        for seq in 1..=10 {
            assert_eq!(t.observe(seq), 0);
        }
        assert_eq!(t.observe(14), 3);
        assert_eq!(t.observe(15), 0);
        assert_eq!(t.lost(), 3);
    }

    #[test]
    fn the_first_number_seen_loses_nothing_whatever_it_is() {
        let mut t = SequenceTracker::new();
        assert_eq!(t.observe(5000), 0);
        assert_eq!(t.observe(5001), 0);
        assert_eq!(t.lost(), 0);
    }

    #[test]
    fn a_restart_or_a_repeat_counts_nothing_and_counting_goes_on_from_it() {
        let mut t = SequenceTracker::new();
        for seq in 1..=100 {
            t.observe(seq);
        }
        assert_eq!(t.observe(1), 0, "a new stream numbers from 1 again");
        assert_eq!(t.observe(2), 0);
        assert_eq!(t.observe(2), 0, "a repeat");
        assert_eq!(t.observe(5), 2);
        assert_eq!(t.lost(), 2);
    }

    #[test]
    fn unnumbered_requests_are_not_counted() {
        let mut t = SequenceTracker::new();
        t.observe(1);
        assert_eq!(t.observe(UNNUMBERED), 0);
        assert_eq!(t.observe(2), 0);
        assert_eq!(t.lost(), 0);
    }

    #[test]
    fn numbering_wraps_from_max_to_1() {
        assert_eq!(next_seq(u32::MAX), 1);
        let mut t = SequenceTracker::new();
        t.observe(u32::MAX - 1);
        assert_eq!(t.observe(u32::MAX), 0);
        assert_eq!(t.observe(1), 0);
        assert_eq!(t.observe(2), 0);
        // A gap across the wrap: MAX then 3 (1 and 2 lost).
        let mut t = SequenceTracker::new();
        t.observe(u32::MAX);
        assert_eq!(t.observe(3), 2);
    }
}
