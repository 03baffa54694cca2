//! The FRF file: a receptance per direction against frequency, parsed from text.
//!
//! See the format in the doc of [`crate::modal_fit`].

use thiserror::Error;

/// Fewest data rows a direction needs for a fit.
pub const MIN_ROWS: usize = 20;

/// The columns a file may have, in any order: the frequency and, per direction, the real and
/// imaginary parts of the receptance.
const FREQUENCY: &str = "frequency_hz";
const COLUMNS: [&str; 4] = [
    "x_re_m_per_n",
    "x_im_m_per_n",
    "y_re_m_per_n",
    "y_im_m_per_n",
];

/// A measured receptance FRF at the tool tip: frequencies and, per direction present, the
/// complex receptance (m/N) at each.
#[derive(Debug, Clone, PartialEq)]
pub struct Frf {
    /// Frequencies in Hz, strictly increasing, ≥ 0.
    pub frequency_hz: Vec<f64>,
    /// Receptance in x (feed) as (real, imaginary) in m/N, one per frequency; `None` when the
    /// file has no x columns.
    pub x_m_per_n: Option<Vec<(f64, f64)>>,
    /// Receptance in y as (real, imaginary) in m/N; `None` when the file has no y columns.
    pub y_m_per_n: Option<Vec<(f64, f64)>>,
}

/// Why an FRF file is refused (lines counted from 1).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum FrfError {
    /// No header line (the file is empty or only comments).
    #[error("the FRF file has no header line")]
    NoHeader,
    /// The header lacks the frequency column.
    #[error("line {line}: the header has no `frequency_hz` column")]
    NoFrequency {
        /// Line of the header.
        line: usize,
    },
    /// A header column is not one of the known names.
    #[error("line {line}: unknown column `{name}` (known: frequency_hz, x_re_m_per_n, x_im_m_per_n, y_re_m_per_n, y_im_m_per_n)")]
    UnknownColumn {
        /// Line of the header.
        line: usize,
        /// The name found.
        name: String,
    },
    /// A header column appears twice.
    #[error("line {line}: column `{name}` appears twice")]
    DuplicateColumn {
        /// Line of the header.
        line: usize,
        /// The repeated name.
        name: String,
    },
    /// A direction has its real or its imaginary column but not both.
    #[error("line {line}: direction {direction} has `{present}` but no `{missing}` column")]
    HalfDirection {
        /// Line of the header.
        line: usize,
        /// `x` or `y`.
        direction: char,
        /// The column present.
        present: &'static str,
        /// The column missing.
        missing: &'static str,
    },
    /// Neither direction has its columns.
    #[error("line {line}: no direction: the header needs x_re_m_per_n and x_im_m_per_n, or y_re_m_per_n and y_im_m_per_n")]
    NoDirection {
        /// Line of the header.
        line: usize,
    },
    /// A data line has another number of fields than the header.
    #[error("line {line}: {found} fields, the header has {expected}")]
    FieldCount {
        /// Line.
        line: usize,
        /// Fields of the header.
        expected: usize,
        /// Fields found.
        found: usize,
    },
    /// A field is not a number.
    #[error("line {line}: `{column}` is not a number: `{text}`")]
    NotANumber {
        /// Line.
        line: usize,
        /// Column name.
        column: String,
        /// The text found.
        text: String,
    },
    /// A field is NaN or infinite.
    #[error("line {line}: `{column}` is not finite ({value})")]
    NonFinite {
        /// Line.
        line: usize,
        /// Column name.
        column: String,
        /// The value read.
        value: f64,
    },
    /// A frequency is negative.
    #[error("line {line}: frequency {frequency_hz} Hz is negative")]
    NegativeFrequency {
        /// Line.
        line: usize,
        /// The frequency.
        frequency_hz: f64,
    },
    /// A frequency is not above the one of the line before.
    #[error("line {line}: frequency {frequency_hz} Hz is not above the {previous_hz} Hz of line {previous_line} (frequencies must strictly increase)")]
    NotIncreasing {
        /// Line.
        line: usize,
        /// The frequency.
        frequency_hz: f64,
        /// Line of the frequency before.
        previous_line: usize,
        /// The frequency before.
        previous_hz: f64,
    },
    /// Too few data rows for a fit.
    #[error("{found} data rows, a fit needs at least {min}")]
    TooFewRows {
        /// Rows found.
        found: usize,
        /// Fewest accepted.
        min: usize,
    },
}

