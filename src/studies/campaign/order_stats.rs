//! Exact order statistics — the median, nearest-rank percentiles — of values that arrive as a
//! stream which can be replayed, in memory that does not grow with their number.
//!
//! A value's rank is taken in f64's total order (`f64::total_cmp`, the order the campaign sorts
//! by), through the order-preserving 64-bit key of the value: a positive value's bits with the
//! sign bit set, a negative value's bits inverted. Each pass over the stream counts the values
//! that share the key digits found so far by their next [`DIGIT_BITS`]-bit digit (a radix
//! select); the digit holding the wanted rank narrows the search for the next pass. While at
//! most [`KEEP_MAX`] values share the digits found so far, their keys are also kept, and the
//! search ends at that pass by sorting them. A group of at most `KEEP_MAX` values is done after
//! one pass; a larger one after a few (three for the campaign's reductions, at most six).
//!
//! Memory per wanted rank: the digit counts (16 kB) and at most `KEEP_MAX` keys (16 kB).

/// Bits of the key resolved per pass.
pub const DIGIT_BITS: u32 = 12;

/// Most keys kept per search (when more share the digits found so far, another pass follows).
pub const KEEP_MAX: usize = 2048;

/// The order-preserving key of `x`: `key(a) < key(b)` exactly when `a.total_cmp(&b)` is `Less`.
pub fn key(x: f64) -> u64 {
    let b = x.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | 1 << 63
    }
}

/// The value of a key (the inverse of [`key`]).
pub fn value(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
}

/// The 0-based rank of the nearest-rank `p`-th percentile (0 < p ≤ 100) of `n ≥ 1` values: the
/// smallest value with at least p % of the values at or below it.
pub fn nearest_rank(p: f64, n: usize) -> usize {
    let rank = ((p / 100.0) * n as f64).ceil().max(1.0) as usize;
    rank.min(n) - 1
}

/// The median of sorted values given its two middle ones: the middle one of an odd number, the
/// mean of the two middle ones of an even number.
pub fn median_of_middle(n: usize, lower: f64, upper: f64) -> f64 {
    if n % 2 == 1 {
        lower
    } else {
        0.5 * (lower + upper)
    }
}

/// A pass over the values that did not replay the first one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the values changed between passes ({first} in the first pass, {now} in a later one)")]
pub struct StreamChanged {
    /// Values in the first pass.
    pub first: usize,
    /// Values in the later pass.
    pub now: usize,
}

/// Which order statistics a [`Selector`] finds.
#[derive(Debug, Clone, PartialEq)]
pub enum Wanted {
    /// The median (the mean of the two middle values of an even number).
    Median,
    /// Nearest-rank percentiles, each in (0, 100].
    Percentiles(Vec<f64>),
}

impl Wanted {
    /// The 0-based ranks needed among `n ≥ 1` values, ascending, without repeats.
    fn ranks(&self, n: usize) -> Vec<usize> {
        let mut r: Vec<usize> = match self {
            Self::Median => vec![(n - 1) / 2, n / 2],
            Self::Percentiles(ps) => ps.iter().map(|&p| nearest_rank(p, n)).collect(),
        };
        r.sort_unstable();
        r.dedup();
        r
    }
}

/// The search for one rank among the values whose keys start with `prefix`'s first `bits` bits.
#[derive(Debug, Clone)]
struct Search {
    /// The key digits found so far (the rest of the bits zero).
    prefix: u64,
    /// How many leading bits of `prefix` are found.
    bits: u32,
    /// The wanted rank among the values sharing the prefix.
    rank: usize,
    /// Values sharing the prefix, by their next digit.
    counts: Vec<u64>,
    /// Their keys, while there are at most [`KEEP_MAX`] (`None` once there were more).
    kept: Option<Vec<u64>>,
    /// The key of rank `rank`, once found.
    found: Option<u64>,
}

impl Search {
    /// A search over all values (rank set when the first pass ends).
    fn start() -> Self {
        Self {
            prefix: 0,
            bits: 0,
            rank: 0,
            counts: vec![0; 1 << DIGIT_BITS],
            kept: Some(Vec::new()),
            found: None,
        }
    }

    /// Width of the next digit.
    fn digit_bits(&self) -> u32 {
        DIGIT_BITS.min(64 - self.bits)
    }

    /// Counts (and keeps) `k` if it shares the prefix.
    fn push(&mut self, k: u64, keep_max: usize) {
        if self.found.is_some() || (self.bits > 0 && (k ^ self.prefix) >> (64 - self.bits) != 0) {
            return;
        }
        let digit = (k << self.bits) >> (64 - self.digit_bits());
        self.counts[digit as usize] += 1;
        if let Some(kept) = &mut self.kept {
            if kept.len() < keep_max {
                kept.push(k);
            } else {
                self.kept = None;
            }
        }
    }

