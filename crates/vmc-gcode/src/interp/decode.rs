//! Block decoding: the words of one block → which modal groups it sets and which values it
//! carries. Checks what can be checked without the modal state: known codes, at most one code
//! per modal group (RS274/NGC / LinuxCNC modal groups).

use super::{Plane, ProbeKind, SpindleDir};
use crate::syntax::{Block, GcodeError, Word};

/// Group 1: motion mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Motion {
    /// G0.
    Rapid,
    /// G1.
    Linear,
    /// G2 (`true`) or G3 (`false`).
    Arc { clockwise: bool },
    /// G80: no motion mode.
    Cancel,
    /// G73, G74, G81–G89: a canned cycle (see `cycles`).
    Cycle(Cycle),
    /// G38.2–G38.5: a straight probe move (see `probe`).
    Probe(ProbeKind),
}

/// The canned cycles (group 1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Cycle {
    /// G73: peck drilling with chip break.
    G73,
    /// G74: left-hand tapping.
    G74,
    /// G81: drilling.
    G81,
    /// G82: drilling with dwell.
    G82,
    /// G83: peck drilling.
    G83,
    /// G84: right-hand tapping.
    G84,
    /// G85: boring, feed out.
    G85,
    /// G86: boring, spindle stop, rapid out.
    G86,
    /// G87: back boring.
    G87,
    /// G88: boring, spindle stop, manual out.
    G88,
    /// G89: boring, dwell, feed out.
    G89,
}

/// Group 10: canned cycle return level.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) enum Retract {
    /// G98: to the initial level (or the R plane if higher).
    InitialLevel,
    /// G99: to the R plane (LinuxCNC's start-up mode).
    #[default]
    RPlane,
}

/// Group 5: feed rate mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) enum FeedMode {
    /// G93: inverse time, the F word of each feed move is 1/minutes.
    InverseTime,
    /// G94: units per minute (the start-up mode).
    #[default]
    PerMinute,
    /// G95: units per spindle revolution.
    PerRevolution,
}

/// Group 0: non-modal codes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum NonModal {
    /// G4.
    Dwell,
    /// G53.
    MachineCoords,
    /// G92.
    SetAxisOffsets,
    /// G52: the G92 offset set to the given values (a local coordinate offset).
    LocalOffsets,
    /// G92.1.
    ResetAxisOffsets,
    /// G92.2: G92 offset off, stored values kept.
    SuspendAxisOffsets,
    /// G92.3: G92 offset back from the stored values.
    RestoreAxisOffsets,
    /// G28 (0) / G30 (1): go home through an optional intermediate point.
    Home(usize),
    /// G28.1 (0) / G30.1 (1): store the current position as home.
    SetHome(usize),
    /// G10: set work offsets (L2 / L20).
    SetCoordData,
}

/// Group 4 M codes that stop: M0, M1, M60, M2/M30.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Stop {
    /// M0.
    Pause,
    /// M1.
    OptionalPause,
    /// M60.
    PalletShuttle,
    /// M2 / M30.
    End,
}

/// Group 8: tool length offset.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ToolLength {
    /// G43: from the tool table.
    Table,
    /// G43.1: the Z word is the length.
    Given,
    /// G43.4: tool centre point control (see `exec::tcp`).
    Tcp,
    /// G49: off.
    Off,
}

/// Group 7: cutter radius compensation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum CompMode {
    /// G40.
    Off,
    /// G41 (`left`) / G42; `given`: G41.1 / G42.1, the D word is the tool diameter, else D
    /// is a tool number.
    On { left: bool, given: bool },
}

/// Group 6: length units.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Units {
    /// G21.
    Mm,
    /// G20.
    Inch,
}

/// Groups 3 (G90/G91) and G90.1/G91.1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Distance {
    /// G90 / G90.1.
    Absolute,
    /// G91 / G91.1.
    Incremental,
}

