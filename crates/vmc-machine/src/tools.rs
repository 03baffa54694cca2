//! Tool tables: the tools a program may load with `M6`, by number.
//!
//! A tool table file is TOML, one `[[tool]]` table per tool with `number`, `length_mm` (spindle
//! gauge line to the tip) and `diameter_mm`. Without a table, every tool number is the machine
//! file's own tool (`[tool]`).
//!
//! Two readers, two conventions for the lengths:
//! - `interpret` gives the interpreter the lengths as they are, as LinuxCNC's `rs274` reads its
//!   table, so that the two print the same moves.
//! - `run` and `check` run on the twin, whose axis positions are those of the machine file's own
//!   tool tip (its master tool): the interpreter gets each length minus the master's
//!   ([`ToolTable::interp_data`]). A program that loads the master tool, or runs without `G43`
//!   and without a tool change, moves exactly as before; a longer tool loaded without `G43`
//!   reaches lower by the difference, as on a real machine. After `M6` the twin's tool tip (its
//!   errors, and the bodies `check` tests) is that of the loaded tool.

use std::path::Path;

use serde::Deserialize;
use thiserror::Error;

use crate::machine::MachineSpec;

/// Tool numbers that stand for the machine's own tool when no table is given (cutter radius
/// compensation `D` needs a diameter per number).
pub const TOOL_NUMBERS: u32 = 1000;

/// One tool.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tool {
    /// Tool number (`T`, `H`, `D` words).
    pub number: u32,
    /// Gauge line to tip, mm.
    pub length_mm: f64,
    /// Cutting diameter, mm.
    pub diameter_mm: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TableFile {
    tool: Vec<Tool>,
}

/// A tool table; empty means "every tool is the machine's own".
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ToolTable {
    tools: Vec<Tool>,
}

/// Tool lengths and diameters, mm, by tool number, as the interpreter takes them.
pub type ToolData = (Vec<(u32, f64)>, Vec<(u32, f64)>);

impl ToolTable {
    /// Parses a tool table; `file` names it in errors.
    ///
    /// # Errors
    /// Bad TOML or an unknown field, a tool given twice, a length that is not finite within
    /// ±10,000 mm, a diameter that is not a finite number ≥ 0.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, ToolTableError> {
        let table: TableFile = toml::from_str(text).map_err(|e| ToolTableError::Toml {
            file: file.to_string(),
            message: crate::read::one_line_toml_error(&e),
        })?;
        for (i, t) in table.tool.iter().enumerate() {
            let bad = |field| ToolTableError::Value {
                file: file.to_string(),
                number: t.number,
                field,
            };
            if table.tool[..i].iter().any(|o| o.number == t.number) {
                return Err(ToolTableError::Twice {
                    file: file.to_string(),
                    number: t.number,
                });
            }
            if !t.length_mm.is_finite() || t.length_mm.abs() > 1e4 {
                return Err(bad("length_mm must be finite within ±10000 mm"));
            }
            if !(t.diameter_mm.is_finite() && t.diameter_mm >= 0.0) {
                return Err(bad("diameter_mm must be a finite number >= 0"));
            }
        }
        Ok(Self { tools: table.tool })
    }

    /// Reads a tool table file.
    ///
    /// # Errors
    /// An unreadable file, or as [`ToolTable::from_toml_str`].
    pub fn load(path: &Path) -> Result<Self, ToolTableError> {
        let text = crate::read::read_named(path, "tool table")?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// True when no table was given.
    pub fn is_empty(&self) -> bool {
        self.tools.is_empty()
    }

    /// The tools, in file order.
    pub fn tools(&self) -> &[Tool] {
        &self.tools
    }

    /// Lengths and diameters as written (for `interpret`, as `rs274` reads its table).
    pub fn absolute_data(&self) -> ToolData {
        (
            self.tools.iter().map(|t| (t.number, t.length_mm)).collect(),
            self.tools
                .iter()
                .map(|t| (t.number, t.diameter_mm))
                .collect(),
        )
    }

    /// What the interpreter gets in `run` and `check` on `machine`: each length minus the
    /// machine's own tool length (see the module doc), each diameter as is; without a table,
    /// length offsets of 0 for every tool and the machine's tool diameter for tool numbers
    /// 0…[`TOOL_NUMBERS`]−1.
    pub fn interp_data(&self, machine: &MachineSpec) -> ToolData {
        if self.tools.is_empty() {
            let d = machine.tool.diameter_mm;
            return (Vec::new(), (0..TOOL_NUMBERS).map(|n| (n, d)).collect());
        }
        let master_mm = master_length_mm(machine);
        (
            self.tools
                .iter()
                .map(|t| (t.number, t.length_mm - master_mm))
                .collect(),
            self.tools
                .iter()
                .map(|t| (t.number, t.diameter_mm))
                .collect(),
        )
    }

    /// The tool that `M6` with `number` loads on `machine`: the table's, or the machine's own
    /// when there is no table; `None` for a number missing from a given table.
    pub fn loaded(&self, number: u32, machine: &MachineSpec) -> Option<Tool> {
        if self.tools.is_empty() {
            return Some(Tool {
                number,
                length_mm: master_length_mm(machine),
                diameter_mm: machine.tool.diameter_mm,
            });
        }
        self.tools.iter().copied().find(|t| t.number == number)
    }
}

