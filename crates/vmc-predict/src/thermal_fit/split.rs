//! The time-ordered split of one measured time series into training, validation and held-out
//! parts.
//!
//! Rows with `time_s ≥ holdout_from_s` are held out: they only serve the final evaluation.
//! The held-out part starts at (first rule that applies):
//! 1. the time the user gives;
//! 2. with a cycle column (e.g. `spindle_rpm`): the last row where that column rises from 0 (or
//!    less) to a positive value, i.e. the start of the last heating cycle;
//! 3. otherwise the start of the last quarter of the time span.
//!
//! The rows before it are split the same way, forward in time: with a cycle column and at least
//! one whole cycle before the held-out one, the validation part is the cycle just before it (so
//! model selection faces the task the held-out test poses: predict a cycle not seen, from the
//! cycles before); otherwise the last `val_fraction` of those rows (by count). The earlier rows
//! train. Neighbouring rows of a thermal series are near copies, so a shuffled split would let
//! the model see the validation data; contiguous blocks in time order do not.

use serde::{Deserialize, Serialize};

use super::ThermalFitError;

/// Where the parts of a time series begin (s, on the file's time axis).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Split {
    /// First time of the validation part, s.
    pub val_from_s: f64,
    /// First time of the held-out part, s.
    pub holdout_from_s: f64,
    /// How `holdout_from_s` was chosen (for the report).
    pub rule: String,
    /// Times where the cycle column rises from 0 (or less) to a positive value, and the first
    /// time if it is positive there: the cycle starts (empty without a cycle column).
    #[serde(default)]
    pub cycle_starts_s: Vec<f64>,
}

/// Which part a row belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// Fitting.
    Train,
    /// Early stopping and model selection.
    Validation,
    /// Final evaluation only.
    Holdout,
}

impl Split {
    /// Resolves the split for rows at `time_s` (strictly increasing, s).
    ///
    /// `holdout_from_s`: rule 1; `cycle`: (name, values) for rule 2; `val_fraction` in (0, 1).
    pub fn resolve(
        time_s: &[f64],
        holdout_from_s: Option<f64>,
        cycle: Option<(&str, &[f64])>,
        val_fraction: f64,
    ) -> Result<Self, ThermalFitError> {
        if !(val_fraction > 0.0 && val_fraction < 1.0) {
            return Err(ThermalFitError::BadSettings {
                field: "val_fraction",
                reason: format!("must lie in (0, 1), got {val_fraction}"),
            });
        }
        let (first, last) = match (time_s.first(), time_s.last()) {
            (Some(f), Some(l)) => (*f, *l),
            _ => {
                return Err(ThermalFitError::BadSettings {
                    field: "split",
                    reason: "no rows to split".into(),
                })
            }
        };
        // Rows where the cycle column rises from ≤ 0 to > 0: cycle starts.
        let starts: Vec<usize> = cycle
            .map(|(_, c)| {
                (1..c.len().min(time_s.len()))
                    .filter(|&n| c[n - 1] <= 0.0 && c[n] > 0.0)
                    .collect()
            })
            .unwrap_or_default();
        let (holdout_from_s, rule) = if let Some(h) = holdout_from_s {
            if !h.is_finite() {
                return Err(ThermalFitError::BadSettings {
                    field: "holdout_from_s",
                    reason: format!("must be finite, got {h}"),
                });
            }
            (h, format!("held out from {h} s (given)"))
        } else if let Some((name, _)) = cycle {
            let start = *starts.last().ok_or_else(|| ThermalFitError::BadSettings {
                field: "cycle column",
                reason: format!(
                    "column \"{name}\" never rises from 0 to a positive value: no cycle \
                         start to hold out from; give the held-out start time instead"
                ),
            })?;
            (
                time_s[start],
                format!(
                    "held out from {} s: the last cycle, where \"{name}\" rises from 0",
                    time_s[start]
                ),
            )
        } else {
            let h = first + 0.75 * (last - first);
            (
                h,
                format!("held out from {h} s: the last quarter of the time span"),
            )
        };
        let n_fit = time_s.iter().take_while(|t| **t < holdout_from_s).count();
        let n_hold = time_s.len() - n_fit;
        // The last cycle start before the held-out part, if it leaves rows to train on.
        let prev_cycle = starts
            .iter()
            .rev()
            .copied()
            .find(|&s| s + 1 < n_fit && s >= 2);
        let (n_val, rule) = match prev_cycle {
            Some(s) => (
                n_fit - s,
                format!(
                    "{rule}; validation: the cycle before it, from {} s",
                    time_s[s]
                ),
            ),
            None => (
                ((n_fit as f64) * val_fraction).round() as usize,
                format!("{rule}; validation: the last {val_fraction} of the rows before it"),
            ),
        };
        if n_hold == 0 || n_val == 0 || n_fit - n_val < 2 {
            return Err(ThermalFitError::BadSettings {
                field: "split",
                reason: format!(
                    "{rule}: {} training, {n_val} validation and {n_hold} held-out rows; every \
                     part needs rows",
                    n_fit.saturating_sub(n_val)
                ),
            });
        }
        Ok(Self {
            val_from_s: time_s[n_fit - n_val],
            holdout_from_s,
            rule,
            // A series that starts heating starts a cycle on its first row.
            cycle_starts_s: cycle
                .filter(|(_, c)| c.first().is_some_and(|v| *v > 0.0))
                .map(|_| first)
                .into_iter()
                .chain(starts.iter().map(|&s| time_s[s]))
                .collect(),
        })
    }