impl Frf {
    /// Parses the text of an FRF file (format in [`crate::modal_fit`]).
    ///
    /// # Errors
    /// The first problem found, with its line: see [`FrfError`].
    pub fn parse(text: &str) -> Result<Self, FrfError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (head_line, head) = lines.next().ok_or(FrfError::NoHeader)?;
        let (freq_col, slots) = header(head_line, head)?;
        let width = head.split(',').count();
        let mut frf = Frf {
            frequency_hz: Vec::new(),
            x_m_per_n: slots[0].map(|_| Vec::new()),
            y_m_per_n: slots[2].map(|_| Vec::new()),
        };
        let mut previous: Option<(usize, f64)> = None;
        for (line, text) in lines {
            let fields: Vec<&str> = text.split(',').map(str::trim).collect();
            if fields.len() != width {
                return Err(FrfError::FieldCount {
                    line,
                    expected: width,
                    found: fields.len(),
                });
            }
            let value = |col: usize, name: &str| number(line, name, fields[col]);
            let f = value(freq_col, FREQUENCY)?;
            if f < 0.0 {
                return Err(FrfError::NegativeFrequency {
                    line,
                    frequency_hz: f,
                });
            }
            if let Some((previous_line, previous_hz)) = previous {
                if f <= previous_hz {
                    return Err(FrfError::NotIncreasing {
                        line,
                        frequency_hz: f,
                        previous_line,
                        previous_hz,
                    });
                }
            }
            previous = Some((line, f));
            frf.frequency_hz.push(f);
            for (dir, out) in [(0, &mut frf.x_m_per_n), (2, &mut frf.y_m_per_n)] {
                if let (Some(re), Some(im), Some(out)) = (slots[dir], slots[dir + 1], out) {
                    let re = value(re, COLUMNS[dir])?;
                    let im = value(im, COLUMNS[dir + 1])?;
                    out.push((re, im));
                }
            }
        }
        if frf.frequency_hz.len() < MIN_ROWS {
            return Err(FrfError::TooFewRows {
                found: frf.frequency_hz.len(),
                min: MIN_ROWS,
            });
        }
        Ok(frf)
    }
}

/// The frequency column and the column of each of [`COLUMNS`] (`None` when absent).
fn header(line: usize, head: &str) -> Result<(usize, [Option<usize>; 4]), FrfError> {
    let mut freq = None;
    let mut slots = [None; 4];
    for (i, name) in head.split(',').map(str::trim).enumerate() {
        let slot = if name == FREQUENCY {
            &mut freq
        } else if let Some(k) = COLUMNS.iter().position(|c| *c == name) {
            &mut slots[k]
        } else {
            return Err(FrfError::UnknownColumn {
                line,
                name: name.to_string(),
            });
        };
        if slot.replace(i).is_some() {
            return Err(FrfError::DuplicateColumn {
                line,
                name: name.to_string(),
            });
        }
    }
    let freq = freq.ok_or(FrfError::NoFrequency { line })?;
    for (dir, direction) in [(0, 'x'), (2, 'y')] {
        match (slots[dir], slots[dir + 1]) {
            (Some(_), None) => {
                return Err(FrfError::HalfDirection {
                    line,
                    direction,
                    present: COLUMNS[dir],
                    missing: COLUMNS[dir + 1],
                })
            }
            (None, Some(_)) => {
                return Err(FrfError::HalfDirection {
                    line,
                    direction,
                    present: COLUMNS[dir + 1],
                    missing: COLUMNS[dir],
                })
            }
            _ => {}
        }
    }
    if slots[0].is_none() && slots[2].is_none() {
        return Err(FrfError::NoDirection { line });
    }
    Ok((freq, slots))
}

