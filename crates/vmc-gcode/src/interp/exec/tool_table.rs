//! The interpreter's tool table: lengths and diameters from [`InterpConfig`], changed by
//! G10 L1 (values given), L10 (length such that the current point has the given Z in the
//! active coordinate system, G92 included) and L11 (the same in G59.3, without G92), as
//! LinuxCNC's G10 tool forms do. Lengths and diameters in mm.
//!
//! A table left empty in the configuration is open: every tool has length (or diameter) 0
//! until a G10 sets it. Tool 0 (no tool) has length and diameter 0 unless listed.

use super::super::decode::Decoded;
use super::super::InterpConfig;
use super::Interpreter;
use crate::syntax::GcodeError;

/// Tool lengths and diameters by tool number, mm.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ToolTable {
    lengths_mm: Vec<(u32, f64)>,
    diameters_mm: Vec<(u32, f64)>,
    /// No lengths configured: unknown tools have length 0.
    lengths_open: bool,
    /// No diameters configured: unknown tools have diameter 0.
    diameters_open: bool,
}

/// A tool's value; tool 0 (no tool in the spindle) has 0 unless the table lists it.
fn find(table: &[(u32, f64)], open: bool, tool: u32) -> Option<f64> {
    match table.iter().find(|t| t.0 == tool) {
        Some(t) => Some(t.1),
        None => (open || tool == 0).then_some(0.0),
    }
}

fn put(table: &mut Vec<(u32, f64)>, tool: u32, value: f64) {
    match table.iter_mut().find(|t| t.0 == tool) {
        Some(t) => t.1 = value,
        None => table.push((tool, value)),
    }
}

impl ToolTable {
    /// The table of a configuration.
    pub(super) fn new(cfg: &InterpConfig) -> Self {
        Self {
            lengths_mm: cfg.tool_lengths_mm.clone(),
            diameters_mm: cfg.tool_diameters_mm.clone(),
            lengths_open: cfg.tool_lengths_mm.is_empty(),
            diameters_open: cfg.tool_diameters_mm.is_empty(),
        }
    }

    /// Length of `tool`, mm; `None` if the table does not hold it.
    pub(super) fn length_mm(&self, tool: u32) -> Option<f64> {
        find(&self.lengths_mm, self.lengths_open, tool)
    }

    /// True if G10 may write `tool`: the table lists it, or no table was configured.
    pub(super) fn holds(&self, tool: u32) -> bool {
        let listed = |t: &[(u32, f64)]| t.iter().any(|e| e.0 == tool);
        listed(&self.lengths_mm)
            || listed(&self.diameters_mm)
            || (self.lengths_open && self.diameters_open)
    }

    /// Diameter of `tool`, mm; `None` if the table does not hold it.
    pub(super) fn diameter_mm(&self, tool: u32) -> Option<f64> {
        find(&self.diameters_mm, self.diameters_open, tool)
    }
}

impl Interpreter {
    /// G10 L1 / L10 / L11 P(tool) Z R (words checked in `check_g10`). A tool the table does
    /// not hold is an error, as in LinuxCNC.
    pub(super) fn set_tool_data(
        &mut self,
        d: &Decoded,
        line: usize,
        col: usize,
    ) -> Result<(), GcodeError> {
        let l = d.l.map_or(1.0, |l| l.value);
        let tool = d.p.map_or(0, |p| p.value as u32);
        let col = d.p.map_or(col, |p| p.col);
        if !self.tools.holds(tool) {
            let msg = format!("Requested tool {tool} not found in the tool table");
            return Err(GcodeError::invalid(line, col, msg));
        }
        let k = self.scale();
        if let Some(z) = d.axes[2] {
            let v_mm = z.value * k;
            let length_mm = if l == 1.0 {
                v_mm
            } else if l == 10.0 {
                // The current point reads Z = v with this length in effect.
                let g5x = self.work_offsets_mm[self.coord_index][2];
                self.pos_mm[2] - g5x - self.axis_offset_mm[2] - v_mm
            } else {
                // L11: the same in G59.3 (the tool-setting fixture), G92 not included.
                self.pos_mm[2] - self.work_offsets_mm[8][2] - v_mm
            };
            put(&mut self.tools.lengths_mm, tool, length_mm);
        }
        if let Some(r) = d.r {
            put(&mut self.tools.diameters_mm, tool, 2.0 * r.value * k);
        }
        Ok(())
    }
}
