//! Modal RS274/NGC interpreter: parsed blocks ([`crate::syntax`]) → canonical machine actions
//! ([`CanonMove`]), the contract with the motion planner.
//!
//! Model: LinuxCNC's interpreter restricted to a 3-axis mill. The modal state (plane, units,
//! distance modes, work offset, G92 offset, motion mode, feed mode, feed, spindle, selected
//! tool, canned cycle return level) starts as LinuxCNC starts a metric machine: G17 G21 G90
//! G91.1 (incremental I/J/K) G54 G80 (no motion mode) G94 G99, feed 0, spindle stopped at S0,
//! tool 0, at [`InterpConfig::start_mm`].
//!
//! Units: every output length is a machine coordinate in mm, every feed in mm/min:
//! `p_machine_mm = k·p_program + g5x_offset_mm + g92_offset_mm` with k = 25.4 under G20,
//! 1 under G21 (G53 moves use `p_machine_mm = k·p_program`; G91 adds `k·Δ` to the current
//! machine position). An F word is read in the units active when it is executed (RS274/NGC
//! order: before this block's G20/G21) and stored in mm/min.
//!
//! Execution order inside a block (RS274/NGC §3.8): G93/G94/G95, F, S, T, M6, M3/M4/M5,
//! M7/M8/M9, M70–M73, G4, G17–G19, G20/G21, G40/G41/G42, G43/G49, G54–G59, G61/G61.1/G64,
//! G90/G91, G90.1/G91.1, G10/G28/G30/G28.1/G30.1/G92/G92.1/G92.2/G92.3, G98/G99, motion (G0–G3,
//! G38.2–G38.5, G53, canned cycles), M0/M1/M60/M2/M30.
//! A rejected block has no effect: it runs on a copy of the state that is kept only on success.
//! Arc centres and tolerances follow LinuxCNC exactly (see `arc`); every number must satisfy
//! |value| ≤ 1e9 so that all results stay finite.
//!
//! Parameters, expressions and O-word control flow: see `expr` and `flow`. Values are
//! evaluated, and parameter settings applied, before the block executes.
//!
//! Spindle: one [`CanonKind::Spindle`] is emitted per block when the (direction, speed) pair
//! differs from the one last emitted (an S word alone while stopped is reported with `Off`).
//! M6 stops a running spindle first (a `Spindle { dir: Off, .. }` before the `ToolChange`); the
//! program must restart it with M3/M4.
//!
//! Also accepted:
//! - Canned cycles G73, G74, G81, G82, G83, G84, G85, G86, G87, G88, G89 with G98/G99, L repeats,
//!   G91 incremental form, in the G17, G18 and G19 planes, cancelled by G80 or another motion
//!   code (see `cycles`: R plane, initial level, the [`PECK_CLEARANCE_MM`] of G73/G83, the
//!   spindle reversal of G74/G84, the back boring of G87, the pause of G88). The motion mode
//!   persists: a later block with axis words drills again with the remembered Z, R, P, Q (and
//!   G87's I, J, K). The lathe cycles G70–G72, G76 are refused as unsupported.
//! - Feed modes G93 (inverse time), G94, G95 (per revolution): every feed move still leaves
//!   with an equivalent feed in mm/min (see `feed`).
//! - M70/M71/M72/M73: save, forget, restore the modal state (M73: restored when the current
//!   subroutine returns), one slot per call level.
//! - G0/G1 without axis words: a move to where the tool is, as LinuxCNC emits one.
//! - `o<name> call` of a subroutine defined in `<name>.ngc` in one of
//!   [`InterpConfig::subroutine_dirs`] (see `sub_files`).
//! - G28/G30: rapid to the intermediate point (the axis words, in the current modes), then to
//!   the stored position (#5161… / #5181…, set by G28.1/G30.1, default 0) along the given
//!   axes, all axes if none is given. G10 L2/L20 P0…P9 set work offsets and their XY
//!   rotation R (degrees about the offset's origin: `p_machine = Rz(R)·(p + g92) + g5x`);
//!   G59.1–G59.3 select systems 7–9. In a rotated system arcs and cutter compensation are
//!   accepted in G17 only (others are unsupported: no canonical plane on the machine).
//! - M19 R (angle, 0…360°) Q (wait, s) P (0 shortest, 1 clockwise, 2 counter-clockwise):
//!   spindle orientation ([`CanonKind::SpindleOrient`]); the spindle is stopped afterwards.
//! - G52: the G92 offset set to the given values (absolute whatever G90/G91), stored as G92's.
//! - G64 R (a planner option of newer LinuxCNC versions): accepted, no effect here.
//! - M7/M8/M9 ([`CanonKind::Coolant`]), M0/M1/M60 ([`CanonKind::Pause`]), M48–M53 and
//!   M62–M68 ([`CanonKind::Io`]): no motion. M61 Q sets the tool in the spindle without a
//!   change.
//! - G61, G61.1, G64 (P, Q): accepted; the planner stops exactly at the end of every move
//!   whatever the mode, so they change nothing.
//! - G43 H (tool length from [`InterpConfig::tool_lengths_mm`]; without H, the spindle's
//!   tool's), G43.1 Z (given length), G49 (off): absolute Z targets are shifted by the length.
//! - G43.4 H (tool centre point control, on a five-axis machine given by
//!   [`InterpConfig::tcp_axes`]; G49, G43, G43.1 end it): X, Y, Z are the tool tip in the part
//!   frame, the length goes to the machine's kinematics ([`run_program_tcp`]; rules in
//!   `exec::tcp`).
//! - G41 / G42 D (cutter radius compensation left / right of the path, D a tool number whose
//!   diameter comes from [`InterpConfig::tool_diameters_mm`]; D0 or no D: the tool in the
//!   spindle, loaded by M6 — a T word alone only selects),
//!   G41.1 / G42.1 D (D the diameter, in program units; negative: the other side), G40 (off),
//!   in the G17 or G18 plane, with LinuxCNC's paths and refusals (see `cutter_comp`): entry
//!   move offset perpendicular at its end, outside corners rounded at the tool radius, inside
//!   corners trimmed (one move of look-ahead: the compensated output is held until the next
//!   move in the plane is known, in order with the actions between), exit move after G40
//!   straight from the compensated point (a tool change before it makes that point the
//!   programmed one, as LinuxCNC re-reads the position after M6). While it is on, the
//!   interpreter's position stays the programmed point (G91 moves and incremental arc centres
//!   start from it); M6, plane, tool length and work offset changes, G28/G30, G53, G92 and
//!   I/O M codes are refused, as LinuxCNC refuses them. An arc as the entry move is
//!   unsupported.
//! - G38.2 / G38.3 / G38.4 / G38.5 probe moves ([`CanonKind::Probe`], see `probe`): the
//!   result comes from outside ([`ProgramRun`], [`Interpreter::probe_result`]); LinuxCNC's
//!   refusals (zero feed, cutter compensation on, G95, a G38.2/G38.4 of no length); G93 is
//!   unsupported. The motion mode persists like G1's.
//! - G80 (cancel motion mode). Beside another motion code in the same block (a Fanuc-style
//!   safe-start line `G0 G17 G21 G40 G49 G80 G90`) it gives way to that code, in either order,
//!   as LinuxCNC does; two G80 are one; two other motion codes still conflict.
//!
//! Anything else outside the subset is a [`GcodeErrorKind::Unsupported`] error, never
//! silently skipped. Execution stops after M2/M30 (LinuxCNC reads no further).