fn number(line: usize, column: &str, text: &str) -> Result<f64, FrfError> {
    let v: f64 = text.parse().map_err(|_| FrfError::NotANumber {
        line,
        column: column.to_string(),
        text: text.to_string(),
    })?;
    if !v.is_finite() {
        return Err(FrfError::NonFinite {
            line,
            column: column.to_string(),
            value: v,
        });
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(n: usize, head: &str, row: impl Fn(usize) -> String) -> String {
        let mut s = format!("# a comment\n{head}\n");
        for i in 0..n {
            s.push_str(&row(i));
            s.push('\n');
        }
        s
    }

    const HEAD: &str = "frequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n,y_im_m_per_n";

    fn good(i: usize) -> String {
        format!("{},{},-1e-7,2e-8,-3e-8", 100 + 10 * i, 1e-8)
    }

    #[test]
    fn a_good_file_reads_both_directions_and_skips_comments() {
        let frf = Frf::parse(&rows(25, HEAD, good)).unwrap();
        assert_eq!(frf.frequency_hz.len(), 25);
        assert_eq!(frf.frequency_hz[1], 110.0);
        assert_eq!(frf.x_m_per_n.as_ref().unwrap()[0], (1e-8, -1e-7));
        assert_eq!(frf.y_m_per_n.as_ref().unwrap()[24], (2e-8, -3e-8));
    }

    #[test]
    fn columns_may_come_in_any_order_and_one_direction_may_be_absent() {
        let head = "y_im_m_per_n,frequency_hz,y_re_m_per_n";
        let frf = Frf::parse(&rows(20, head, |i| format!("-2e-8,{},1e-8", 50 + i))).unwrap();
        assert!(frf.x_m_per_n.is_none());
        assert_eq!(frf.y_m_per_n.unwrap()[3], (1e-8, -2e-8));
    }

    fn err(text: &str) -> String {
        Frf::parse(text).unwrap_err().to_string()
    }

    #[test]
    fn frequencies_that_do_not_increase_are_refused_with_both_lines() {
        let text = rows(25, HEAD, |i| if i == 7 { good(6) } else { good(i) });
        // Header on line 2, row i on line i + 3.
        assert_eq!(
            err(&text),
            "line 10: frequency 160 Hz is not above the 160 Hz of line 9 (frequencies must strictly increase)"
        );
    }

    #[test]
    fn nan_inf_and_words_are_refused_with_the_line_and_column() {
        let nan = rows(25, HEAD, |i| {
            if i == 3 {
                "130,NaN,-1e-7,2e-8,-3e-8".into()
            } else {
                good(i)
            }
        });
        assert_eq!(err(&nan), "line 6: `x_re_m_per_n` is not finite (NaN)");
        let inf = rows(25, HEAD, |i| {
            if i == 0 {
                "100,1e-8,-1e-7,2e-8,inf".into()
            } else {
                good(i)
            }
        });
        assert_eq!(err(&inf), "line 3: `y_im_m_per_n` is not finite (inf)");
        let word = rows(25, HEAD, |i| {
            if i == 1 {
                "110,1e-8,abc,2e-8,-3e-8".into()
            } else {
                good(i)
            }
        });
        assert_eq!(err(&word), "line 4: `x_im_m_per_n` is not a number: `abc`");
    }

    #[test]
    fn a_missing_column_of_a_direction_is_named() {
        let head = "frequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n";
        let text = rows(25, head, |i| format!("{},1e-8,-1e-7,2e-8", 100 + i));
        assert_eq!(
            err(&text),
            "line 2: direction y has `y_re_m_per_n` but no `y_im_m_per_n` column"
        );
        assert_eq!(
            err("frequency_hz\n1\n"),
            "line 1: no direction: the header needs x_re_m_per_n and x_im_m_per_n, or y_re_m_per_n and y_im_m_per_n"
        );
        assert_eq!(
            err("x_re_m_per_n,x_im_m_per_n\n"),
            "line 1: the header has no `frequency_hz` column"
        );
        assert!(err("frequency_hz,x_re,x_im\n").starts_with("line 1: unknown column `x_re`"));
        assert_eq!(
            err("frequency_hz,x_re_m_per_n,x_im_m_per_n,x_re_m_per_n\n"),
            "line 1: column `x_re_m_per_n` appears twice"
        );
    }

    #[test]
    fn short_lines_too_few_rows_negative_frequencies_and_empty_files_are_refused() {
        let short = rows(25, HEAD, |i| {
            if i == 2 {
                "120,1e-8,-1e-7".into()
            } else {
                good(i)
            }
        });
        assert_eq!(err(&short), "line 5: 3 fields, the header has 5");
        assert_eq!(
            err(&rows(19, HEAD, good)),
            "19 data rows, a fit needs at least 20"
        );
        let negative = rows(25, HEAD, |i| {
            if i == 0 {
                "-5,1e-8,-1e-7,2e-8,-3e-8".into()
            } else {
                good(i)
            }
        });
        assert_eq!(err(&negative), "line 3: frequency -5 Hz is negative");
        assert_eq!(
            err("# only a comment\n\n"),
            "the FRF file has no header line"
        );
    }
}
