//! Program coordinates ↔ machine coordinates: work offsets G54…G59.3 with their XY rotation
//! (G10 L2/L20 R), the G92 offset and the tool length offset.
//!
//! Model (as LinuxCNC places a program point, checked against its interpreter on the rotation
//! cases of its test suite), all lengths in mm:
//!
//! `p_machine = Rz(θ)·(p_program + g92) + g5x + (0, 0, tool_length)`
//!
//! with θ the rotation of the active coordinate system about its origin (degrees in the
//! program, counter-clockwise seen from +Z). Z is never rotated.

use super::super::decode::{Decoded, Distance};
use super::Interpreter;

/// Number of work coordinate systems: G54…G59, G59.1…G59.3.
pub(in crate::interp) const COORD_SYSTEMS: usize = super::super::WORK_OFFSETS;

/// `v` rotated by `angle_deg` about Z (X and Y only).
fn rotate_xy(v: [f64; 3], angle_deg: f64) -> [f64; 3] {
    if angle_deg == 0.0 {
        return v;
    }
    let (sin, cos) = angle_deg.to_radians().sin_cos();
    [v[0] * cos - v[1] * sin, v[0] * sin + v[1] * cos, v[2]]
}

impl Interpreter {
    /// Rotation of the active coordinate system, degrees (0: none).
    pub(super) fn rotation_deg(&self) -> f64 {
        self.rotations_deg[self.coord_index]
    }

    /// A program point (mm, in the active coordinate system, G92 included) on the machine.
    pub(super) fn machine_from_program(&self, p_mm: [f64; 3]) -> [f64; 3] {
        let q = [0, 1, 2].map(|a| p_mm[a] + self.axis_offset_mm[a]);
        let r = rotate_xy(q, self.rotation_deg());
        [0, 1, 2].map(|a| r[a] + self.work_offsets_mm[self.coord_index][a] + self.tlo_mm(a))
    }

    /// A machine point in program coordinates (mm); the inverse of
    /// [`Self::machine_from_program`].
    pub(super) fn program_from_machine(&self, m_mm: [f64; 3]) -> [f64; 3] {
        let q =
            [0, 1, 2].map(|a| m_mm[a] - self.work_offsets_mm[self.coord_index][a] - self.tlo_mm(a));
        let r = rotate_xy(q, -self.rotation_deg());
        [0, 1, 2].map(|a| r[a] - self.axis_offset_mm[a])
    }

    /// A machine point in the active work offset's unrotated frame:
    /// `g5x + Rz(−θ)·(p_machine − g5x)` (XY only).
    pub(super) fn unrotated_from_machine(&self, m_mm: [f64; 3]) -> [f64; 3] {
        let o = self.work_offsets_mm[self.coord_index];
        let r = rotate_xy(
            [m_mm[0] - o[0], m_mm[1] - o[1], m_mm[2]],
            -self.rotation_deg(),
        );
        [r[0] + o[0], r[1] + o[1], r[2]]
    }

    /// The inverse of [`Self::unrotated_from_machine`].
    pub(super) fn machine_from_unrotated(&self, u_mm: [f64; 3]) -> [f64; 3] {
        let o = self.work_offsets_mm[self.coord_index];
        let r = rotate_xy(
            [u_mm[0] - o[0], u_mm[1] - o[1], u_mm[2]],
            self.rotation_deg(),
        );
        [r[0] + o[0], r[1] + o[1], r[2]]
    }

    /// Program-to-machine offset (G5x + G92 + tool length) along `axis`, mm, when the
    /// coordinate system is not rotated.
    pub(super) fn offset_mm(&self, axis: usize) -> f64 {
        self.work_offsets_mm[self.coord_index][axis] + self.axis_offset_mm[axis] + self.tlo_mm(axis)
    }

    /// Tool length offset along `axis`, mm (Z only).
    pub(super) fn tlo_mm(&self, axis: usize) -> f64 {
        if axis == 2 {
            self.tool_offset_mm
        } else {
            0.0
        }
    }

    /// G92: offsets such that the current point gets the programmed coordinates.
    pub(super) fn set_axis_offsets(&mut self, d: &Decoded) {
        let here = self.program_from_machine(self.pos_mm);
        for (axis, word) in d.axes.iter().enumerate() {
            if let Some(w) = word {
                // `here + g92` is the point in the unshifted (but rotated) frame.
                let unshifted = here[axis] + self.axis_offset_mm[axis];
                self.axis_offset_mm[axis] = unshifted - w.value * self.scale();
            }
        }
    }

