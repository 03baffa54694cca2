//! A generic numeric CSV table: named columns (units in the names, `t1_degc`, `ch1_um`), one time
//! column, one row per sample, rows in time order.
//!
//! Rules, checked with errors that name the file, line and column:
//! - line 1 is the header; fields are separated by `,`, surrounding spaces and double quotes are
//!   stripped; blank lines are skipped; column names must be unique;
//! - the time column is the one the caller names, else the only column whose name starts with
//!   `time` (`time_s`, `time_min`, `time_h`); its unit suffix (`_s`, `_min`, `_h`) converts it to
//!   seconds; the time must increase strictly from row to row;
//! - only the columns asked for are parsed; each of their cells must be a finite number
//!   (`NaN`, `inf` and empty cells are errors);
//! - at least `min_rows` data rows.
//!
//! Text in, table out: no file access here (the binary reads the file).

use super::ThermalFitError;

/// What to read from a table.
#[derive(Debug, Clone, Default)]
pub struct TableRequest {
    /// Time column; `None` applies the detection rule of the module doc.
    pub time: Option<String>,
    /// Columns that must be present, with the role reported in errors (`"input"`, `"output"`).
    pub required: Vec<(String, &'static str)>,
    /// Columns read when present (e.g. measured outputs when predicting).
    pub optional: Vec<String>,
    /// Fewest data rows accepted.
    pub min_rows: usize,
}

/// The columns read from a CSV file.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Where the text came from (for messages).
    pub source: String,
    /// Name of the time column as written in the file.
    pub time_name: String,
    /// Time of each row, s (converted from the column's unit).
    pub time_s: Vec<f64>,
    /// The requested columns present in the file: (name, values in the column's unit).
    pub columns: Vec<(String, Vec<f64>)>,
    /// Every column name of the header, in file order.
    pub header: Vec<String>,
    /// File line (1-based) of each data row.
    pub lines: Vec<usize>,
}

impl Table {
    /// Number of data rows.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when there are no data rows.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Values of a column read from the file, if it was requested and present.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Seconds per unit of a time column, from its name's suffix.
fn time_unit_factor(name: &str) -> Option<f64> {
    let unit = name.rsplit('_').next()?;
    match unit {
        "s" => Some(1.0),
        "min" => Some(60.0),
        "h" => Some(3600.0),
        _ => None,
    }
}

/// Splits one CSV line into trimmed, unquoted fields.
fn fields(line: &str) -> Vec<&str> {
    line.split(',')
        .map(|f| {
            let f = f.trim();
            f.strip_prefix('"')
                .and_then(|g| g.strip_suffix('"'))
                .unwrap_or(f)
                .trim()
        })
        .collect()
}

/// Levenshtein distance (for "did you mean").
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

/// The header name closest to `name` (case-insensitive edit distance), if reasonably close.
pub(crate) fn closest<'a>(name: &str, header: &'a [String]) -> Option<&'a str> {
    let lower = name.to_lowercase();
    header
        .iter()
        .map(|h| (edit_distance(&lower, &h.to_lowercase()), h))
        .filter(|(d, h)| *d <= (h.len().max(name.len()) / 2).max(1))
        .min_by_key(|(d, _)| *d)
        .map(|(_, h)| h.as_str())
}

fn missing(source: &str, name: &str, role: &'static str, header: &[String]) -> ThermalFitError {
    ThermalFitError::MissingColumn {
        source_name: source.to_string(),
        column: name.to_string(),
        role,
        suggestion: closest(name, header).map(str::to_string),
        available: header.to_vec(),
    }
}