/// What one G code does.
enum GAction {
    Motion(Motion),
    NonModal(NonModal),
    Plane(Plane),
    Units(Units),
    Distance(Distance),
    ArcDistance(Distance),
    CoordSystem(usize),
    ToolLength(ToolLength),
    Retract(Retract),
    FeedMode(FeedMode),
    CutterComp(CompMode),
    /// G61 / G61.1 / G64: path control (the planner stops exactly at every move's end).
    PathControl,
}

/// A decoded block. Each field holds the value and the 1-based column of the word that set it.
#[derive(Debug, Default)]
pub(super) struct Decoded {
    pub motion: Option<(Motion, usize)>,
    pub non_modal: Option<(NonModal, usize)>,
    pub plane: Option<Plane>,
    pub units: Option<Units>,
    pub distance: Option<Distance>,
    pub arc_distance: Option<Distance>,
    pub coord_system: Option<usize>,
    pub tool_length: Option<(ToolLength, usize)>,
    /// G98 / G99.
    pub retract: Option<Retract>,
    /// G93 / G94 / G95 and the column.
    pub feed_mode: Option<(FeedMode, usize)>,
    /// M70–M73 (modal state save/restore): the M number and column.
    pub modal_state: Option<(u32, usize)>,
    /// G40 / G41 / G42 / G41.1 / G42.1 and the column.
    pub cutter_comp: Option<(CompMode, usize)>,
    /// M0, M1, M60, M2, M30 and the column.
    pub stop: Option<(Stop, usize)>,
    /// Path control code (G61, G61.1, G64) column.
    pub path_control: Option<(u32, usize)>,
    /// Columns of M7 (mist on), M8 (flood on), M9 (both off).
    pub coolant: [Option<usize>; 3],
    /// Column of M6.
    pub tool_change: Option<usize>,
    pub spindle: Option<(SpindleDir, usize)>,
    /// X, Y, Z.
    pub axes: [Option<Word>; 3],
    /// A, B, C (rotary axes, degrees).
    pub abc: [Option<Word>; 3],
    /// I, J, K.
    pub ijk: [Option<Word>; 3],
    pub r: Option<Word>,
    pub p: Option<Word>,
    pub f: Option<Word>,
    pub s: Option<Word>,
    pub t: Option<Word>,
    pub h: Option<Word>,
    pub d: Option<Word>,
    pub l: Option<Word>,
    pub e: Option<Word>,
    /// M48–M53 (override switches) or M62–M68 (I/O): the M number and column.
    pub io: Option<(u32, usize)>,
    /// Column of M61 (set current tool).
    pub set_tool: Option<usize>,
    /// M19 (spindle orientation): its column.
    pub orient: Option<usize>,
    pub q: Option<Word>,
}

impl Decoded {
    /// True if any of X, Y, Z, A, B, C is present.
    pub fn has_axis_words(&self) -> bool {
        self.has_xyz_words() || self.abc.iter().any(Option::is_some)
    }

    /// True if any of X, Y, Z is present.
    pub fn has_xyz_words(&self) -> bool {
        self.axes.iter().any(Option::is_some)
    }

    /// The first axis word of the block (X, Y, Z, then A, B, C), for messages.
    pub fn first_axis_word(&self) -> Option<Word> {
        self.axes.iter().chain(&self.abc).flatten().copied().next()
    }

    /// The first of I, J, K, R present (for messages).
    pub fn first_arc_word(&self) -> Option<Word> {
        self.ijk
            .iter()
            .flatten()
            .chain(self.r.iter())
            .copied()
            .next()
    }
}

