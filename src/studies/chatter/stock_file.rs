//! The stock file (TOML) of the chatter check: a box in the program's coordinates and,
//! optionally, the Z-map's grid spacing. Units in names; unknown keys are refused.
//!
//! ```toml
//! name = "pocket blank"          # optional
//! min_mm = [0.0, 0.0, -20.0]     # lowest corner x, y, z
//! max_mm = [80.0, 60.0, 0.0]     # highest corner
//! grid_mm = 0.5                  # optional; default: the tool's diameter / 32
//! ```

use serde::Deserialize;
use thiserror::Error;

use vmc_machine::cutting::{CuttingError, StockBox};

/// A stock file, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct StockSpec {
    /// The file's `name` (or the file name).
    pub name: String,
    /// The box (mm).
    pub stock: StockBox,
    /// Grid spacing of the Z-map (mm), if the file gives one.
    pub grid_mm: Option<f64>,
}

/// A stock file that cannot be used.
#[derive(Debug, Error)]
pub enum StockFileError {
    /// Not TOML, or not the schema (the parser's message has line and column).
    #[error("{path}: {msg}")]
    Parse {
        /// The file.
        path: String,
        /// The TOML parser's message.
        msg: String,
    },
    /// An empty box or a bad spacing.
    #[error("{path}: {err}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        err: CuttingError,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StockFile {
    name: Option<String>,
    min_mm: [f64; 3],
    max_mm: [f64; 3],
    grid_mm: Option<f64>,
}

impl StockSpec {
    /// Parses and checks a stock file's text; `path` names it in errors.
    ///
    /// # Errors
    /// See [`StockFileError`].
    pub fn from_toml_str(text: &str, path: &str) -> Result<Self, StockFileError> {
        let f: StockFile = toml::from_str(text).map_err(|e| StockFileError::Parse {
            path: path.to_string(),
            msg: vmc_machine::read::one_line_toml_error(&e),
        })?;
        let invalid = |err| StockFileError::Invalid {
            path: path.to_string(),
            err,
        };
        let stock = StockBox {
            min_mm: f.min_mm,
            max_mm: f.max_mm,
        };
        stock.validate().map_err(invalid)?;
        if let Some(g) = f.grid_mm {
            if !(g > 0.0 && g.is_finite()) {
                return Err(invalid(CuttingError::Spacing { spacing_mm: g }));
            }
        }
        Ok(Self {
            name: f.name.unwrap_or_else(|| path.to_string()),
            stock,
            grid_mm: f.grid_mm,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const GOOD: &str = "min_mm = [0, 0, -20]\nmax_mm = [80, 60, 0]\n";

    fn err(text: &str) -> String {
        StockSpec::from_toml_str(text, "s.toml")
            .unwrap_err()
            .to_string()
    }

    #[test]
    fn a_box_with_an_optional_grid_reads() {
        let s = StockSpec::from_toml_str(GOOD, "s.toml").unwrap();
        assert_eq!(s.stock.max_mm, [80.0, 60.0, 0.0]);
        assert_eq!((s.name.as_str(), s.grid_mm), ("s.toml", None));
        let s = StockSpec::from_toml_str(&format!("name = \"b\"\n{GOOD}grid_mm = 0.25"), "s.toml")
            .unwrap();
        assert_eq!((s.name.as_str(), s.grid_mm), ("b", Some(0.25)));
    }

    #[test]
    fn bad_stock_files_name_the_file_and_the_fault() {
        assert_eq!(
            err("min_mm = [0, 0, 0]\nmax_mm = [80, 60, 0]"),
            "s.toml: the stock box is empty along z: min_mm 0 must be below max_mm 0"
        );
        assert!(err(&format!("{GOOD}height_mm = 3")).contains("height_mm"));
        assert!(err("min_mm = [0, 0]\nmax_mm = [1, 1, 1]").starts_with("s.toml: "));
        assert_eq!(
            err(&format!("{GOOD}grid_mm = -1")),
            "s.toml: the grid spacing must be > 0 mm, got -1"
        );
    }
}
