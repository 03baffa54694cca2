//! Canned cycles G73, G74, G81–G89 (LinuxCNC semantics), expanded into traverse,
//! feed, dwell, spindle and pause actions.
//!
//! Terms, along the cycle axis (Z in G17, Y in G18, X in G19):
//! - *initial level*: the axis position when the first cycle of a run starts (a run ends when
//!   the motion mode becomes G0–G3 or G80);
//! - *R plane*: the R word (G90: a coordinate; G91: relative to the initial level);
//! - *bottom*: the axis word (G90: a coordinate; G91: relative to the R plane);
//! - *clear level*: where a hole ends: the R plane under G99, the higher of the initial
//!   level and the R plane under G98.
//!
//! Per block: if the initial level is below the R plane, a rapid first goes straight to the
//! R plane. Then, L times (default 1): a rapid to the hole position — at the clear level if
//! the tool is at or below the R plane, else at its current height — then a rapid to the R
//! plane (when not already there) and the cycle's own moves. Under G91 the X/Y (plane) words
//! are increments applied before each repetition; under G90 the repetitions drill the same hole.
//! The axis word, R, P and Q are remembered while the cycle stays the motion mode; a block
//! that switches to a cycle must give the axis word and R (and P or Q where the cycle needs
//! them). G73/G83 pecks back off (G73) or re-approach (G83) by [`PECK_CLEARANCE_MM`].
//!
//! G87 (back boring) takes the tool, spindle oriented (stopped), down at the hole position
//! shifted by I/J/K along the plane's axes, back to the centre at the bottom, restarts the
//! spindle, feeds up to the level of the third word (K in G17, J in G18, I in G19; G90: a
//! coordinate, G91: relative to the bottom) and back down, then leaves shifted again, spindle
//! oriented, up to the clear level and back to the centre, where the spindle restarts.
//! Spindle orientation is reported as a spindle stop.

use super::checks::{plane_axes, AXES};
pub(super) use super::decode::Cycle;
use super::decode::{cycle_name, Decoded, Retract};
use super::{CanonKind, PauseKind, Plane, SpindleDir};
use crate::syntax::{Block, GcodeError, Word};

/// Back-off after each G73 peck and approach gap before each G83 peck: 0.010 inch, whatever
/// the program units (LinuxCNC's fixed value).
pub const PECK_CLEARANCE_MM: f64 = 0.254;

/// Two levels closer than this are the same level (1e-9 mm: float rounding only).
const LEVEL_EPS_MM: f64 = 1e-9;

/// Modal state of the canned cycles.
#[derive(Debug, Clone, Default)]
pub(super) struct CycleState {
    /// G98 (initial level) or G99 (R plane, the start-up mode).
    pub retract: Retract,
    /// Initial level of the current run of cycles, machine mm along the cycle axis.
    initial_level_mm: Option<f64>,
    /// Remembered words, in program units as written: axis (bottom), R, P, Q.
    bottom: Option<f64>,
    r: Option<f64>,
    p: Option<f64>,
    q: Option<f64>,
    /// G87's I, J, K (program units, by axis).
    ijk: Option<[f64; 3]>,
}

impl CycleState {
    /// Called when a block sets the motion mode: a non-cycle mode ends the run of cycles.
    pub fn motion_mode_set(&mut self, is_cycle: bool) {
        if !is_cycle {
            self.initial_level_mm = None;
        }
    }
}

/// What a cycle block sees of the interpreter's state.
pub(super) struct CycleInput<'a> {
    pub block: &'a Block,
    pub d: &'a Decoded,
    pub cycle: Cycle,
    /// Column of the motion code (or of the first axis word).
    pub col: usize,
    /// True when the block switches the motion mode to this cycle.
    pub first: bool,
    pub pos_mm: [f64; 3],
    pub plane: Plane,
    pub incremental: bool,
    /// mm per program unit.
    pub scale: f64,
    /// Program-to-machine offset of each axis, mm.
    pub offset_mm: [f64; 3],
    /// A, B, C during the cycle (a cycle block carries no rotary word), degrees.
    pub abc_deg: [f64; 3],
    pub feed_mm_per_min: f64,
    pub spindle: (SpindleDir, f64),
}