/// Decodes a block; rejects unknown/unsupported codes and two codes of one modal group.
pub(super) fn decode(block: &Block) -> Result<Decoded, GcodeError> {
    let mut d = Decoded::default();
    // (group id, first word) for conflict messages.
    let mut seen: Vec<(u32, Word)> = Vec::new();
    let claim = |seen: &mut Vec<(u32, Word)>, group: u32, w: &Word| -> Result<(), GcodeError> {
        if let Some((_, prev)) = seen.iter().find(|(g, _)| *g == group) {
            return Err(GcodeError::invalid(
                block.line,
                w.col,
                format!(
                    "{} and {} are in the same modal group and cannot share a block",
                    prev.display(),
                    w.display()
                ),
            ));
        }
        seen.push((group, *w));
        Ok(())
    };
    for w in &block.words {
        match w.letter {
            'G' => {
                let code = code_of(block, w)?;
                let (group, action) = g_action(code).map_err(|e| e.at(block.line, w))?;
                if let GAction::Motion(m) = action {
                    // G80 beside another motion code gives way to it, in either order (a
                    // Fanuc-style safe-start line `G0 G17 G21 G40 G49 G80 G90`), as LinuxCNC
                    // does; two other motion codes still conflict.
                    match (d.motion, m) {
                        (Some(_), Motion::Cancel) => continue,
                        (Some((Motion::Cancel, _)), _) => {
                            if let Some(entry) = seen.iter_mut().find(|(g, _)| *g == group) {
                                entry.1 = *w;
                            }
                            d.motion = Some((m, w.col));
                            continue;
                        }
                        _ => {}
                    }
                }
                claim(&mut seen, group, w)?;
                match action {
                    GAction::Motion(m) => d.motion = Some((m, w.col)),
                    GAction::NonModal(n) => d.non_modal = Some((n, w.col)),
                    GAction::Plane(p) => d.plane = Some(p),
                    GAction::Units(u) => d.units = Some(u),
                    GAction::Distance(x) => d.distance = Some(x),
                    GAction::ArcDistance(x) => d.arc_distance = Some(x),
                    GAction::CoordSystem(i) => d.coord_system = Some(i),
                    GAction::ToolLength(t) => d.tool_length = Some((t, w.col)),
                    GAction::Retract(r) => d.retract = Some(r),
                    GAction::FeedMode(m) => d.feed_mode = Some((m, w.col)),
                    GAction::CutterComp(c) => d.cutter_comp = Some((c, w.col)),
                    GAction::PathControl => d.path_control = Some((code, w.col)),
                }
            }
            'M' => {
                let code = code_of(block, w)?;
                let group = match code {
                    0 | 10 | 20 | 300 | 600 => {
                        let stop = match code {
                            0 => Stop::Pause,
                            10 => Stop::OptionalPause,
                            600 => Stop::PalletShuttle,
                            _ => Stop::End,
                        };
                        d.stop = Some((stop, w.col));
                        4
                    }
                    70 | 80 | 90 => {
                        d.coolant[(code / 10 - 7) as usize] = Some(w.col);
                        8
                    }
                    480..=530 | 620..=680 if code.is_multiple_of(10) => {
                        d.io = Some((code / 10, w.col));
                        105
                    }
                    700..=730 if code.is_multiple_of(10) => {
                        d.modal_state = Some((code / 10, w.col));
                        107
                    }
                    610 => {
                        d.set_tool = Some(w.col);
                        6
                    }
                    190 => {
                        d.orient = Some(w.col);
                        7
                    }
                    60 => {
                        d.tool_change = Some(w.col);
                        6
                    }
                    30 | 40 | 50 => {
                        let dir = match code {
                            30 => SpindleDir::Cw,
                            40 => SpindleDir::Ccw,
                            _ => SpindleDir::Off,
                        };
                        d.spindle = Some((dir, w.col));
                        7
                    }
                    _ => return Err(m_unsupported(code).at(block.line, w)),
                };
                claim(&mut seen, 100 + group, w)?;
            }
            'X' => d.axes[0] = Some(*w),
            'Y' => d.axes[1] = Some(*w),
            'Z' => d.axes[2] = Some(*w),
            'A' => d.abc[0] = Some(*w),
            'B' => d.abc[1] = Some(*w),
            'C' => d.abc[2] = Some(*w),
            'I' => d.ijk[0] = Some(*w),
            'J' => d.ijk[1] = Some(*w),
            'K' => d.ijk[2] = Some(*w),
            'R' => d.r = Some(*w),
            'P' => d.p = Some(*w),
            'F' => d.f = Some(*w),
            'S' => d.s = Some(*w),
            'T' => d.t = Some(*w),
            'H' => d.h = Some(*w),
            'D' => d.d = Some(*w),
            'L' => d.l = Some(*w),
            'E' => d.e = Some(*w),
            'Q' => d.q = Some(*w),
            other => {
                // The lexer only lets supported letters through.
                return Err(GcodeError::unsupported(
                    block.line,
                    w.col,
                    format!("{other} word is not supported"),
                ));
            }
        }
    }
    Ok(d)
}

