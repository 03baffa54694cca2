//! M70 (save the modal state), M71 (forget it), M72 (restore it), M73 (save it and restore it
//! when the current subroutine returns), as LinuxCNC does.
//!
//! Saved: units, plane, distance and arc-distance modes, work offset, feed mode, F, S,
//! spindle direction, coolant, canned cycle return level (G98/G99). Not saved: the motion
//! mode, the position, offsets' values, the tool. Each subroutine call level has its own slot:
//! a state saved inside a subroutine is gone when it returns, and M72 with nothing saved at
//! the current level is an error.

use super::super::decode::{Distance, FeedMode, Retract, Units};
use super::super::{CanonKind, Plane, SpindleDir};
use super::Interpreter;
use crate::syntax::GcodeError;

/// One saved modal state.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Saved {
    units: Units,
    plane: Plane,
    distance: Distance,
    arc_distance: Distance,
    coord_index: usize,
    feed_mode: FeedMode,
    feed_mm_per_min: f64,
    spindle: (SpindleDir, f64),
    coolant: (bool, bool),
    retract: Retract,
}

/// The saved states, one slot per call level (index 0: the main program), and whether the
/// slot is restored automatically at the level's return (M73).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Contexts(Vec<Option<(Saved, bool)>>);

impl Default for Contexts {
    fn default() -> Self {
        Self(vec![None])
    }
}

impl Interpreter {
    fn saved_state(&self) -> Saved {
        Saved {
            units: self.units,
            plane: self.plane,
            distance: self.distance,
            arc_distance: self.arc_distance,
            coord_index: self.coord_index,
            feed_mode: self.feed_mode,
            feed_mm_per_min: self.feed_mm_per_min,
            spindle: self.spindle,
            coolant: self.coolant,
            retract: self.cycle.retract,
        }
    }

    fn restore_state(&mut self, s: &Saved, emit: &mut impl FnMut(CanonKind)) {
        self.units = s.units;
        self.plane = s.plane;
        self.distance = s.distance;
        self.arc_distance = s.arc_distance;
        self.coord_index = s.coord_index;
        self.feed_mode = s.feed_mode;
        self.feed_mm_per_min = s.feed_mm_per_min;
        self.spindle = s.spindle;
        self.report_spindle(emit);
        if self.coolant != s.coolant {
            self.coolant = s.coolant;
            emit(CanonKind::Coolant {
                mist: s.coolant.0,
                flood: s.coolant.1,
            });
        }
        self.cycle.retract = s.retract;
    }

    /// Runs M70 … M73 (`m`) of a block.
    pub(super) fn modal_state_code(
        &mut self,
        m: u32,
        line: usize,
        col: usize,
        emit: &mut impl FnMut(CanonKind),
    ) -> Result<(), GcodeError> {
        let saved = self.saved_state();
        let slot = self.contexts.0.last_mut().expect("the main program's slot");
        match m {
            70 => *slot = Some((saved, false)),
            71 => *slot = None,
            73 => *slot = Some((saved, true)),
            _ => {
                let Some((s, _)) = slot.clone() else {
                    return Err(GcodeError::invalid(
                        line,
                        col,
                        "M72: no modal state saved (M70 or M73) at this call level",
                    ));
                };
                self.restore_state(&s, emit);
            }
        }
        Ok(())
    }

    /// A subroutine call starts a new level (no state saved yet).
    pub(crate) fn enter_call(&mut self) {
        self.contexts.0.push(None);
    }

    /// A subroutine returns: its level ends, restoring the state saved by M73 there. Returns
    /// the actions of the restoration.
    pub(crate) fn leave_call(&mut self) -> Vec<CanonKind> {
        let mut out = Vec::new();
        if self.contexts.0.len() > 1 {
            if let Some((s, true)) = self.contexts.0.pop().flatten() {
                self.restore_state(&s, &mut |k| out.push(k));
            }
        }
        out
    }
}
