//! G43.4: tool centre point control (Fanuc's G43.4, Heidenhain's M128/TCPM, Siemens' TRAORI;
//! LinuxCNC reaches it through switchable kinematics). While it is on, X, Y, Z are the tool
//! tip's position in the part frame and A, B, C the rotary axes' angles; the machine's inverse
//! kinematics, not the interpreter, turns each such pose into axis positions (see
//! [`super::super::run_program_tcp`]). G49, G43 and G43.1 (the same modal group) switch it off.
//!
//! Rules:
//! - G43.4 needs a machine with kinematics for it ([`InterpConfig::tcp_axes`]) and the tool's
//!   length (H, else the spindle's tool, from the tool table, > 0): the tool tip is what it
//!   controls. The length goes to the kinematics; Z targets are not shifted by it.
//! - The interpreter does not know the kinematics, so it cannot tell where the tip is when the
//!   frame changes: the first move after G43.4 is switched on or off must give X, Y and Z in
//!   G90.
//! - While it is on: a rotary word of an axis the machine lacks, G53, G28/G30, canned cycles,
//!   probe moves, cutter radius compensation and M6 are refused.
//!
//! Lengths in mm.

use super::super::decode::{Decoded, Distance, Motion, NonModal, ToolLength};
use super::{motion_col, Interpreter, MotionStep};
use crate::syntax::{Block, GcodeError};

/// Tool centre point control state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct TcpState {
    /// Which of A, B, C the machine has (`None`: no kinematics for G43.4).
    axes: Option<[bool; 3]>,
    /// Tool length while G43.4 is on, mm.
    length_mm: Option<f64>,
    /// The frame changed and no move has given the full position since.
    fresh: bool,
}

impl TcpState {
    /// The state at start-up: off.
    pub(super) fn new(axes: Option<[bool; 3]>) -> Self {
        Self {
            axes,
            length_mm: None,
            fresh: false,
        }
    }
}

impl Interpreter {
    /// The tool length under G43.4, mm; `None` when tool centre point control is off.
    pub fn tcp_length_mm(&self) -> Option<f64> {
        self.tcp.length_mm
    }

    /// The checks of a block that switches G43.4 on or off or runs under it.
    pub(super) fn check_tcp(
        &self,
        block: &Block,
        d: &Decoded,
        step: MotionStep,
    ) -> Result<(), GcodeError> {
        let line = block.line;
        let entering = match d.tool_length {
            Some((ToolLength::Tcp, col)) => Some(col),
            _ => None,
        };
        let leaving = self.tcp.length_mm.is_some() && d.tool_length.is_some() && entering.is_none();
        if let Some(col) = entering {
            let Some(_) = self.tcp.axes else {
                let msg = "G43.4 (tool centre point control) needs a five-axis machine's \
                           kinematics; this machine has none";
                return Err(GcodeError::invalid(line, col, msg));
            };
            let tool = d.h.map_or(self.spindle_tool, |h| h.value as u32);
            match self.tool_length_mm(tool) {
                Some(l) if l > 0.0 => {}
                _ => {
                    let msg = format!(
                        "G43.4 needs the tool's length: tool {tool} has none in the tool table"
                    );
                    return Err(GcodeError::invalid(line, col, msg));
                }
            }
            if self.comp.is_on() {
                let msg = "G43.4 with cutter radius compensation on is not supported";
                return Err(GcodeError::unsupported(line, col, msg));
            }
        }
        let on_after = entering.is_some() || (self.tcp.length_mm.is_some() && !leaving);
        if on_after {
            self.check_under_tcp(block, d, step)?;
        }
        let fresh = entering.is_some() || leaving || self.tcp.fresh;
        if let (true, MotionStep::Move(_)) = (fresh, step) {
            let absolute = d.distance.unwrap_or(self.distance) == Distance::Absolute;
            if !absolute || d.axes.iter().any(Option::is_none) {
                let col = motion_col(block, d);
                let msg = "the first move after G43.4 is switched on or off must give X, Y \
                           and Z in G90: the tool tip's place in the new frame";
                return Err(GcodeError::invalid(line, col, msg));
            }
        }
        Ok(())
    }

    /// What G43.4 refuses while it is on.
    fn check_under_tcp(
        &self,
        block: &Block,
        d: &Decoded,
        step: MotionStep,
    ) -> Result<(), GcodeError> {
        let line = block.line;
        let axes = self.tcp.axes.unwrap_or([true; 3]);
        for (i, w) in d.abc.iter().enumerate() {
            if let Some(w) = w.filter(|_| !axes[i]) {
                let msg = format!("G43.4: this machine has no {} axis", w.letter);
                return Err(GcodeError::invalid(line, w.col, msg));
            }
        }
        let refused = |col: usize, what: &str| {
            let msg = format!("{what} with G43.4 (tool centre point control) on is not supported");
            Err(GcodeError::unsupported(line, col, msg))
        };
        match d.non_modal {
            Some((NonModal::MachineCoords, col)) => return refused(col, "G53"),
            Some((NonModal::Home(_), col)) => return refused(col, "G28/G30"),
            _ => {}
        }
        if let MotionStep::Move(m @ (Motion::Cycle(_) | Motion::Probe(_))) = step {
            let what = if matches!(m, Motion::Cycle(_)) {
                "a canned cycle"
            } else {
                "a probe move"
            };
            return refused(motion_col(block, d), what);
        }
        if let Some((mode, col)) = d.cutter_comp {
            if mode != super::super::decode::CompMode::Off {
                return refused(col, "cutter radius compensation");
            }
        }
        if let Some(col) = d.tool_change {
            return refused(col, "M6");
        }
        Ok(())
    }

    /// Switches G43.4 on or off after the block's tool length code; a move of the block gives
    /// the full position (checked), so the frame is no longer fresh after it.
    pub(super) fn set_tcp(&mut self, d: &Decoded, step: MotionStep) {
        match d.tool_length {
            Some((ToolLength::Tcp, _)) => {
                let tool = d.h.map_or(self.spindle_tool, |h| h.value as u32);
                self.tcp.length_mm = self.tool_length_mm(tool);
                self.tcp.fresh = true;
            }
            Some(_) if self.tcp.length_mm.is_some() => {
                self.tcp.length_mm = None;
                self.tcp.fresh = true;
            }
            _ => {}
        }
        if let MotionStep::Move(_) = step {
            self.tcp.fresh = false;
        }
    }
}