/// True if the cycle uses a P word (dwell, seconds).
pub(super) fn uses_p(c: Cycle) -> bool {
    matches!(c, Cycle::G82 | Cycle::G86 | Cycle::G88 | Cycle::G89)
}

/// True if the cycle uses a Q word (peck depth).
pub(super) fn uses_q(c: Cycle) -> bool {
    matches!(c, Cycle::G73 | Cycle::G83)
}

/// Word checks of a canned cycle block: it claims R, L and (per cycle) P and Q; I, J, K, E
/// have no use; codes that would need its words too are refused.
pub(super) fn check_words(line: usize, c: Cycle, d: &Decoded) -> Result<(), GcodeError> {
    let name = cycle_name(c);
    let inv = |w: &Word, msg: String| Err(GcodeError::invalid(line, w.col, msg));
    let ijk = d.ijk.iter().flatten().filter(|_| c != Cycle::G87);
    if let Some(w) = ijk.chain(d.e.iter()).next() {
        return inv(
            w,
            format!("{} word with {name} (nothing uses it)", w.letter),
        );
    }
    if let Some(w) = d.p.filter(|_| !uses_p(c)) {
        return inv(
            &w,
            format!("P word with {name} (only G82, G86, G88, G89 dwell)"),
        );
    }
    if let Some(w) = d.q.filter(|_| !uses_q(c)) {
        return inv(&w, format!("Q word with {name} (only G73 and G83 peck)"));
    }
    if let Some(w) = d.h {
        return inv(&w, format!("H word with {name} (H needs G43)"));
    }
    let other = [
        d.non_modal.map(|n| n.1),
        d.tool_length.map(|t| t.1),
        d.io.map(|m| m.1),
        d.set_tool,
    ];
    if let Some(col) = other.into_iter().flatten().next() {
        let msg = format!(
            "{name} in a block with G4, G10, G28, G30, G43, G53, G92, M61 or an I/O M code \
             is not supported"
        );
        return Err(GcodeError::unsupported(line, col, msg));
    }
    Ok(())
}