mod arc;
mod checks;
mod comp_block;
mod cutter_comp;
#[cfg(test)]
mod cutter_comp_tests;
mod cycles;
#[cfg(test)]
mod cycles_tests;
mod decode;
mod exec;
mod expr;
mod feed;
mod flow;
#[cfg(test)]
mod flow_tests;
#[cfg(test)]
mod location_tests;
mod probe;
#[cfg(test)]
mod probe_tests;
mod program;
mod program_run;
#[cfg(test)]
mod rotary_tests;
mod source;
mod sub_files;
#[cfg(test)]
mod tcp_tests;
#[cfg(test)]
mod tests;

pub use crate::syntax::{CallSite, ErrorIn, GcodeError, GcodeErrorKind};
pub use cycles::{MAX_REPEATS, PECK_CLEARANCE_MM};
pub use exec::Interpreter;
pub use expr::NUM_PARAMS;
pub use flow::{MAX_CALL_DEPTH, MAX_ITERATIONS};
pub use probe::{
    straight_probe_call, ProbeKind, ProbeOutcome, ProbeParams, ProbeRequest, PROBE_PARAM_FIRST,
    STANDALONE_BACKOFF_MM,
};
pub use program_run::{LengthUnit, ProgramRun, RunEvent};
pub use source::ProgramSource;