    /// The rows of each cycle, in time order, when there are at least two cycle starts: a cycle
    /// runs from its start to the next one; the rows before the first start belong to the first
    /// cycle. Empty otherwise.
    pub fn cycles(&self, time_s: &[f64]) -> Vec<Vec<usize>> {
        if self.cycle_starts_s.len() < 2 {
            return Vec::new();
        }
        let mut cycles = vec![Vec::new(); self.cycle_starts_s.len()];
        for (r, t) in time_s.iter().enumerate() {
            let k = self.cycle_starts_s[1..]
                .iter()
                .take_while(|s| **s <= *t)
                .count();
            cycles[k].push(r);
        }
        cycles
    }

    /// The part a row at `time_s` belongs to.
    pub fn part(&self, time_s: f64) -> Part {
        if time_s >= self.holdout_from_s {
            Part::Holdout
        } else if time_s >= self.val_from_s {
            Part::Validation
        } else {
            Part::Train
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_rise_of_the_cycle_column_starts_the_held_out_part() {
        let t: Vec<f64> = (0..12).map(|i| 10.0 * f64::from(i)).collect();
        let rpm = [
            0., 1000., 1000., 0., 0., 2000., 2000., 0., 0., 3000., 3000., 0.,
        ];
        let s = Split::resolve(&t, None, Some(("spindle_rpm", &rpm)), 0.25).unwrap();
        assert_eq!(s.holdout_from_s, 90.0);
        // The cycle before it validates.
        assert_eq!(s.val_from_s, 50.0);
        assert_eq!(s.part(40.0), Part::Train);
        assert_eq!(s.part(80.0), Part::Validation);
        // Three cycles; the first holds the row before its rise.
        assert_eq!(
            s.cycles(&t),
            [vec![0, 1, 2, 3, 4], vec![5, 6, 7, 8], vec![9, 10, 11]]
        );
        // Given a held-out start without a cycle column: the last round(9/4) = 2 rows validate.
        let s = Split::resolve(&t, Some(90.0), None, 0.25).unwrap();
        assert_eq!(s.val_from_s, 70.0);
        assert!(s.cycles(&t).is_empty());
        // A series that starts heating: its first row starts a cycle.
        let mut hot = rpm;
        hot[0] = 500.0;
        let s = Split::resolve(&t, None, Some(("spindle_rpm", &hot)), 0.25).unwrap();
        assert_eq!(s.cycle_starts_s, [0.0, 50.0, 90.0]);
        assert_eq!(s.cycles(&t).len(), 3);
        assert_eq!(s.part(90.0), Part::Holdout);
    }

    #[test]
    fn without_rules_the_last_quarter_is_held_out_and_empty_parts_are_errors() {
        let t: Vec<f64> = (0..101).map(f64::from).collect();
        let s = Split::resolve(&t, None, None, 0.2).unwrap();
        assert_eq!(s.holdout_from_s, 75.0);
        assert!(Split::resolve(&t, Some(200.0), None, 0.2).is_err());
        assert!(Split::resolve(&t, Some(50.0), None, 1.5).is_err());
        assert!(Split::resolve(&t, None, Some(("rpm", &[0.0; 101])), 0.2).is_err());
    }
}