    /// Ends a pass: the rank's key when every value sharing the prefix was kept, or when the
    /// whole key is found; otherwise the next digit, and a fresh count for the next pass.
    /// False when the rank is beyond the values counted (they changed since the first pass).
    fn end_pass(&mut self) -> bool {
        if self.found.is_some() {
            return true;
        }
        if let Some(kept) = &mut self.kept {
            kept.sort_unstable();
            self.found = kept.get(self.rank).copied();
            self.counts = Vec::new();
            self.kept = None;
            return self.found.is_some();
        }
        let d = self.digit_bits();
        let mut below = 0;
        let Some(digit) = self.counts.iter().position(|&c| {
            below += c as usize;
            self.rank < below
        }) else {
            return false;
        };
        self.rank -= below - self.counts[digit] as usize;
        self.prefix |= (digit as u64) << (64 - self.bits - d);
        self.bits += d;
        if self.bits == 64 {
            self.found = Some(self.prefix);
            self.counts = Vec::new();
        } else {
            self.counts = vec![0; 1 << self.digit_bits()];
            self.kept = Some(Vec::new());
        }
        true
    }
}

/// Exact order statistics of one group of values, fed in passes over the same values in the
/// same order: [`Selector::push`] every value, then [`Selector::end_pass`], until it says done.
#[derive(Debug, Clone)]
pub struct Selector {
    wanted: Wanted,
    keep_max: usize,
    /// Values in the first pass.
    n: usize,
    /// Values in the current pass.
    seen: usize,
    /// Passes ended.
    passes: u32,
    /// The ranks sought (known after the first pass) and their searches.
    ranks: Vec<usize>,
    searches: Vec<Search>,
}

impl Selector {
    /// A selector of `wanted`, keeping at most [`KEEP_MAX`] keys per search.
    pub fn new(wanted: Wanted) -> Self {
        Self::with_keep_max(wanted, KEEP_MAX)
    }

    /// A selector keeping at most `keep_max` keys per search (more passes with fewer).
    pub fn with_keep_max(wanted: Wanted, keep_max: usize) -> Self {
        Self {
            wanted,
            keep_max,
            n: 0,
            seen: 0,
            passes: 0,
            ranks: Vec::new(),
            searches: vec![Search::start()],
        }
    }

    /// Feeds a value of the current pass.
    pub fn push(&mut self, x: f64) {
        self.seen += 1;
        let k = key(x);
        for s in &mut self.searches {
            s.push(k, self.keep_max);
        }
    }

    /// Ends a pass; true when every wanted value is found (no further pass is needed).
    ///
    /// # Errors
    /// The pass held another number of values than the first one (the stream was not replayed).
    pub fn end_pass(&mut self) -> Result<bool, StreamChanged> {
        let seen = std::mem::take(&mut self.seen);
        if self.passes == 0 {
            self.n = seen;
            self.ranks = if self.n == 0 {
                Vec::new()
            } else {
                self.wanted.ranks(self.n)
            };
            let first = self.searches.pop().unwrap_or_else(Search::start);
            self.searches = self
                .ranks
                .iter()
                .map(|&rank| Search {
                    rank,
                    ..first.clone()
                })
                .collect();
        } else if seen != self.n {
            return Err(StreamChanged {
                first: self.n,
                now: seen,
            });
        }
        self.passes += 1;
        let mut located = true;
        for s in &mut self.searches {
            located &= s.end_pass();
        }
        if !located {
            return Err(StreamChanged {
                first: self.n,
                now: seen,
            });
        }
        Ok(self.done())
    }

    /// Whether every wanted value is found.
    pub fn done(&self) -> bool {
        self.passes > 0 && self.searches.iter().all(|s| s.found.is_some())
    }

    /// The number of values (after the first pass).
    pub fn count(&self) -> usize {
        self.n
    }

    /// The value of 0-based rank `rank`, if it was wanted and is found.
    fn at(&self, rank: usize) -> Option<f64> {
        let i = self.ranks.iter().position(|&r| r == rank)?;
        self.searches[i].found.map(value)
    }

    /// The median (with [`Wanted::Median`], once done; None without values).
    pub fn median(&self) -> Option<f64> {
        let n = self.n;
        if n == 0 {
            return None;
        }
        Some(median_of_middle(n, self.at((n - 1) / 2)?, self.at(n / 2)?))
    }

    /// The nearest-rank `p`-th percentile (one of [`Wanted::Percentiles`], once done; None
    /// without values).
    pub fn percentile(&self, p: f64) -> Option<f64> {
        if self.n == 0 {
            return None;
        }
        self.at(nearest_rank(p, self.n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs passes over `v` until done; gives the number of passes.
    fn select(sel: &mut Selector, v: &[f64]) -> u32 {
        let mut passes = 0;
        loop {
            for &x in v {
                sel.push(x);
            }
            passes += 1;
            if sel.end_pass().unwrap() {
                return passes;
            }
            assert!(passes <= 6, "at most six passes");
        }
    }

    /// The median as the campaign computes it from a sorted copy.
    fn sorted_median(v: &[f64]) -> f64 {
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        median_of_middle(n, s[(n - 1) / 2], s[n / 2])
    }

    /// A deterministic sequence of awkward values: clustered, repeated, signed zeros, negative,
    /// infinite and NaN.
    fn awkward(n: usize, seed: u64) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|i| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                match i % 17 {
                    0 => 0.97,
                    1 => -0.0,
                    2 => 0.0,
                    3 => -u * 1e3,
                    4 if i % 5 == 0 => f64::INFINITY,
                    5 if i % 7 == 0 => f64::NAN,
                    _ => 0.95 + 0.04 * u,
                }
            })
            .collect()
    }