/// Largest P (turn count) accepted on G2/G3: guards against programs that would expand to
/// absurd paths (and hangs downstream).
pub const MAX_ARC_TURNS: u32 = 1000;

/// How many work coordinate systems there are: G54…G59 and G59.1…G59.3.
pub const WORK_OFFSETS: usize = 9;

/// Start-up settings of the interpreter.
#[derive(Debug, Clone, PartialEq)]
pub struct InterpConfig {
    /// Machine position of the tool when the program starts, mm (default: origin, as LinuxCNC's
    /// reference runs assume).
    pub start_mm: [f64; 3],
    /// Angles of the rotary axes A, B, C when the program starts, degrees (default: 0).
    pub start_abc_deg: [f64; 3],
    /// Work offsets G54…G59, G59.1…G59.3 (index 0…8) in machine coordinates, mm (default:
    /// all zero).
    pub work_offsets_mm: [[f64; 3]; WORK_OFFSETS],
    /// Tool lengths (tool number, length in mm) for G43 H. Empty (the default): every tool has
    /// length 0, the machine's positions being those of its own tool's tip.
    pub tool_lengths_mm: Vec<(u32, f64)>,
    /// Tool diameters (tool number, diameter in mm) for cutter radius compensation G41/G42 D.
    /// Empty (the default): every tool has diameter 0.
    pub tool_diameters_mm: Vec<(u32, f64)>,
    /// Block delete switch: when on, lines starting with `/` are skipped (default: off, as
    /// LinuxCNC starts).
    pub block_delete: bool,
    /// Folders searched, in order, for `<name>.ngc` when `o<name> call` names a subroutine the
    /// program does not define (LinuxCNC's subroutine path). Default: none (such a call is
    /// refused as unsupported).
    pub subroutine_dirs: Vec<std::path::PathBuf>,
    /// Which of the rotary axes A, B, C a five-axis machine has, for tool centre point control
    /// (G43.4, see [`run_program_tcp`]). `None` (the default): the machine has no kinematics for
    /// it and G43.4 is refused.
    pub tcp_axes: Option<[bool; 3]>,
}

impl Default for InterpConfig {
    fn default() -> Self {
        Self {
            start_mm: [0.0; 3],
            start_abc_deg: [0.0; 3],
            work_offsets_mm: [[0.0; 3]; WORK_OFFSETS],
            tool_lengths_mm: Vec::new(),
            tool_diameters_mm: Vec::new(),
            block_delete: false,
            subroutine_dirs: Vec::new(),
            tcp_axes: None,
        }
    }
}

/// Interprets a whole program: parse, run every block until M2/M30 or the end of the text.
/// Stops at the first error. Probe moves get the stand-alone outcome of LinuxCNC's `rs274`
/// ([`ProbeOutcome::Standalone`]); use [`ProgramRun`] to give them a machine's results.
///
/// ```
/// use vmc_gcode::interp::{run_program, CanonKind, InterpConfig};
/// let moves = run_program("G21 G90\nG1 X10 F600\nM2", &InterpConfig::default())?;
/// assert_eq!(moves[0].line, 2);
/// assert_eq!(
///     moves[0].kind,
///     CanonKind::Feed { end_mm: [10.0, 0.0, 0.0], end_abc_deg: [0.0; 3], feed_mm_per_min: 600.0 }
/// );
/// assert_eq!(moves[1].kind, CanonKind::ProgramEnd);
/// let err = run_program("G1 X1 F100\nG33 X5", &InterpConfig::default()).unwrap_err();
/// assert!(err.is_unsupported());
/// assert_eq!(err.to_string(), "line 2, column 1: G33 (spindle-synchronised motion) is not supported");
/// # Ok::<(), vmc_gcode::interp::GcodeError>(())
/// ```
pub fn run_program(src: &str, cfg: &InterpConfig) -> Result<Vec<CanonMove>, GcodeError> {
    run_program_with_units(src, cfg).map(|(moves, _)| moves)
}