    /// G10 L2 (offsets given) / L20 (offsets such that the current point has the given
    /// coordinates) for work offset P (0 = the active one), R its rotation. Values are absolute
    /// (G91 ignored).
    pub(super) fn set_coord_data(&mut self, d: &Decoded) {
        let l20 = d.l.is_some_and(|l| l.value == 20.0);
        let p = d.p.map_or(0, |p| p.value.round() as usize);
        let index = if p == 0 { self.coord_index } else { p - 1 };
        let k = self.scale();
        if !l20 {
            for (axis, word) in d.axes.iter().enumerate() {
                if let Some(w) = word {
                    self.work_offsets_mm[index][axis] = w.value * k;
                }
            }
            if let Some(r) = d.r {
                self.rotations_deg[index] = r.value;
            }
            self.set_rotary_coord_data(d, index, false);
            return;
        }
        // L20 (R is refused with it): where the current point is in system `index` (its
        // offsets and rotation, G92 and the tool length), with the given coordinates replaced.
        let active = self.coord_index;
        self.coord_index = index;
        let mut p_mm = self.program_from_machine(self.pos_mm);
        for (axis, word) in d.axes.iter().enumerate() {
            if let Some(w) = word {
                p_mm[axis] = w.value * k;
            }
        }
        let q = [0, 1, 2].map(|a| p_mm[a] + self.axis_offset_mm[a]);
        let rotated = rotate_xy(q, self.rotations_deg[index]);
        // In a rotated system, X and Y of the offset both follow from the point's X and Y.
        let rotated_xy = self.rotations_deg[index] != 0.0;
        let xy_given = d.axes[0].is_some() || d.axes[1].is_some();
        for (axis, word) in d.axes.iter().enumerate() {
            if word.is_some() || (axis < 2 && rotated_xy && xy_given) {
                self.work_offsets_mm[index][axis] =
                    self.pos_mm[axis] - rotated[axis] - self.tlo_mm(axis);
            }
        }
        self.coord_index = active;
        self.set_rotary_coord_data(d, index, true);
    }

    /// End point of a move, machine coordinates, mm. Uses the block's units/distance modes,
    /// which are already applied when this runs.
    pub(super) fn target_mm(&self, d: &Decoded, machine: bool) -> [f64; 3] {
        let k = self.scale();
        let incremental = self.distance == Distance::Incremental;
        if machine || self.rotation_deg() == 0.0 {
            // Axis by axis: axes without a word stay exactly where they are.
            let mut end = self.pos_mm;
            for (axis, word) in d.axes.iter().enumerate() {
                if let Some(w) = word {
                    let v_mm = w.value * k;
                    end[axis] = if machine {
                        v_mm
                    } else if incremental {
                        self.pos_mm[axis] + v_mm
                    } else {
                        v_mm + self.offset_mm(axis)
                    };
                }
            }
            return end;
        }
        if !d.has_xyz_words() {
            return self.pos_mm;
        }
        let mut p_mm = self.program_from_machine(self.pos_mm);
        for (axis, word) in d.axes.iter().enumerate() {
            if let Some(w) = word {
                p_mm[axis] = if incremental { p_mm[axis] } else { 0.0 } + w.value * k;
            }
        }
        self.machine_from_program(p_mm)
    }

    /// Arc centre from I/J/K words (absolute under G90.1, else from the start), machine
    /// coordinates, mm: the plane coordinates `[a1, a2]`.
    pub(super) fn arc_centre_mm(&self, d: &Decoded, a1: usize, a2: usize) -> [f64; 2] {
        let k = self.scale();
        if self.rotation_deg() == 0.0 {
            return [a1, a2].map(|axis| match (self.arc_distance, d.ijk[axis]) {
                (Distance::Absolute, Some(w)) => w.value * k + self.offset_mm(axis),
                (_, w) => self.pos_mm[axis] + w.map_or(0.0, |w| w.value * k),
            });
        }
        let mut c_mm = self.program_from_machine(self.pos_mm);
        for axis in [a1, a2] {
            c_mm[axis] = match (self.arc_distance, d.ijk[axis]) {
                (Distance::Absolute, Some(w)) => w.value * k,
                (_, w) => c_mm[axis] + w.map_or(0.0, |w| w.value * k),
            };
        }
        let m = self.machine_from_program(c_mm);
        [m[a1], m[a2]]
    }
}
