//! Which global samples (iterations, for the VCM family) a render state holds.

use std::fmt;
use std::ops::Range;
use std::str::FromStr;

/// A set of global sample indices as sorted, disjoint, non-adjacent ranges: `0..16` after
/// sixteen samples per pixel, `0..8,16..24` after merging two shards with a gap between.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SampleRanges(Vec<Range<u32>>);

impl SampleRanges {
    /// No samples.
    pub fn new() -> SampleRanges {
        SampleRanges::default()
    }

    /// The samples of `range` (none if it is empty).
    pub fn from_range(range: Range<u32>) -> SampleRanges {
        let mut ranges = SampleRanges::new();
        ranges.insert(range);
        ranges
    }

    /// The ranges, sorted, disjoint and non-adjacent.
    pub fn ranges(&self) -> &[Range<u32>] {
        &self.0
    }

    /// How many samples.
    pub fn count(&self) -> u64 {
        self.0.iter().map(|r| u64::from(r.end - r.start)).sum()
    }

    /// One past the last sample (0 when empty): where a resumed render continues.
    pub fn end(&self) -> u32 {
        self.0.last().map_or(0, |r| r.end)
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The first range `range` shares samples with, if any.
    pub fn overlap(&self, range: &Range<u32>) -> Option<Range<u32>> {
        self.0
            .iter()
            .map(|r| r.start.max(range.start)..r.end.min(range.end))
            .find(|r| r.start < r.end)
    }

    /// The first samples `other` shares with `self`, if any.
    pub fn overlap_with(&self, other: &SampleRanges) -> Option<Range<u32>> {
        other.0.iter().find_map(|r| self.overlap(r))
    }

    /// Adds the samples of `range`, joining it with the ranges it overlaps or touches.
    pub fn insert(&mut self, range: Range<u32>) {
        if range.start >= range.end {
            return;
        }
        let (mut start, mut end) = (range.start, range.end);
        // Everything that overlaps or touches [start, end) is folded into it.
        self.0.retain(|r| {
            let apart = r.end < start || r.start > end;
            if !apart {
                start = start.min(r.start);
                end = end.max(r.end);
            }
            apart
        });
        let at = self.0.partition_point(|r| r.start < start);
        self.0.insert(at, start..end);
    }

    /// Adds every range of `other`.
    pub fn insert_all(&mut self, other: &SampleRanges) {
        for r in &other.0 {
            self.insert(r.clone());
        }
    }
}

impl fmt::Display for SampleRanges {
    /// `0..16,32..48`; empty for no samples.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, r) in self.0.iter().enumerate() {
            if i > 0 {
                f.write_str(",")?;
            }
            write!(f, "{}..{}", r.start, r.end)?;
        }
        Ok(())
    }
}

/// Parses one `A..B` range with A < B.
pub fn parse_range(text: &str) -> Result<Range<u32>, String> {
    let (start, end) = text
        .split_once("..")
        .ok_or_else(|| format!("`{text}` is not a range A..B"))?;
    let number = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|_| format!("`{s}` in `{text}` is not a sample index (0 to 2³² − 1)"))
    };
    let (start, end) = (number(start)?, number(end)?);
    if start >= end {
        return Err(format!(
            "the range `{text}` holds no samples (A must be below B)"
        ));
    }
    Ok(start..end)
}

impl FromStr for SampleRanges {
    type Err = String;

    /// The inverse of `Display`: comma-separated `A..B` ranges, sorted and disjoint.
    fn from_str(text: &str) -> Result<SampleRanges, String> {
        let mut ranges = SampleRanges::new();
        if text.is_empty() {
            return Ok(ranges);
        }
        for part in text.split(',') {
            let range = parse_range(part)?;
            if ranges.end() > range.start && !ranges.is_empty() {
                return Err(format!("`{text}`: the ranges are not sorted and disjoint"));
            }
            ranges.insert(range);
        }
        Ok(ranges)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inserting_joins_touching_and_overlapping_ranges() {
        let mut ranges = SampleRanges::new();
        ranges.insert(8..16);
        ranges.insert(0..4);
        assert_eq!(ranges.to_string(), "0..4,8..16");
        ranges.insert(4..8);
        assert_eq!(ranges.to_string(), "0..16");
        ranges.insert(20..30);
        ranges.insert(10..22);
        assert_eq!(ranges.to_string(), "0..30");
        ranges.insert(5..5);
        assert_eq!((ranges.count(), ranges.end()), (30, 30));
    }

    #[test]
    fn overlaps_are_found() {
        let ranges: SampleRanges = "0..8,16..24".parse().unwrap();
        assert_eq!(ranges.overlap(&(8..16)), None);
        assert_eq!(ranges.overlap(&(6..18)), Some(6..8));
        let other: SampleRanges = "10..12,20..30".parse().unwrap();
        assert_eq!(ranges.overlap_with(&other), Some(20..24));
    }

    #[test]
    fn text_round_trips_and_bad_text_is_refused() {
        for text in ["", "0..1", "0..16,32..48", "5..4294967295"] {
            let ranges: SampleRanges = text.parse().unwrap();
            assert_eq!(ranges.to_string(), text);
        }
        for bad in [
            "0..",
            "..4",
            "4..4",
            "5..3",
            "a..b",
            "0..4,2..6",
            "8..9,0..4",
            "-1..3",
        ] {
            assert!(bad.parse::<SampleRanges>().is_err(), "{bad}");
        }
    }
}