/// [`run_program`], with the program's length unit (G20/G21) when it emitted each move (for
/// messages in the units the program was written in).
pub fn run_program_with_units(
    src: &str,
    cfg: &InterpConfig,
) -> Result<(Vec<CanonMove>, Vec<LengthUnit>), GcodeError> {
    let mut run = ProgramRun::new(src, cfg)?;
    let mut out = Vec::new();
    while let RunEvent::Probe(_) = run.resume(&mut out)? {
        run.probe_result(ProbeOutcome::Standalone)?;
    }
    let units = (0..out.len()).map(|i| run.length_unit_at(i)).collect();
    Ok((out, units))
}

/// [`run_program`] on a five-axis machine with tool centre point control
/// ([`InterpConfig::tcp_axes`]): with each move, the tool length under G43.4 when it was
/// emitted (`Some`: the move's X, Y, Z are the tool tip in the part frame, to be turned into
/// axis positions by the machine's inverse kinematics; `None`: machine positions).
///
/// ```
/// use vmc_gcode::interp::{run_program_tcp, InterpConfig};
/// let cfg = InterpConfig {
///     tool_lengths_mm: vec![(1, 150.0)],
///     tcp_axes: Some([false, true, true]),
///     ..InterpConfig::default()
/// };
/// let (moves, tcp) = run_program_tcp("G0 Z0\nG43.4 H1\nG0 X0 Y0 Z20 B-30\nG49\nG0 X0 Y0 Z0\nM2", &cfg)?;
/// assert_eq!(tcp[..3], [None, Some(150.0), None]);
/// let err = run_program_tcp("G43.4 H1\nG0 X1 A5", &cfg).unwrap_err();
/// assert_eq!(err.to_string(), "line 2, column 7: G43.4: this machine has no A axis");
/// # Ok::<(), vmc_gcode::interp::GcodeError>(())
/// ```
pub fn run_program_tcp(
    src: &str,
    cfg: &InterpConfig,
) -> Result<(Vec<CanonMove>, Vec<Option<f64>>), GcodeError> {
    let mut run = ProgramRun::new(src, cfg)?;
    let mut out = Vec::new();
    while let RunEvent::Probe(_) = run.resume(&mut out)? {
        run.probe_result(ProbeOutcome::Standalone)?;
    }
    let tcp = (0..out.len()).map(|i| run.tcp_length_at(i)).collect();
    Ok((out, tcp))
}

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
    /// G0 rapid move to `end_mm` (and the rotary axes to `end_abc_deg`) at the machine's
    /// rapid rate.
    Traverse {
        end_mm: [f64; 3],
        /// A, B, C at the end, machine coordinates, degrees (0 on a program without them).
        end_abc_deg: [f64; 3],
    },
    /// G1 straight feed move to `end_mm`, the rotary axes moving in step to `end_abc_deg`.
    Feed {
        end_mm: [f64; 3],
        /// A, B, C at the end, machine coordinates, degrees.
        end_abc_deg: [f64; 3],
        /// The feed of the move (see [`rotary_only`]): along the XYZ path in mm/min; for a
        /// move of the rotary axes alone, along the A, B, C angle in deg/min.
        feed_mm_per_min: f64,
    },
    /// G2/G3 arc (helix if the axis coordinate changes) from the current point to `end_mm`;
    /// the rotary axes move in step to `end_abc_deg` (LinuxCNC's extra axes of an arc).
    Arc {
        end_mm: [f64; 3],
        /// A, B, C at the end, machine coordinates, degrees.
        end_abc_deg: [f64; 3],
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
    /// M19: the spindle stops at `angle_deg` (its direction state becomes stopped).
    SpindleOrient {
        /// Angle from the spindle's zero, degrees (0…360).
        angle_deg: f64,
        /// Which way it turns to get there.
        direction: OrientDirection,
        /// Q: how long to wait for the orientation to complete, s (`None`: no wait).
        timeout_s: Option<f64>,
    },
    /// G38.2 / G38.3 / G38.4 / G38.5 straight probe move toward `end_mm` (the rotary axes
    /// toward `end_abc_deg`): the machine stops where the probe input changes state, at the
    /// target at the latest, and reports where (see [`ProbeOutcome`]); the interpreter goes
    /// on from there. The next move starts where the machine says the tool came to rest.
    Probe {
        end_mm: [f64; 3],
        /// A, B, C at the target, machine coordinates, degrees.
        end_abc_deg: [f64; 3],
        /// As for [`CanonKind::Feed`]: mm/min along the XYZ path, deg/min for a move of the
        /// rotary axes alone.
        feed_mm_per_min: f64,
        /// Which of G38.2 … G38.5.
        kind: ProbeKind,
    },
    /// M6 tool change to tool `tool`.
    ToolChange { tool: u32 },
    /// M2 / M30.
    ProgramEnd,
    /// `(MSG, text)`: shown to the operator; no motion.
    Message(String),
    /// M7 / M8 / M9: the coolant state after the command.
    Coolant { mist: bool, flood: bool },
    /// M0 / M1 / M60: the program waits for the operator (no motion, no machine time).
    Pause(PauseKind),
    /// M48–M53 (override switches), M62–M68 (digital/analog I/O, M66 waits on an input and
    /// returns at once here): the M number and its P, E, L, Q values; no motion.
    Io {
        /// The M number (48…53, 62…68).
        m: u32,
        /// P, E, L, Q words, if given.
        p: Option<f64>,
        /// E word.
        e: Option<f64>,
        /// L word.
        l: Option<f64>,
        /// Q word.
        q: Option<f64>,
    },
}