/// Length of the machine file's own tool (gauge line to tip along the spindle axis), mm.
pub fn master_length_mm(machine: &MachineSpec) -> f64 {
    -machine.tool.offset_mm[2]
}

/// A tool table that cannot be used.
#[derive(Debug, Error)]
pub enum ToolTableError {
    /// The file could not be read.
    #[error(transparent)]
    Read(#[from] crate::read::ReadError),
    /// Not TOML, or not a tool table's fields.
    #[error("{file}: {message}")]
    Toml {
        /// The file.
        file: String,
        /// The parser's message, on one line.
        message: String,
    },
    /// A tool number given twice.
    #[error("{file}: tool {number} appears twice")]
    Twice {
        /// The file.
        file: String,
        /// The tool number.
        number: u32,
    },
    /// A length or diameter out of range.
    #[error("{file}: tool {number}: {field}")]
    Value {
        /// The file.
        file: String,
        /// The tool number.
        number: u32,
        /// Which value and its range.
        field: &'static str,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: &str = "[[tool]]\nnumber = 1\nlength_mm = 150.0\ndiameter_mm = 12.0\n\n\
                         [[tool]]\nnumber = 2\nlength_mm = 100.0\ndiameter_mm = 6.0\n";

    #[test]
    fn run_lengths_are_relative_to_the_machine_tool_and_interpret_lengths_absolute() {
        let m = MachineSpec::reference();
        let t = ToolTable::from_toml_str(TABLE, "t.toml").unwrap();
        assert_eq!(t.interp_data(&m).0, vec![(1, 0.0), (2, -50.0)]);
        assert_eq!(t.absolute_data().0, vec![(1, 150.0), (2, 100.0)]);
        assert_eq!(t.loaded(2, &m).unwrap().diameter_mm, 6.0);
        assert!(t.loaded(3, &m).is_none());
        // No table: every number is the machine's own tool.
        let none = ToolTable::default();
        assert_eq!(none.loaded(7, &m).unwrap().length_mm, 150.0);
        let (lengths, diameters) = none.interp_data(&m);
        assert!(lengths.is_empty());
        assert_eq!(diameters[7], (7, m.tool.diameter_mm));
    }

    #[test]
    fn bad_tables_name_the_file_and_the_tool() {
        let twice = format!("{TABLE}\n[[tool]]\nnumber = 2\nlength_mm = 1.0\ndiameter_mm = 1.0\n");
        let e = ToolTable::from_toml_str(&twice, "t.toml").unwrap_err();
        assert_eq!(e.to_string(), "t.toml: tool 2 appears twice");
        let e = ToolTable::from_toml_str(&TABLE.replace("6.0", "-6.0"), "t.toml").unwrap_err();
        assert!(e.to_string().contains("tool 2: diameter_mm"), "{e}");
        let e = ToolTable::from_toml_str("[[tool]]\nnumber = 1\n", "t.toml").unwrap_err();
        assert!(format!("{e:#}").contains("missing field"), "{e:#}");
    }
}