/// Runs one cycle block: appends its actions to `out`, returns the final position (mm).
pub(super) fn run(
    input: &CycleInput,
    state: &mut CycleState,
    out: &mut Vec<CanonKind>,
) -> Result<[f64; 3], GcodeError> {
    let CycleInput {
        block, d, cycle, ..
    } = *input;
    let name = cycle_name(cycle);
    let line = block.line;
    let inv = |col: usize, msg: String| GcodeError::invalid(line, col, msg);
    let (a1, a2, ax) = plane_axes(input.plane);
    let axis_letter = AXES[ax];

    let bottom_word = d.axes[ax].map(|w| w.value).or(state.bottom);
    let Some(bottom_word) = bottom_word.filter(|_| !input.first || d.axes[ax].is_some()) else {
        let msg = format!("{name} needs {axis_letter} (hole bottom) in the block that starts it");
        return Err(inv(input.col, msg));
    };
    let Some(r_word) =
        d.r.map(|w| w.value)
            .or(state.r)
            .filter(|_| !input.first || d.r.is_some())
    else {
        let msg = format!("{name} needs R (retract plane) in the block that starts it");
        return Err(inv(input.col, msg));
    };
    let positive = |w: Option<Word>, what: &str| -> Result<Option<f64>, GcodeError> {
        match w {
            Some(w) if w.value <= 0.0 => Err(inv(
                w.col,
                format!("{name} {} ({what}) must be > 0", w.letter),
            )),
            Some(w) => Ok(Some(w.value)),
            None => Ok(None),
        }
    };
    let mut p = None;
    if uses_p(cycle) {
        if let Some(w) = d.p.filter(|w| w.value < 0.0) {
            return Err(inv(w.col, format!("{name} dwell P must not be negative")));
        }
        p = d.p.map(|w| w.value).or(state.p.filter(|_| !input.first));
        if p.is_none() {
            let msg = format!("{name} needs P (dwell time, seconds) in the block that starts it");
            return Err(inv(input.col, msg));
        }
    }
    let mut q = None;
    if uses_q(cycle) {
        q = positive(d.q, "peck depth")?.or(state.q.filter(|_| !input.first));
        if q.is_none() {
            let msg = format!("{name} needs Q (peck depth) in the block that starts it");
            return Err(inv(input.col, msg));
        }
    }
    let mut ijk = None;
    if cycle == Cycle::G87 {
        ijk = match (d.ijk, state.ijk) {
            ([Some(i), Some(j), Some(k)], _) => Some([i.value, j.value, k.value]),
            ([None, None, None], Some(kept)) if !input.first => Some(kept),
            _ => {
                let msg = "G87 needs I, J and K (shift and top of the back bore)".to_string();
                return Err(inv(input.col, msg));
            }
        };
    }
    let repeats = match d.l {
        Some(l) if l.value.fract() != 0.0 || l.value < 1.0 => {
            let msg = format!(
                "{name} repeat count L{} must be a whole number >= 1",
                l.value
            );
            return Err(inv(l.col, msg));
        }
        Some(l) if l.value > f64::from(MAX_REPEATS) => {
            let msg = format!(
                "{name} repeat count L{} above the supported maximum {MAX_REPEATS}",
                l.value
            );
            return Err(GcodeError::unsupported(line, l.col, msg));
        }
        Some(l) => l.value as u32,
        None => 1,
    };
    match (cycle, input.spindle.0) {
        (Cycle::G84, SpindleDir::Cw) | (Cycle::G74, SpindleDir::Ccw) => {}
        (Cycle::G86 | Cycle::G87 | Cycle::G88, SpindleDir::Cw | SpindleDir::Ccw) => {}
        (Cycle::G84, _) => {
            let msg = "G84 (right-hand tapping) needs the spindle turning clockwise (M3)";
            return Err(inv(input.col, msg.to_string()));
        }
        (Cycle::G74, _) => {
            let msg = "G74 (left-hand tapping) needs the spindle turning counter-clockwise (M4)";
            return Err(inv(input.col, msg.to_string()));
        }
        (Cycle::G86 | Cycle::G87 | Cycle::G88, _) => {
            let msg = format!("{name} needs the spindle turning (M3 or M4)");
            return Err(inv(input.col, msg));
        }
        _ => {}
    }

    let k = input.scale;
    let initial = *state.initial_level_mm.get_or_insert(input.pos_mm[ax]);
    let (r_mm, bottom_mm) = if input.incremental {
        let r = initial + r_word * k;
        (r, r + bottom_word * k)
    } else {
        let off = input.offset_mm[ax];
        (r_word * k + off, bottom_word * k + off)
    };
    if r_mm < bottom_mm {
        let msg = format!(
            "{name}: R plane ({r_word}) below the hole bottom {axis_letter} ({bottom_word})"
        );
        return Err(inv(input.col, msg));
    }
    if let Some(q) = q {
        let pecks = (r_mm - bottom_mm) / (q * k) * f64::from(repeats);
        if pecks > f64::from(MAX_REPEATS) {
            let msg =
                format!("{name} would make more than {MAX_REPEATS} pecks in one block (Q{q})");
            return Err(GcodeError::unsupported(line, input.col, msg));
        }
    }
    let clear_mm = match state.retract {
        Retract::RPlane => r_mm,
        Retract::InitialLevel => initial.max(r_mm),
    };

    // Peck levels as LinuxCNC computes them: in program units, down from R by Q while above
    // the bottom (the rounding of that sum decides whether a last peck lands on the bottom).
    let pecks_mm = if matches!(cycle, Cycle::G73 | Cycle::G83) {
        let off = input.offset_mm[ax];
        let (r_u, bottom_u) = if input.incremental {
            // LinuxCNC holds the position in program units, as written (`Z0.047`); ours comes
            // back from mm with a rounding error of ~1e-15: snapped to 1e-10 of a unit, far
            // below any written digit, so that the peck sums round as LinuxCNC's do.
            let initial_u = ((initial - off) / k * 1e10).round() / 1e10;
            let r_u = initial_u + r_word;
            (r_u, r_u + bottom_word)
        } else {
            (r_word, bottom_word)
        };
        let q_u = q.unwrap_or(r_u - bottom_u).max(f64::MIN_POSITIVE);
        let mut levels = Vec::new();
        let mut depth_u = r_u - q_u;
        while depth_u > bottom_u {
            levels.push(depth_u * k + off);
            depth_u -= q_u;
        }
        levels
    } else {
        Vec::new()
    };
    let mut pos = input.pos_mm;
    let mut cx = Expander {
        out,
        pos: &mut pos,
        ax,
        abc_deg: input.abc_deg,
        feed: input.feed_mm_per_min,
        pecks_mm,
    };
    if initial < r_mm {
        cx.traverse(r_mm);
    }
    let step = |axis: usize| d.axes[axis].map_or(0.0, |w| w.value * k);
    for _ in 0..repeats {
        let mut hole = *cx.pos;
        for a in [a1, a2] {
            if input.incremental {
                hole[a] += step(a);
            } else if let Some(w) = d.axes[a] {
                hole[a] = w.value * k + input.offset_mm[a];
            }
        }
        // Levels within LEVEL_EPS_MM are one level: in G91 the R plane is a sum computed in mm
        // here and in program units by LinuxCNC, whose roundings differ.
        hole[ax] = if cx.pos[ax] <= r_mm + LEVEL_EPS_MM {
            clear_mm
        } else {
            cx.pos[ax]
        };
        cx.out.push(CanonKind::Traverse {
            end_mm: hole,
            end_abc_deg: input.abc_deg,
        });
        *cx.pos = hole;
        if (hole[ax] - r_mm).abs() > LEVEL_EPS_MM {
            cx.traverse(r_mm);
        }
        if let Some(ijk) = ijk {
            let mut shift = ijk.map(|v| v * k);
            let top = if input.incremental {
                bottom_mm + shift[ax]
            } else {
                shift[ax] + input.offset_mm[ax]
            };
            shift[ax] = 0.0;
            cx.back_bore(shift, top, bottom_mm, clear_mm, input.spindle);
            continue;
        }
        cx.body(cycle, r_mm, bottom_mm, clear_mm, p, input.spindle);
    }
    state.ijk = ijk.or(state.ijk);

    state.bottom = Some(bottom_word);
    state.r = Some(r_word);
    state.p = p.or(state.p);
    state.q = q.or(state.q);
    Ok(pos)
}

