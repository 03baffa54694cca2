//! The rotary axes A, B, C, as LinuxCNC's interpreter treats them: three more coordinates in
//! degrees, each independent of the others and of X, Y, Z.
//!
//! `a_machine_deg = a_program + g5x_deg + g92_deg` (G53: `a_machine_deg = a_program`; G91:
//! `a_machine_deg += Δ`). Angles are not scaled by G20/G21, not turned by the XY rotation of
//! `G10 L2 R` and not shifted by the tool length. Work offsets (`G10 L2/L20`), `G92`, `G52`,
//! `G92.1`–`G92.3` and the `G28`/`G30` positions carry A, B, C like X, Y, Z; their parameters
//! are LinuxCNC's (#5164–#5166, #5184–#5186, #5214–#5216, #5224–#5226 for G54, …).

use super::super::decode::{Decoded, Distance};
use super::{Interpreter, COORD_SYSTEMS};

/// The rotary part of the modal state, degrees.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct RotaryState {
    /// Current A, B, C, machine coordinates, degrees.
    pub(super) pos_deg: [f64; 3],
    /// Work offsets G54…G59.3 of A, B, C, degrees.
    pub(super) g5x_deg: [[f64; 3]; COORD_SYSTEMS],
    /// Active G92 offset of A, B, C, degrees.
    pub(super) g92_deg: [f64; 3],
    /// Stored G92 offset (G92.2 suspends the active one, G92.3 restores it from here).
    pub(super) g92_saved_deg: [f64; 3],
    /// G28 and G30 positions of A, B, C, machine coordinates, degrees.
    pub(super) homes_deg: [[f64; 3]; 2],
}

impl RotaryState {
    /// The start-up state: at `start_deg`, every offset zero.
    pub(super) fn new(start_deg: [f64; 3]) -> Self {
        Self {
            pos_deg: start_deg,
            g5x_deg: [[0.0; 3]; COORD_SYSTEMS],
            g92_deg: [0.0; 3],
            g92_saved_deg: [0.0; 3],
            homes_deg: [[0.0; 3]; 2],
        }
    }
}

impl Interpreter {
    /// Program-to-machine offset of rotary axis `axis` (0 = A), degrees.
    pub(super) fn rotary_offset_deg(&self, axis: usize) -> f64 {
        self.rotary.g5x_deg[self.coord_index][axis] + self.rotary.g92_deg[axis]
    }

    /// End angles of a move (machine coordinates, degrees): axes without a word stay.
    pub(super) fn target_abc_deg(&self, d: &Decoded, machine: bool) -> [f64; 3] {
        let incremental = self.distance == Distance::Incremental;
        let mut end = self.rotary.pos_deg;
        for (axis, word) in d.abc.iter().enumerate() {
            if let Some(w) = word {
                end[axis] = if machine {
                    w.value
                } else if incremental {
                    self.rotary.pos_deg[axis] + w.value
                } else {
                    w.value + self.rotary_offset_deg(axis)
                };
            }
        }
        end
    }

    /// G92 for A, B, C: offsets such that the current angles get the programmed values.
    pub(super) fn set_rotary_axis_offsets(&mut self, d: &Decoded) {
        for (axis, word) in d.abc.iter().enumerate() {
            if let Some(w) = word {
                let unshifted =
                    self.rotary.pos_deg[axis] - self.rotary.g5x_deg[self.coord_index][axis];
                self.rotary.g92_deg[axis] = unshifted - w.value;
            }
        }
    }

    /// G52 for A, B, C: the G92 offsets set to the given values.
    pub(super) fn set_rotary_local_offsets(&mut self, d: &Decoded) {
        for (axis, word) in d.abc.iter().enumerate() {
            if let Some(w) = word {
                self.rotary.g92_deg[axis] = w.value;
            }
        }
    }

    /// G10 L2 (offsets given) / L20 (offsets such that the current angles read the given
    /// values, the G92 offset included) for A, B, C of work offset `index`.
    pub(super) fn set_rotary_coord_data(&mut self, d: &Decoded, index: usize, l20: bool) {
        for (axis, word) in d.abc.iter().enumerate() {
            if let Some(w) = word {
                self.rotary.g5x_deg[index][axis] = if l20 {
                    self.rotary.pos_deg[axis] - self.rotary.g92_deg[axis] - w.value
                } else {
                    w.value
                };
            }
        }
    }

    /// Reads the rotary parameters (see the module doc).
    pub(super) fn sync_rotary_params_in(&mut self, params: &super::super::expr::Params) {
        for a in 0..3 {
            self.rotary.homes_deg[0][a] = params.get(5164 + a);
            self.rotary.homes_deg[1][a] = params.get(5184 + a);
            self.rotary.g92_saved_deg[a] = params.get(5214 + a);
            for (i, offset) in self.rotary.g5x_deg.iter_mut().enumerate() {
                offset[a] = params.get(5224 + 20 * i + a);
            }
        }
    }

    /// Writes the rotary parameters (see the module doc).
    pub(super) fn sync_rotary_params_out(&self, params: &mut super::super::expr::Params) {
        for a in 0..3 {
            params.set(5164 + a, self.rotary.homes_deg[0][a]);
            params.set(5184 + a, self.rotary.homes_deg[1][a]);
            params.set(5214 + a, self.rotary.g92_saved_deg[a]);
            for (i, offset) in self.rotary.g5x_deg.iter().enumerate() {
                params.set(5224 + 20 * i + a, offset[a]);
            }
        }
    }
}
