//! Tables frozen at one thermal state, applied as a controller applies them: the compensator a
//! machine runs when it loads the exported tables and nothing else.
//!
//! **Model.** A table set ([`TableSet`]) holds corrections `c = −E` sampled from a model at one
//! thermal state (see the `sample` module). The controller adds them to the commanded axis
//! positions `p` (mm) at every interpolation cycle, looked up at the *commanded* position, not
//! at a fixed point of the model (LinuxCNC looks the joint table up at the joint's commanded
//! position; a CEC table at its base axis's setpoint):
//!
//! - per-joint tables ([`TableScope::OwnAxis`], a LinuxCNC `COMP_FILE` per joint):
//!   `q_k = p_k + c_k(p_k)`, with the forward column after a positive motion of axis `k` and
//!   the reverse column after a negative one;
//! - own-axis and cross tables ([`TableScope::OwnAndCross`], the CEC export):
//!   `q_j = p_j + c_j(p_j) + Σ_{k≠j} c_jk(p_k)`, the own table direction-dependent as above,
//!   the cross tables for both directions.
//!
//! Looking up at `p` instead of solving `q = p − E(q)` differs by `|∂E/∂q|·|E|` ≈ 0.5 nm (the
//! `sample` module doc): below the tables' 1 nm resolution.
//!
//! **Frozen.** The tables do not follow the machine: the sensor readings, the commanded spindle
//! speed and the axes' feeds reach [`TableCompensator`] (the [`Controller`] interface requires
//! it to say what it does with them) and change nothing, as a controller loading static tables
//! does. Only the commanded motion counts, for each axis's direction of motion, keyed exactly as
//! the live compensator keys its reversal ([`ApproachDirections`]).

use serde::{Deserialize, Serialize};
use vmc_predict::controller::{ApproachDirections, Controller};

use crate::number::Direction;
use crate::sample::TableSet;

/// Which of a set's tables a controller applies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum TableScope {
    /// The own-axis tables only: each axis corrected from its own position (LinuxCNC
    /// per-joint `COMP_FILE`s).
    OwnAxis,
    /// The own-axis and the cross tables (Siemens CEC with cross tables).
    OwnAndCross,
}

impl TableScope {
    /// Short name for reports: `per-joint` or `own+cross`.
    pub fn name(self) -> &'static str {
        match self {
            TableScope::OwnAxis => "per-joint",
            TableScope::OwnAndCross => "own+cross",
        }
    }
}

impl TableSet {
    /// The correction (mm, X, Y, Z) a controller adds to the commanded position `p_mm` (mm)
    /// with the tables of `scope`, each axis's own table in the column of its last direction
    /// of motion (`negative[k]`: axis `k` last moved in the negative direction).
    pub fn correction_mm(
        &self,
        p_mm: [f64; 3],
        negative: [bool; 3],
        scope: TableScope,
    ) -> [f64; 3] {
        std::array::from_fn(|j| {
            let direction = if negative[j] {
                Direction::Negative
            } else {
                Direction::Positive
            };
            let own = self.own_correction_mm(j, p_mm[j], direction);
            match scope {
                TableScope::OwnAxis => own,
                TableScope::OwnAndCross => {
                    own + (0..3)
                        .filter(|&k| k != j)
                        .map(|k| self.cross_correction_mm(j, k, p_mm[k]))
                        .sum::<f64>()
                }
            }
        })
    }
}

/// A controller that applies a frozen table set (module doc): the loop's [`Controller`], like
/// the live compensator, so that the same runs judge both.
#[derive(Debug, Clone)]
pub struct TableCompensator {
    tables: TableSet,
    scope: TableScope,
    directions: ApproachDirections,
}

impl TableCompensator {
    /// A compensator applying the tables of `scope` from `tables`.
    pub fn new(tables: TableSet, scope: TableScope) -> Self {
        Self {
            tables,
            scope,
            directions: ApproachDirections::default(),
        }
    }

    /// The tables.
    pub fn tables(&self) -> &TableSet {
        &self.tables
    }

    /// Which tables it applies.
    pub fn scope(&self) -> TableScope {
        self.scope
    }
}

impl Controller for TableCompensator {
    /// Frozen tables: the readings change nothing.
    fn on_readings(&mut self, _time_s: f64, _values_degc: &[f64]) {}

    /// Frozen tables: the spindle speed changes nothing.
    fn on_spindle_speed(&mut self, _time_s: f64, _rpm: f64) {}

    /// Frozen tables: the axes' feeds change nothing.
    fn on_axis_feeds(&mut self, _time_s: f64, _feeds_mm_per_min: [f64; 3]) {}

    /// The commanded motion sets each axis's direction (the column of its own table).
    fn on_commanded_motion(&mut self, start_mm: [f64; 3], end_mm: [f64; 3]) {
        self.directions.note_motion_segment_mm(start_mm, end_mm);
    }

    /// Tables are sampled for the tool of their thermal state: another tool needs other tables.
    fn on_tool_change(&mut self, tool_offset_mm: [f64; 3]) -> Result<(), String> {
        Err(format!(
            "static tables hold one tool's corrections: a tool change (to offset \
             {tool_offset_mm:?} mm) needs tables sampled for that tool"
        ))
    }

    /// `p + c(p)` with the tables of the scope (module doc); `p_mm` also counts as commanded
    /// motion for the directions.
    fn axis_command_mm(&mut self, p_mm: [f64; 3]) -> [f64; 3] {
        self.directions.note_commanded_mm(p_mm);
        let c = self
            .tables
            .correction_mm(p_mm, self.directions.negative(), self.scope);
        [p_mm[0] + c[0], p_mm[1] + c[1], p_mm[2] + c[2]]
    }
}

#[cfg(test)]
mod tests;
