//! Block-level rules of cutter radius compensation (LinuxCNC's): the D word, the radius a
//! G41/G42 selects, and what a block may not do while compensation is on.

use super::decode::{CompMode, Decoded, NonModal};
use super::Plane;
use crate::syntax::{Block, GcodeError};

/// Side (+1 left, −1 right) and radius (mm) selected by a G41/G42/G41.1/G42.1 block.
/// `diameter_of` gives a tool's diameter from the table (`None`: not in it), `selected` is
/// the current tool, `mm_per_unit` converts a G41.1/G42.1 D word.
pub(super) fn selected_radius(
    block: &Block,
    d: &Decoded,
    col: usize,
    mode: CompMode,
    selected: u32,
    mm_per_unit: f64,
    diameter_of: impl Fn(u32) -> Option<f64>,
) -> Result<Option<(f64, f64)>, GcodeError> {
    let CompMode::On { left, given } = mode else {
        return Ok(None);
    };
    let side = if left { 1.0 } else { -1.0 };
    let g = match (left, given) {
        (true, false) => "G41",
        (false, false) => "G42",
        (true, true) => "G41.1",
        (false, true) => "G42.1",
    };
    if given {
        let Some(dw) = d.d else {
            let msg = format!("{g} needs a D word (tool diameter)");
            return Err(GcodeError::invalid(block.line, col, msg));
        };
        // A negative diameter puts the tool on the other side.
        let dia = dw.value * mm_per_unit;
        return Ok(Some((side * dia.signum(), dia.abs() / 2.0)));
    }
    let tool = match d.d {
        Some(w) if w.value < 0.0 || w.value.fract() != 0.0 => {
            let msg = format!("{g} D word must be a tool number (a non-negative integer)");
            return Err(GcodeError::invalid(block.line, w.col, msg));
        }
        // D0 and no D: the current tool.
        Some(w) if w.value > 0.0 => w.value as u32,
        _ => selected,
    };
    match diameter_of(tool) {
        Some(dia) => Ok(Some((side, dia / 2.0))),
        None => {
            let at = d.d.map_or(col, |w| w.col);
            let msg = format!("{g}: tool {tool} is not in the tool table");
            Err(GcodeError::invalid(block.line, at, msg))
        }
    }
}

/// Checks a block against the compensation state: `on_before` at the block's start,
/// `on_after` once its G40/G41/G42 has run, `plane` the plane before the block.
pub(super) fn check_block(
    block: &Block,
    d: &Decoded,
    on_before: bool,
    on_after: bool,
    plane: Plane,
) -> Result<(), GcodeError> {
    let line = block.line;
    let err = |col: usize, msg: &str| Err(GcodeError::invalid(line, col, msg));
    match (d.d, d.cutter_comp) {
        (Some(w), None | Some((CompMode::Off, _))) => {
            return err(w.col, "D word without G41, G42, G41.1 or G42.1 to use it");
        }
        (_, Some((CompMode::On { .. }, col))) => {
            if on_before {
                return err(col, "Cannot turn cutter radius comp on when on");
            }
            if d.plane.unwrap_or(plane) == Plane::Yz {
                return err(
                    col,
                    "Cutter radius compensation allowed only in XY, XZ planes",
                );
            }
        }
        _ => {}
    }
    if on_before {
        if let Some(col) = d.tool_change {
            return err(
                col,
                "Cannot change tools with cutter radius compensation on",
            );
        }
        if let Some((m, col)) = d.io {
            let msg = if m <= 53 {
                "Cannot change overrides with cutter radius compensation on"
            } else {
                "Cannot use digital or analog I/O with cutter radius compensation on"
            };
            return err(col, msg);
        }
        if d.plane.is_some_and(|p| p != plane) {
            let col = plane_col(block).unwrap_or(block.first_col);
            return err(
                col,
                "Cannot change planes with cutter radius compensation on",
            );
        }
    }
    if !on_after {
        return Ok(());
    }
    if let Some((_, col)) = d.tool_length {
        return err(
            col,
            "Cannot change tool offset with cutter radius compensation on",
        );
    }
    if d.coord_system.is_some() {
        let col = g_col(block, |c| (540..=590).contains(&c)).unwrap_or(block.first_col);
        return err(
            col,
            "Cannot change coordinate systems with cutter radius compensation on",
        );
    }
    let msg = match d.non_modal {
        Some((NonModal::Home(_), col)) => {
            Some((col, "Cannot use g28 or g30 with cutter radius comp"))
        }
        Some((NonModal::MachineCoords, col)) => {
            Some((col, "Cannot use g53 with cutter radius comp"))
        }
        Some((
            NonModal::SetAxisOffsets
            | NonModal::LocalOffsets
            | NonModal::ResetAxisOffsets
            | NonModal::SuspendAxisOffsets
            | NonModal::RestoreAxisOffsets,
            col,
        )) => Some((col, "Cannot change axis offsets with cutter radius comp")),
        _ => None,
    };
    match msg {
        Some((col, msg)) => err(col, msg),
        None => Ok(()),
    }
}

/// The column of the block's first G word whose code (×10) satisfies `pred`.
fn g_col(block: &Block, pred: impl Fn(u32) -> bool) -> Option<usize> {
    block
        .words
        .iter()
        .find(|w| w.letter == 'G' && w.code_x10().is_some_and(&pred))
        .map(|w| w.col)
}

fn plane_col(block: &Block) -> Option<usize> {
    g_col(block, |c| matches!(c, 170 | 180 | 190))
}