/// How M19 turns the spindle to its angle (P0, P1, P2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OrientDirection {
    /// P0 (default): the shorter way.
    Shortest,
    /// P1: clockwise.
    Clockwise,
    /// P2: counter-clockwise.
    CounterClockwise,
}

/// Why a program pauses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PauseKind {
    /// M0.
    Program,
    /// M1 (only if the optional-stop switch is on).
    Optional,
    /// M60: pallet shuttle, then pause.
    PalletShuttle,
}

/// Largest XYZ travel, mm, of a move that counts as a move of the rotary axes alone (1e-7 mm
/// = 0.1 nm: rounding of offsets, not motion; LinuxCNC's canonical layer uses the same
/// threshold).
pub const XYZ_STILL_MM: f64 = 1e-7;

/// True if a straight move from (`start_mm`, `start_abc_deg`) to (`end_mm`, `end_abc_deg`)
/// turns a rotary axis and leaves X, Y, Z where they are (within [`XYZ_STILL_MM`]): LinuxCNC's
/// rule then applies the feed to the rotary angle `√(ΔA² + ΔB² + ΔC²)` in deg/min instead of
/// to the XYZ path in mm/min.
pub fn rotary_only(
    start_mm: [f64; 3],
    end_mm: [f64; 3],
    start_abc_deg: [f64; 3],
    end_abc_deg: [f64; 3],
) -> bool {
    let d = |a: [f64; 3], b: [f64; 3]| (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    d(start_mm, end_mm) <= XYZ_STILL_MM && d(start_abc_deg, end_abc_deg) > 0.0
}

/// A canonical action with the source line (1-based) it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct CanonMove {
    /// 1-based line number in the source file.
    pub line: usize,
    /// What the machine must do.
    pub kind: CanonKind,
}