/// Parses CSV `text` (from `source`) into the columns `request` asks for.
pub fn read_csv(
    text: &str,
    source: &str,
    request: &TableRequest,
) -> Result<Table, ThermalFitError> {
    // A UTF-8 byte-order mark (as spreadsheet programs write) is not part of the first name.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, head) = lines.next().ok_or_else(|| ThermalFitError::EmptyTable {
        source_name: source.to_string(),
    })?;
    let header: Vec<String> = fields(head).iter().map(|s| s.to_string()).collect();
    for (i, h) in header.iter().enumerate() {
        if h.is_empty() {
            return Err(ThermalFitError::BadHeader {
                source_name: source.to_string(),
                reason: format!("column {} has an empty name", i + 1),
            });
        }
        if header[..i].contains(h) {
            return Err(ThermalFitError::BadHeader {
                source_name: source.to_string(),
                reason: format!("column \"{h}\" appears twice"),
            });
        }
    }
    let time_name = match &request.time {
        Some(t) => {
            if !header.contains(t) {
                return Err(missing(source, t, "time", &header));
            }
            t.clone()
        }
        None => {
            let cands: Vec<&String> = header
                .iter()
                .filter(|h| h.to_lowercase().starts_with("time"))
                .collect();
            match cands.as_slice() {
                [one] => (*one).clone(),
                _ => {
                    return Err(ThermalFitError::NoTimeColumn {
                        source_name: source.to_string(),
                        candidates: cands.iter().map(|s| s.to_string()).collect(),
                        available: header.clone(),
                    })
                }
            }
        }
    };
    let factor = time_unit_factor(&time_name).ok_or_else(|| ThermalFitError::TimeUnit {
        source_name: source.to_string(),
        column: time_name.clone(),
    })?;
    let time_idx = header.iter().position(|h| *h == time_name).unwrap_or(0);
    let mut wanted: Vec<(String, usize)> = Vec::new();
    for (name, role) in &request.required {
        let idx = header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| missing(source, name, role, &header))?;
        if !wanted.iter().any(|(n, _)| n == name) {
            wanted.push((name.clone(), idx));
        }
    }
    for name in &request.optional {
        if let Some(idx) = header.iter().position(|h| h == name) {
            if !wanted.iter().any(|(n, _)| n == name) {
                wanted.push((name.clone(), idx));
            }
        }
    }
    let mut time_s = Vec::new();
    let mut rows_line = Vec::new();
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); wanted.len()];
    for (line_no, line) in lines {
        let f = fields(line);
        if f.len() != header.len() {
            return Err(ThermalFitError::RaggedRow {
                source_name: source.to_string(),
                line: line_no,
                expected: header.len(),
                got: f.len(),
            });
        }
        let cell = |idx: usize, name: &str| -> Result<f64, ThermalFitError> {
            let text = f[idx];
            let bad = |reason: &str| ThermalFitError::BadCell {
                source_name: source.to_string(),
                line: line_no,
                column: name.to_string(),
                text: text.to_string(),
                reason: reason.to_string(),
            };
            if text.is_empty() {
                return Err(bad("empty cell"));
            }
            let v: f64 = text.parse().map_err(|_| bad("not a number"))?;
            if !v.is_finite() {
                return Err(bad("not a finite number"));
            }
            Ok(v)
        };
        let t = cell(time_idx, &time_name)? * factor;
        if let Some(&prev) = time_s.last() {
            if t <= prev {
                return Err(ThermalFitError::TimeNotIncreasing {
                    source_name: source.to_string(),
                    line: line_no,
                    column: time_name.clone(),
                    time_s: t,
                    previous_s: prev,
                });
            }
        }
        time_s.push(t);
        rows_line.push(line_no);
        for ((name, idx), col) in wanted.iter().zip(cols.iter_mut()) {
            col.push(cell(*idx, name)?);
        }
    }
    if time_s.len() < request.min_rows.max(1) {
        return Err(ThermalFitError::TooFewRows {
            source_name: source.to_string(),
            rows: time_s.len(),
            needed: request.min_rows.max(1),
        });
    }
    Ok(Table {
        source: source.to_string(),
        time_name,
        time_s,
        columns: wanted.into_iter().map(|(n, _)| n).zip(cols).collect(),
        header,
        lines: rows_line,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request(cols: &[&str]) -> TableRequest {
        TableRequest {
            time: None,
            required: cols.iter().map(|c| (c.to_string(), "input")).collect(),
            optional: vec!["ch9_um".into()],
            min_rows: 2,
        }
    }

    #[test]
    fn minutes_are_converted_and_quotes_crlf_and_blank_lines_are_accepted() {
        let text = "\"time_min\", t1_degc ,ch1_um\r\n0,20.5,1\r\n\r\n1.5,21,2\r\n";
        let t = read_csv(text, "a.csv", &request(&["t1_degc"])).unwrap();
        assert_eq!(t.time_s, vec![0.0, 90.0]);
        assert_eq!(t.column("t1_degc"), Some(&[20.5, 21.0][..]));
        // Optional columns absent from the file are simply not there.
        assert_eq!(t.column("ch9_um"), None);
        assert_eq!(t.lines, vec![2, 4]);
    }

    #[test]
    fn the_closest_column_is_suggested_only_when_it_is_close() {
        let header: Vec<String> = ["time_s", "t1_degc", "t12_degc", "ch1_um"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        assert_eq!(closest("T1_degC", &header), Some("t1_degc"));
        assert_eq!(closest("ch1_mm", &header), Some("ch1_um"));
        assert_eq!(closest("spindle_rpm", &header), None);
    }

    #[test]
    fn unknown_time_units_duplicates_and_ragged_rows_are_errors() {
        let e = read_csv("time_ms,a_x\n0,1\n", "f", &request(&["a_x"])).unwrap_err();
        assert!(matches!(e, ThermalFitError::TimeUnit { .. }), "{e}");
        let e = read_csv("time_s,a_x,a_x\n0,1,2\n", "f", &request(&["a_x"])).unwrap_err();
        assert!(e.to_string().contains("appears twice"), "{e}");
        let e = read_csv("time_s,a_x\n0,1\n1\n", "f", &request(&["a_x"])).unwrap_err();
        assert_eq!(e.to_string(), "f: line 3: 1 fields, the header has 2");
        let e = read_csv("time_s,a_x\n0,\n", "f", &request(&["a_x"])).unwrap_err();
        assert_eq!(
            e.to_string(),
            "f: line 2, column \"a_x\": empty cell (\"\")"
        );
        // Cells of columns nobody asked for are not parsed.
        let t = read_csv("time_s,a_x,junk\n0,1,n/a\n1,2,?\n", "f", &request(&["a_x"])).unwrap();
        assert_eq!(t.len(), 2);
    }
}
