//! Modal RS274/NGC interpreter: parsed blocks → canonical machine actions.
//!
//! (Types below are the contract between the interpreter and the motion planner.)

/// Active plane for arcs (G17 / G18 / G19).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    /// G17: arcs in XY, axis Z.
    Xy,
    /// G18: arcs in ZX, axis Y.
    Zx,
    /// G19: arcs in YZ, axis X.
    Yz,
}

/// Spindle state commanded by M3 / M4 / M5.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpindleDir {
    /// M3: clockwise.
    Cw,
    /// M4: counter-clockwise.
    Ccw,
    /// M5: stopped.
    Off,
}

/// One canonical action, in machine coordinates (mm, after unit conversion, G5x and G92 offsets).
#[derive(Debug, Clone, PartialEq)]
pub enum CanonKind {
    /// G0 rapid move to `end_mm` at the machine's rapid rate.
    Traverse { end_mm: [f64; 3] },
    /// G1 straight feed move to `end_mm`.
    Feed { end_mm: [f64; 3], feed_mm_per_min: f64 },
    /// G2/G3 arc (helix if the axis coordinate changes) from the current point to `end_mm`.
    Arc {
        end_mm: [f64; 3],
        /// Centre in machine coordinates; its coordinate along the plane's axis is the start's.
        center_mm: [f64; 3],
        plane: Plane,
        /// True for G2 (clockwise seen from the positive plane axis).
        clockwise: bool,
        /// Additional full turns (P word − 1); 0 for a plain arc.
        extra_turns: u32,
        feed_mm_per_min: f64,
    },
    /// G4 dwell.
    Dwell { duration_s: f64 },
    /// Spindle speed or direction change (S with M3/M4/M5 state). `rpm` is the programmed S.
    Spindle { dir: SpindleDir, rpm: f64 },
    /// M6 tool change to tool `tool`.
    ToolChange { tool: u32 },
    /// M2 / M30.
    ProgramEnd,
}

/// A canonical action with the source line (1-based) it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct CanonMove {
    /// 1-based line number in the source file.
    pub line: usize,
    /// What the machine must do.
    pub kind: CanonKind,
}