/// Largest L (repeat count) accepted on a cycle, and most G73/G83 pecks in one block.
pub const MAX_REPEATS: u32 = 10_000;

/// Emits moves along the cycle axis from the current position.
struct Expander<'a> {
    out: &'a mut Vec<CanonKind>,
    pos: &'a mut [f64; 3],
    ax: usize,
    /// A, B, C, unchanged by the cycle, degrees.
    abc_deg: [f64; 3],
    feed: f64,
    /// G73/G83: the levels the pecks feed to (above the bottom), mm.
    pecks_mm: Vec<f64>,
}

impl Expander<'_> {
    fn to(&mut self, level: f64) -> [f64; 3] {
        self.pos[self.ax] = level;
        *self.pos
    }

    fn traverse(&mut self, level: f64) {
        let end_mm = self.to(level);
        self.out.push(CanonKind::Traverse {
            end_mm,
            end_abc_deg: self.abc_deg,
        });
    }

    fn feed(&mut self, level: f64) {
        let end_mm = self.to(level);
        self.out.push(CanonKind::Feed {
            end_mm,
            end_abc_deg: self.abc_deg,
            feed_mm_per_min: self.feed,
        });
    }

    /// A tapping feed (G74/G84). LinuxCNC sends these two moves with the coordinates rotated
    /// outside G17 — G18: (Y, Z, X), G19: (Z, X, Y) — while its position follows the cycle
    /// as programmed; the twin moves where the controller does.
    fn tap_feed(&mut self, level: f64) {
        let p = self.to(level);
        let shift = match self.ax {
            1 => 1,
            0 => 2,
            _ => 0,
        };
        let end_mm = [0, 1, 2].map(|i| p[(i + shift) % 3]);
        self.out.push(CanonKind::Feed {
            end_mm,
            end_abc_deg: self.abc_deg,
            feed_mm_per_min: self.feed,
        });
    }

    fn dwell(&mut self, duration_s: f64) {
        self.out.push(CanonKind::Dwell { duration_s });
    }

    fn spindle(&mut self, dir: SpindleDir, rpm: f64) {
        self.out.push(CanonKind::Spindle { dir, rpm });
    }

    /// G87 from the R plane (see the module documentation).
    fn back_bore(
        &mut self,
        shift: [f64; 3],
        top: f64,
        bottom: f64,
        clear: f64,
        spindle: (SpindleDir, f64),
    ) {
        let (dir, rpm) = spindle;
        let centre = *self.pos;
        let shifted = [0, 1, 2].map(|i| centre[i] + shift[i]);
        let rapid = |x: &mut Self, base: [f64; 3], level: f64| {
            *x.pos = base;
            x.traverse(level);
        };
        rapid(self, shifted, centre[self.ax]);
        self.spindle(SpindleDir::Off, rpm);
        rapid(self, shifted, bottom);
        rapid(self, centre, bottom);
        self.spindle(dir, rpm);
        self.feed(top);
        self.feed(bottom);
        self.spindle(SpindleDir::Off, rpm);
        rapid(self, shifted, bottom);
        rapid(self, shifted, clear);
        rapid(self, centre, clear);
        self.spindle(dir, rpm);
    }

    /// The cycle's own moves, from the R plane.
    #[allow(clippy::too_many_arguments)]
    fn body(
        &mut self,
        cycle: Cycle,
        r: f64,
        bottom: f64,
        clear: f64,
        p: Option<f64>,
        spindle: (SpindleDir, f64),
    ) {
        let p = p.unwrap_or(0.0);
        let (dir, rpm) = spindle;
        match cycle {
            Cycle::G81 => {
                self.feed(bottom);
                self.traverse(clear);
            }
            Cycle::G82 => {
                self.feed(bottom);
                self.dwell(p);
                self.traverse(clear);
            }
            Cycle::G73 | Cycle::G83 => {
                for depth in self.pecks_mm.clone() {
                    self.feed(depth);
                    if cycle == Cycle::G73 {
                        self.traverse(depth + PECK_CLEARANCE_MM);
                    } else {
                        self.traverse(r);
                        self.traverse(depth + PECK_CLEARANCE_MM);
                    }
                }
                self.feed(bottom);
                self.traverse(clear);
            }
            Cycle::G74 | Cycle::G84 => {
                let reverse = if cycle == Cycle::G84 {
                    SpindleDir::Ccw
                } else {
                    SpindleDir::Cw
                };
                self.tap_feed(bottom);
                self.spindle(SpindleDir::Off, rpm);
                self.spindle(reverse, rpm);
                self.dwell(0.0);
                self.tap_feed(clear);
                self.spindle(SpindleDir::Off, rpm);
                self.spindle(dir, rpm);
            }
            Cycle::G85 => {
                self.feed(bottom);
                self.feed(r);
                self.traverse(clear);
            }
            Cycle::G86 => {
                self.feed(bottom);
                self.dwell(p);
                self.spindle(SpindleDir::Off, rpm);
                self.traverse(clear);
                self.spindle(dir, rpm);
            }
            Cycle::G88 => {
                self.feed(bottom);
                self.dwell(p);
                self.spindle(SpindleDir::Off, rpm);
                self.out.push(CanonKind::Pause(PauseKind::Program));
                self.spindle(dir, rpm);
            }
            Cycle::G89 => {
                self.feed(bottom);
                self.dwell(p);
                self.feed(clear);
            }
            // `run` expands G87 with `back_bore`.
            Cycle::G87 => {}
        }
    }
}