fn code_of(block: &Block, w: &Word) -> Result<u32, GcodeError> {
    w.code_x10().ok_or_else(|| {
        GcodeError::invalid(
            block.line,
            w.col,
            format!("{}{} is not a valid code number", w.letter, w.value),
        )
    })
}

/// A code that is not accepted, before it is placed at a line and column.
enum Rejected {
    Unsupported(&'static str),
    Unknown,
}

impl Rejected {
    fn at(self, line: usize, w: &Word) -> GcodeError {
        match self {
            Rejected::Unsupported(what) => GcodeError::unsupported(
                line,
                w.col,
                format!("{} ({what}) is not supported", w.display()),
            ),
            Rejected::Unknown => {
                GcodeError::invalid(line, w.col, format!("unknown code {}", w.display()))
            }
        }
    }
}

/// Modal group and action of a G code (×10), LinuxCNC's group numbers.
fn g_action(code: u32) -> Result<(u32, GAction), Rejected> {
    use GAction as A;
    Ok(match code {
        0 => (1, A::Motion(Motion::Rapid)),
        10 => (1, A::Motion(Motion::Linear)),
        20 => (1, A::Motion(Motion::Arc { clockwise: true })),
        30 => (1, A::Motion(Motion::Arc { clockwise: false })),
        800 => (1, A::Motion(Motion::Cancel)),
        730 => (1, A::Motion(Motion::Cycle(Cycle::G73))),
        740 => (1, A::Motion(Motion::Cycle(Cycle::G74))),
        810 => (1, A::Motion(Motion::Cycle(Cycle::G81))),
        820 => (1, A::Motion(Motion::Cycle(Cycle::G82))),
        830 => (1, A::Motion(Motion::Cycle(Cycle::G83))),
        840 => (1, A::Motion(Motion::Cycle(Cycle::G84))),
        850 => (1, A::Motion(Motion::Cycle(Cycle::G85))),
        860 => (1, A::Motion(Motion::Cycle(Cycle::G86))),
        870 => (1, A::Motion(Motion::Cycle(Cycle::G87))),
        880 => (1, A::Motion(Motion::Cycle(Cycle::G88))),
        890 => (1, A::Motion(Motion::Cycle(Cycle::G89))),
        382..=385 => (
            1,
            A::Motion(Motion::Probe(ProbeKind {
                toward: code <= 383,
                error_on_no_contact: code.is_multiple_of(2),
            })),
        ),
        980 => (10, A::Retract(Retract::InitialLevel)),
        990 => (10, A::Retract(Retract::RPlane)),
        930 => (5, A::FeedMode(FeedMode::InverseTime)),
        950 => (5, A::FeedMode(FeedMode::PerRevolution)),
        40 => (0, A::NonModal(NonModal::Dwell)),
        530 => (0, A::NonModal(NonModal::MachineCoords)),
        920 => (0, A::NonModal(NonModal::SetAxisOffsets)),
        520 => (0, A::NonModal(NonModal::LocalOffsets)),
        921 => (0, A::NonModal(NonModal::ResetAxisOffsets)),
        922 => (0, A::NonModal(NonModal::SuspendAxisOffsets)),
        923 => (0, A::NonModal(NonModal::RestoreAxisOffsets)),
        280 => (0, A::NonModal(NonModal::Home(0))),
        300 => (0, A::NonModal(NonModal::Home(1))),
        281 => (0, A::NonModal(NonModal::SetHome(0))),
        301 => (0, A::NonModal(NonModal::SetHome(1))),
        100 => (0, A::NonModal(NonModal::SetCoordData)),
        610 | 611 | 640 => (13, A::PathControl),
        170 => (2, A::Plane(Plane::Xy)),
        180 => (2, A::Plane(Plane::Zx)),
        190 => (2, A::Plane(Plane::Yz)),
        900 => (3, A::Distance(Distance::Absolute)),
        910 => (3, A::Distance(Distance::Incremental)),
        901 => (4, A::ArcDistance(Distance::Absolute)),
        911 => (4, A::ArcDistance(Distance::Incremental)),
        940 => (5, A::FeedMode(FeedMode::PerMinute)),
        200 => (6, A::Units(Units::Inch)),
        210 => (6, A::Units(Units::Mm)),
        400 => (7, A::CutterComp(CompMode::Off)),
        410 | 411 | 420 | 421 => (
            7,
            A::CutterComp(CompMode::On {
                left: code < 420,
                given: code % 10 == 1,
            }),
        ),
        430 => (8, A::ToolLength(ToolLength::Table)),
        431 => (8, A::ToolLength(ToolLength::Given)),
        434 => (8, A::ToolLength(ToolLength::Tcp)),
        490 => (8, A::ToolLength(ToolLength::Off)),
        540..=590 if code.is_multiple_of(10) => (12, A::CoordSystem(((code - 540) / 10) as usize)),
        591..=593 => (12, A::CoordSystem((code - 591) as usize + 6)),
        _ => return Err(g_unsupported(code)),
    })
}

/// Classifies a G code we do not implement: known to LinuxCNC, or (G43.5) to the controllers
/// whose G43.4 the interpreter follows (unsupported), or unknown.
fn g_unsupported(code: u32) -> Rejected {
    let what = match code {
        50..=53 => "spline",
        70 | 80 => "lathe diameter/radius mode",
        171 | 181 | 191 => "UVW plane",
        330 | 331 => "spindle-synchronised motion",
        432 => "additional tool length offset",
        435 => "tool centre point control with the tool axis as a vector I J K; program the rotary angles under G43.4",
        700 | 710..=712 | 720..=722 | 760 => "lathe cycle",
        960 | 970 => "spindle speed mode",
        _ => return Rejected::Unknown,
    };
    Rejected::Unsupported(what)
}

/// Classifies an M code we do not implement.
fn m_unsupported(code: u32) -> Rejected {
    if !code.is_multiple_of(10) {
        return Rejected::Unknown;
    }
    let what = match code / 10 {
        98 | 99 => "subroutine call/return",
        100..=199 => "user-defined M code",
        _ => return Rejected::Unknown,
    };
    Rejected::Unsupported(what)
}

/// The G code of a cycle, for messages.
pub(super) fn cycle_name(c: Cycle) -> &'static str {
    match c {
        Cycle::G73 => "G73",
        Cycle::G74 => "G74",
        Cycle::G81 => "G81",
        Cycle::G82 => "G82",
        Cycle::G83 => "G83",
        Cycle::G84 => "G84",
        Cycle::G85 => "G85",
        Cycle::G86 => "G86",
        Cycle::G87 => "G87",
        Cycle::G88 => "G88",
        Cycle::G89 => "G89",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::syntax::{parse_line, GcodeErrorKind};

    fn dec(text: &str) -> Result<Decoded, GcodeError> {
        let line = parse_line(4, text).expect("lexes").expect("has words");
        decode(&Block::from_literal_line(&line).expect("literal values"))
    }

    #[test]
    fn modal_codes_of_different_groups_share_a_block() {
        let d = dec("G17 G21 G90 G91.1 G54 G40 G49 G94 G1 X1 F100 S2 T3 M6 M3 M2").unwrap();
        assert_eq!(d.plane, Some(Plane::Xy));
        assert_eq!(d.units, Some(Units::Mm));
        assert_eq!(d.distance, Some(Distance::Absolute));
        assert_eq!(d.arc_distance, Some(Distance::Incremental));
        assert_eq!(d.coord_system, Some(0));
        assert_eq!(d.motion.map(|m| m.0), Some(Motion::Linear));
        assert_eq!(d.spindle.map(|s| s.0), Some(SpindleDir::Cw));
        assert!(d.tool_change.is_some() && d.stop.is_some());
    }

    #[test]
    fn two_motion_codes_in_one_block_are_invalid_at_the_second() {
        let e = dec("G0 G2 X1 R1").unwrap_err();
        assert_eq!((e.line, e.col, e.kind), (4, 4, GcodeErrorKind::Invalid));
        assert!(e.msg.contains("G0") && e.msg.contains("G2"), "{e}");
    }

    #[test]
    fn g80_gives_way_to_another_motion_code_in_either_order() {
        // rs274: `G80 G0 X1 Y2` and `G0 G80 X1` traverse, `G1 G80 X1 F100` feeds,
        // `G80 G2 X2 I1 F100` arcs, `G80 G81 G80 X1 Z-1 R1 F10` drills.
        for (text, motion, col) in [
            ("G00 G17 G21 G40 G49 G80 G90", Motion::Rapid, 1),
            ("G80 G0 X1 Y2", Motion::Rapid, 5),
            ("G1 G80 X1 F100", Motion::Linear, 1),
            ("G80 G2 X2 I1", Motion::Arc { clockwise: true }, 5),
            ("G80 G81 G80 X1 Z-1 R1", Motion::Cycle(Cycle::G81), 5),
        ] {
            let d = dec(text).unwrap_or_else(|e| panic!("{text}: {e}"));
            assert_eq!(d.motion, Some((motion, col)), "{text}");
        }
        assert_eq!(
            dec("G80 G80").unwrap().motion.map(|m| m.0),
            Some(Motion::Cancel)
        );
    }

    #[test]
    fn two_motion_codes_beside_g80_still_conflict() {
        // rs274: "Two g codes used from same modal group" for both.
        for text in ["G0 G80 G1 X1", "G80 G0 G1 X1"] {
            let e = dec(text).unwrap_err();
            assert_eq!(
                (e.col, e.kind),
                (text.rfind("G1").unwrap() + 1, GcodeErrorKind::Invalid)
            );
            assert!(e.msg.starts_with("G0 and G1 "), "{text}: {e}");
        }
    }

    #[test]
    fn two_spindle_m_codes_are_invalid() {
        assert_eq!(dec("M3 M5").unwrap_err().kind, GcodeErrorKind::Invalid);
    }

    #[test]
    fn g59_selects_the_sixth_work_offset() {
        assert_eq!(dec("G59").unwrap().coord_system, Some(5));
    }

    #[test]
    fn known_linuxcnc_codes_are_unsupported_and_unknown_codes_invalid() {
        for text in ["G43.2", "G43.5 I0 J0 K1", "G76 Z1", "G33", "M98", "G5.2"] {
            let e = dec(text).unwrap_err();
            assert_eq!(e.kind, GcodeErrorKind::Unsupported, "{text}: {e}");
            assert!(
                e.msg.starts_with(text.split(' ').next().unwrap()),
                "{text}: {e}"
            );
        }
        for text in ["G6", "G999", "M2.5", "G1.25", "M1000"] {
            assert_eq!(
                dec(text).unwrap_err().kind,
                GcodeErrorKind::Invalid,
                "{text}"
            );
        }
    }
}
