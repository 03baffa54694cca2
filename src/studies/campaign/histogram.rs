//! Histograms of equal bins from the smallest to the largest finite value, built in two passes
//! over the values (the range, then the counts) in memory that does not grow with their number.

/// A histogram: `counts[k]` values in `[lo + k·width, lo + (k+1)·width)` (the last bin closed).
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Lower edge of the first bin.
    pub lo: f64,
    /// Bin width (1 when every value is the same).
    pub width: f64,
    /// Values per bin.
    pub counts: Vec<u64>,
}

impl Histogram {
    /// `bins` equal bins from the smallest to the largest finite value of `v`; None without
    /// one or with no bin.
    pub fn of(v: &[f64], bins: usize) -> Option<Self> {
        let mut h = HistogramBuilder::new(bins);
        for pass in 0..2 {
            for &x in v {
                h.push(x);
            }
            if pass == 0 {
                h.end_range_pass();
            }
        }
        h.finish()
    }

    /// The bins' centres.
    pub fn centres(&self) -> Vec<f64> {
        (0..self.counts.len())
            .map(|k| self.lo + (k as f64 + 0.5) * self.width)
            .collect()
    }
}

/// A [`Histogram`] fed in two passes over the same values: the first finds the range, the
/// second counts.
#[derive(Debug, Clone)]
pub struct HistogramBuilder {
    bins: usize,
    /// Smallest and largest finite value (first pass).
    lo: Option<f64>,
    hi: Option<f64>,
    /// Bin width and counts (second pass).
    width: f64,
    counts: Option<Vec<u64>>,
}

impl HistogramBuilder {
    /// A histogram of `bins` bins.
    pub fn new(bins: usize) -> Self {
        Self {
            bins,
            lo: None,
            hi: None,
            width: 1.0,
            counts: None,
        }
    }

    /// Feeds a value of the current pass (non-finite values are left out).
    pub fn push(&mut self, x: f64) {
        if !x.is_finite() {
            return;
        }
        match &mut self.counts {
            None => {
                self.lo = Some(self.lo.map_or(x, |l| l.min(x)));
                self.hi = Some(self.hi.map_or(x, |h| h.max(x)));
            }
            Some(counts) => {
                let lo = self.lo.unwrap_or(x);
                let k = (((x - lo) / self.width) as usize).min(self.bins - 1);
                counts[k] += 1;
            }
        }
    }

    /// Ends the first pass: the bins are set from the range, the next pass counts.
    pub fn end_range_pass(&mut self) {
        if let (Some(lo), Some(hi)) = (self.lo, self.hi) {
            if self.bins > 0 {
                self.width = if hi > lo {
                    (hi - lo) / self.bins as f64
                } else {
                    1.0
                };
                self.counts = Some(vec![0; self.bins]);
            }
        }
    }

    /// The histogram, after the counting pass; None without a finite value or with no bin.
    pub fn finish(self) -> Option<Histogram> {
        Some(Histogram {
            lo: self.lo?,
            width: self.width,
            counts: self.counts?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_value_falls_in_one_bin_and_the_largest_in_the_last() {
        let h = Histogram::of(&[0.0, 1.0, 2.0, 3.0, 4.0, f64::NAN], 4).unwrap();
        assert_eq!(h.lo, 0.0);
        assert_eq!(h.width, 1.0);
        assert_eq!(h.counts, vec![1, 1, 1, 2]);
        assert_eq!(h.centres(), vec![0.5, 1.5, 2.5, 3.5]);
        assert_eq!(Histogram::of(&[2.0, 2.0], 3).unwrap().counts, vec![2, 0, 0]);
        assert_eq!(Histogram::of(&[], 3), None);
        assert_eq!(Histogram::of(&[1.0], 0), None);
        assert_eq!(Histogram::of(&[f64::INFINITY], 2), None);
    }
}
