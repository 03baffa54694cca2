//! Read-only parameters that report the interpreter's state, as LinuxCNC sets them before
//! each block: #5400 the tool in the spindle, #5403 its length and #5410 its diameter (from
//! the tool table), #5420…#5428 the current point X Y Z A B C U V W in the active work
//! coordinates (work offset, G92 offset, XY rotation and tool length removed), and the named
//! `#<_x>` … `#<_w>` (the same point), `#<_current_tool>`, `#<_selected_tool>`. Lengths in
//! the program's current units, angles in degrees; U V W are always 0 (no such axes).

use super::super::expr::Params;
use super::Interpreter;

/// The named parameters of the current point, in the order of #5420…#5428.
const POSITION_NAMES: [&str; 9] = ["_x", "_y", "_z", "_a", "_b", "_c", "_u", "_v", "_w"];

impl Interpreter {
    /// Writes the state parameters (see the module documentation).
    pub(super) fn sync_state_params_out(&self, params: &mut Params) {
        let k = self.scale();
        let tool = self.spindle_tool;
        params.set(5400, f64::from(tool));
        params.set(5403, self.tools.length_mm(tool).unwrap_or(0.0) / k);
        params.set(5410, self.tools.diameter_mm(tool).unwrap_or(0.0) / k);
        let p_mm = self.program_from_machine(self.pos_mm);
        let mut point = [0.0; 9];
        for a in 0..3 {
            point[a] = p_mm[a] / k;
            point[3 + a] = self.rotary.pos_deg[a] - self.rotary_offset_deg(a);
        }
        for (i, v) in point.into_iter().enumerate() {
            params.set(5420 + i, v);
            params.set_global(POSITION_NAMES[i], v);
        }
        params.set_global("_current_tool", f64::from(tool));
        params.set_global("_selected_tool", f64::from(self.selected_tool));
    }
}