    #[test]
    fn keys_order_values_as_total_cmp_does_and_give_them_back() {
        let v = [
            f64::NEG_INFINITY,
            -1.5,
            -f64::MIN_POSITIVE,
            -0.0,
            0.0,
            f64::MIN_POSITIVE,
            0.98,
            1e300,
            f64::INFINITY,
            f64::NAN,
        ];
        for a in v {
            assert_eq!(value(key(a)).to_bits(), a.to_bits());
            for b in v {
                assert_eq!(key(a).cmp(&key(b)), a.total_cmp(&b), "{a} {b}");
            }
        }
    }

    #[test]
    fn medians_equal_those_of_a_sorted_copy_bit_for_bit_whatever_the_passes() {
        for n in [1, 2, 3, 10, 11, 500, 4001] {
            let v = awkward(n, n as u64);
            let expected = sorted_median(&v);
            for keep_max in [1, 3, 64, KEEP_MAX] {
                let mut sel = Selector::with_keep_max(Wanted::Median, keep_max);
                let passes = select(&mut sel, &v);
                let got = sel.median().unwrap();
                assert_eq!(got.to_bits(), expected.to_bits(), "n {n} keep {keep_max}");
                if n <= keep_max {
                    assert_eq!(passes, 1, "n {n} keep {keep_max}: all kept");
                }
            }
        }
    }

    #[test]
    fn clustered_reductions_need_three_passes_and_little_memory() {
        // 84,000 reductions between 0.93 and 0.99, as a fleet of 1,000 machines gives.
        let v: Vec<f64> = (0..84_000)
            .map(|i| 0.93 + 0.06 * ((i * 7919) % 84_000) as f64 / 84_000.0)
            .collect();
        let mut sel = Selector::new(Wanted::Median);
        assert_eq!(select(&mut sel, &v), 3);
        assert_eq!(sel.median().unwrap().to_bits(), sorted_median(&v).to_bits());
    }

    #[test]
    fn percentiles_are_of_the_nearest_rank() {
        let v: Vec<f64> = (1..=10).rev().map(f64::from).collect();
        let ps = vec![5.0, 50.0, 95.0, 100.0];
        for keep_max in [2, KEEP_MAX] {
            let mut sel = Selector::with_keep_max(Wanted::Percentiles(ps.clone()), keep_max);
            select(&mut sel, &v);
            let got: Vec<f64> = ps.iter().map(|&p| sel.percentile(p).unwrap()).collect();
            assert_eq!(got, vec![1.0, 5.0, 10.0, 10.0]);
        }
        let v = awkward(3000, 7);
        let mut s = v.clone();
        s.sort_by(f64::total_cmp);
        let ps = vec![5.0, 25.0, 50.0, 75.0, 95.0, 100.0];
        let mut sel = Selector::with_keep_max(Wanted::Percentiles(ps.clone()), 16);
        select(&mut sel, &v);
        for p in ps {
            let expected = s[nearest_rank(p, s.len())];
            assert_eq!(
                sel.percentile(p).unwrap().to_bits(),
                expected.to_bits(),
                "P{p}"
            );
        }
    }

    #[test]
    fn no_values_give_no_statistics_after_one_pass() {
        let mut sel = Selector::new(Wanted::Median);
        assert!(sel.end_pass().unwrap());
        assert_eq!(sel.median(), None);
        let mut sel = Selector::new(Wanted::Percentiles(vec![50.0]));
        assert!(sel.end_pass().unwrap());
        assert_eq!(sel.percentile(50.0), None);
    }

    #[test]
    fn a_pass_with_other_values_is_an_error() {
        let mut sel = Selector::with_keep_max(Wanted::Median, 2);
        for x in [1.0, 2.0, 3.0] {
            sel.push(x);
        }
        assert_eq!(sel.end_pass(), Ok(false));
        sel.push(1.0);
        assert_eq!(sel.end_pass(), Err(StreamChanged { first: 3, now: 1 }));
    }

    #[test]
    fn identical_values_are_found_when_the_whole_key_is_known() {
        let v = vec![0.5; 100];
        let mut sel = Selector::with_keep_max(Wanted::Median, 10);
        assert_eq!(select(&mut sel, &v), 6);
        assert_eq!(sel.median(), Some(0.5));
    }
}
