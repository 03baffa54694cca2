//! The checks of a block against the modal state it will see, before anything of it runs:
//! which motion it makes, which words it may carry, and the words of an arc.

use super::super::checks::{
    check_g10, check_io, check_values, motion_name, plane_axes, plane_names, AXES, IJK,
};
use super::super::cycles;
use super::super::decode::{Decoded, Distance, Motion, NonModal, ToolLength};
use super::super::feed;
use super::super::MAX_ARC_TURNS;
use super::{Interpreter, MotionStep};
use crate::syntax::{Block, GcodeError, Word};

impl Interpreter {
    /// All checks of a block against the modal state it will see; decides the motion step.
    pub(super) fn check(&self, block: &Block, d: &Decoded) -> Result<MotionStep, GcodeError> {
        check_values(block, d)?;
        let step = self.motion_step(block, d)?;
        self.check_tcp(block, d, step)?;
        self.check_word_users(block, d, step)?;
        if let MotionStep::Move(Motion::Probe(kind)) = step {
            self.check_probe(block, d, motion_col(block, d), kind)?;
        }
        if let MotionStep::Move(m @ (Motion::Linear | Motion::Arc { .. } | Motion::Cycle(_))) = step
        {
            let col = d
                .motion
                .map(|m| m.1)
                .or_else(|| d.first_axis_word().map(|w| w.col))
                .unwrap_or(block.first_col);
            if let Motion::Arc { clockwise } = m {
                self.check_arc_words(block, d, col, clockwise)?;
            }
            feed::check_move(block, d, col, m, self.feed_mode, self.spindle.1)?;
            let kept = if d.feed_mode.is_some() {
                0.0
            } else {
                self.feed_mm_per_min
            };
            let feed = d.f.map_or(kept, |f| f.value);
            if feed <= 0.0 {
                let name = motion_name(m);
                let msg = format!("{name} with zero feed rate (no F word > 0 given yet)");
                return Err(GcodeError::invalid(block.line, col, msg));
            }
        }
        Ok(step)
    }

    /// Which motion the block makes: axis words move with the block's or the modal motion
    /// mode, unless G92 claims them; an explicit G2/G3 moves even without axis words (full
    /// circle).
    fn motion_step(&self, block: &Block, d: &Decoded) -> Result<MotionStep, GcodeError> {
        let explicit = d.motion.map(|m| m.0);
        if let Some((ToolLength::Given, col)) = d.tool_length {
            if let Some(w) = d.axes[0]
                .or(d.axes[1])
                .or(d.abc.iter().flatten().copied().next())
            {
                let msg = format!(
                    "G43.1 {} (a tool offset other than along Z) is not supported",
                    w.letter
                );
                return Err(GcodeError::unsupported(block.line, w.col, msg));
            }
            if d.motion.is_some_and(|m| m.0 != Motion::Cancel) || d.non_modal.is_some() {
                return Err(GcodeError::invalid(
                    block.line,
                    col,
                    "G43.1 and another code both use the axis words",
                ));
            }
            return Ok(MotionStep::None);
        }
        if let Some((
            nm @ (NonModal::SetAxisOffsets
            | NonModal::LocalOffsets
            | NonModal::Home(_)
            | NonModal::SetCoordData),
            col,
        )) = d.non_modal
        {
            let name = match nm {
                NonModal::SetAxisOffsets => "G92",
                NonModal::LocalOffsets => "G52",
                NonModal::Home(0) => "G28",
                NonModal::Home(_) => "G30",
                _ => "G10",
            };
            if !d.has_axis_words() && nm == NonModal::SetAxisOffsets {
                return Err(GcodeError::invalid(
                    block.line,
                    col,
                    "G92 needs at least one of X, Y, Z, A, B, C",
                ));
            }
            if let Some((m, mcol)) = d.motion.filter(|m| m.0 != Motion::Cancel) {
                let msg = format!("{name} and {} both use the axis words", motion_name(m));
                return Err(GcodeError::invalid(block.line, mcol, msg));
            }
            return Ok(MotionStep::None);
        }
        if let Some(w) = d.first_axis_word() {
            return match explicit.or(self.motion) {
                Some(Motion::Cancel) | None => {
                    let why = if explicit == Some(Motion::Cancel) {
                        "G80 cancels the motion mode"
                    } else {
                        "no motion mode is active"
                    };
                    let msg = format!("{} word without G0/G1/G2/G3 to use it ({why})", w.letter);
                    Err(GcodeError::invalid(block.line, w.col, msg))
                }
                Some(m) => Ok(MotionStep::Move(m)),
            };
        }
        Ok(match explicit {
            // G0/G1 alone: a move to where the tool is (LinuxCNC emits it too).
            Some(m @ (Motion::Arc { .. } | Motion::Rapid | Motion::Linear)) => MotionStep::Move(m),
            Some(Motion::Probe(kind)) => {
                // LinuxCNC: "All axes missing with motion code".
                let msg = format!(
                    "{} needs an axis word (X, Y, Z, A, B, C): the point to probe toward",
                    kind.code()
                );
                return Err(GcodeError::invalid(block.line, motion_col(block, d), msg));
            }
            _ => MotionStep::None,
        })
    }

    /// I/J/K/R need an arc, P needs G4 or an arc (not both), G53 needs G0/G1 in G90.
    fn check_word_users(
        &self,
        block: &Block,
        d: &Decoded,
        step: MotionStep,
    ) -> Result<(), GcodeError> {
        let line = block.line;
        let inv = |w: &Word, msg: &str| GcodeError::invalid(line, w.col, msg);
        let arc_move = matches!(step, MotionStep::Move(Motion::Arc { .. }));
        let cycle = match step {
            MotionStep::Move(Motion::Cycle(c)) => Some(c),
            _ => None,
        };
        if let Some(c) = cycle {
            if let Some(w) = d.abc.iter().flatten().next() {
                // LinuxCNC: "Cannot put an a in canned cycle".
                let msg = format!("{} word in a canned cycle block is not allowed", w.letter);
                return Err(inv(w, &msg));
            }
            return cycles::check_words(line, c, d);
        }
        let g10 = d.non_modal.filter(|n| n.0 == NonModal::SetCoordData);
        let g64_r = d.path_control.filter(|c| c.0 == 640).and(d.r);
        if let (Some(r), Some(_)) = (g64_r, d.orient) {
            return Err(inv(
                &r,
                "R word is ambiguous with both G64 and M19 (use separate lines)",
            ));
        }
        if let Some(r) = g64_r.filter(|r| r.value < 0.0) {
            return Err(inv(&r, "G64 R (planner option) must not be negative"));
        }
        // G64 R: a planner option of newer LinuxCNC versions; our planner does not blend.
        if let Some(col) = d.orient {
            return check_orient(line, col, d);
        }
        let g10_r = |w: &Word| (g10.is_some() || g64_r.is_some()) && w.letter == 'R';
        if let Some(w) = d.first_arc_word().filter(|w| !arc_move && !g10_r(w)) {
            return Err(inv(
                &w,
                &format!("{} word without G2/G3 to use it", w.letter),
            ));
        }
        if let Some((m, col)) = d.io {
            return check_io(line, col, m, d);
        }
        if let Some(e) = d.e {
            return Err(inv(&e, "E word without M66, M67 or M68 to use it"));
        }
        if let Some(col) = d.set_tool {
            return match d.q {
                Some(q) if q.value >= 0.0 && q.value.fract() == 0.0 => Ok(()),
                _ => Err(GcodeError::invalid(
                    line,
                    col,
                    "M61 needs Q, a tool number >= 0",
                )),
            };
        }
        match (d.h, d.tool_length) {
            (Some(h), Some((ToolLength::Table | ToolLength::Tcp, _)))
                if h.value < 0.0 || h.value.fract() != 0.0 =>
            {
                return Err(inv(&h, "H word must be a non-negative integer"));
            }
            (Some(_), Some((ToolLength::Table | ToolLength::Tcp, _))) | (None, _) => {}
            (Some(h), _) => return Err(inv(&h, "H word without G43 to use it")),
        }
        if let Some((ToolLength::Table, col)) = d.tool_length {
            let tool = d.h.map_or(self.spindle_tool, |h| h.value as u32);
            if self.tool_length_mm(tool).is_none() {
                let msg = format!("G43: tool {tool} is not in the tool table");
                return Err(GcodeError::invalid(line, col, msg));
            }
        }
        let g64 = d.path_control.filter(|c| c.0 == 640);
        if let Some(l) = d.l.filter(|_| g10.is_none()) {
            return Err(inv(&l, "L word without G10 to use it"));
        }
        if let Some(q) = d.q.filter(|_| g64.is_none() && g10.is_none()) {
            return Err(inv(&q, "Q word without G64 to use it"));
        }
        if let Some((_, col)) = g10 {
            return check_g10(line, col, d);
        }
        if let (Some(p), Some(_)) = (d.p, g64) {
            if p.value < 0.0 {
                return Err(inv(&p, "G64 P tolerance must not be negative"));
            }
            return Ok(());
        }
        if let Some(q) = d.q.filter(|q| q.value < 0.0) {
            return Err(inv(&q, "G64 Q tolerance must not be negative"));
        }
        let dwell = d.non_modal.filter(|n| n.0 == NonModal::Dwell);
        match (d.p, dwell, arc_move) {
            (Some(p), Some(_), true) => return Err(inv(&p, "P word claimed by both G4 and G2/G3")),
            (Some(p), None, false) => return Err(inv(&p, "P word without G4, G2 or G3 to use it")),
            (Some(p), Some(_), false) if p.value < 0.0 => {
                return Err(inv(&p, "G4 dwell time P must not be negative"))
            }
            (None, Some((_, col)), _) => {
                return Err(GcodeError::invalid(
                    line,
                    col,
                    "G4 needs a P word (dwell time in seconds)",
                ))
            }
            _ => {}
        }
        if let Some((NonModal::MachineCoords, col)) = d.non_modal {
            let mode = d.motion.map(|m| m.0).or(self.motion);
            if !matches!(mode, Some(Motion::Rapid | Motion::Linear)) {
                return Err(GcodeError::invalid(line, col, "G53 needs G0 or G1"));
            }
            if d.distance.unwrap_or(self.distance) == Distance::Incremental {
                return Err(GcodeError::invalid(
                    line,
                    col,
                    "G53 cannot be used in G91 incremental mode",
                ));
            }
        }
        Ok(())
    }

    /// Word checks of an arc block (LinuxCNC's `convert_arc` rules).
    fn check_arc_words(
        &self,
        block: &Block,
        d: &Decoded,
        col: usize,
        clockwise: bool,
    ) -> Result<(), GcodeError> {
        let line = block.line;
        let g = if clockwise { "G2" } else { "G3" };
        let plane = d.plane.unwrap_or(self.plane);
        let (a1, a2, axis) = plane_axes(plane);
        let (pn, letters) = plane_names(plane);
        let has_ijk = d.ijk.iter().any(Option::is_some);
        match (d.r, has_ijk) {
            (None, false) => {
                return Err(GcodeError::invalid(
                    line,
                    col,
                    format!("{g} needs I/J/K or R"),
                ))
            }
            (Some(r), true) => {
                return Err(GcodeError::invalid(
                    line,
                    r.col,
                    format!("{g} cannot mix R with I/J/K"),
                ))
            }
            (Some(_), false) => {
                if d.axes[a1].is_none() && d.axes[a2].is_none() {
                    let msg = format!(
                        "{g} with R needs {} or {} (end point in the {pn} plane)",
                        AXES[a1], AXES[a2]
                    );
                    return Err(GcodeError::invalid(line, col, msg));
                }
            }
            (None, true) => {
                if let Some(w) = d.ijk[axis] {
                    return Err(GcodeError::invalid(
                        line,
                        w.col,
                        format!(
                            "{} word given for an arc in the {pn} plane (uses {letters})",
                            w.letter
                        ),
                    ));
                }
                if d.arc_distance.unwrap_or(self.arc_distance) == Distance::Absolute {
                    for a in [a1, a2] {
                        if d.ijk[a].is_none() {
                            let msg = format!(
                                "{} word missing for an absolute-centre (G90.1) arc",
                                IJK[a]
                            );
                            return Err(GcodeError::invalid(line, col, msg));
                        }
                    }
                }
            }
        }
        if let Some(p) = d.p {
            if p.value < 1.0 || (p.value - p.value.round()).abs() > 1e-9 {
                return Err(GcodeError::invalid(
                    line,
                    p.col,
                    format!("{g} turn count P must be a whole number >= 1"),
                ));
            }
            if p.value > f64::from(MAX_ARC_TURNS) {
                let msg = format!(
                    "{g} turn count P{} above the supported maximum {MAX_ARC_TURNS}",
                    p.value
                );
                return Err(GcodeError::unsupported(line, p.col, msg));
            }
        }
        Ok(())
    }
}

pub(super) fn motion_col(block: &Block, d: &Decoded) -> usize {
    d.motion
        .map(|m| m.1)
        .or_else(|| d.first_axis_word().map(|w| w.col))
        .unwrap_or(block.first_col)
}

/// M19's words: R the angle within 0…360°, Q a wait > 0 s, P the direction 0, 1 or 2; no
/// other word that needs a user (as LinuxCNC's messages say).
fn check_orient(line: usize, col: usize, d: &Decoded) -> Result<(), GcodeError> {
    let inv = |w: &Word, msg: &str| GcodeError::invalid(line, w.col, msg);
    if let Some(r) = d.r.filter(|r| !(0.0..=360.0).contains(&r.value)) {
        return Err(inv(&r, "R value must be within 0..360 with M19"));
    }
    if let Some(q) = d.q.filter(|q| q.value <= 0.0) {
        return Err(inv(&q, "Q word with M19 requires a value > 0"));
    }
    if let Some(p) = d.p.filter(|p| ![0.0, 1.0, 2.0].contains(&p.value)) {
        return Err(inv(&p, "P value must be 0, 1 or 2 with M19"));
    }
    if let Some(w) = [d.ijk[0], d.ijk[1], d.ijk[2], d.e, d.l, d.h]
        .into_iter()
        .flatten()
        .next()
    {
        return Err(inv(
            &w,
            &format!("{} word without a code to use it", w.letter),
        ));
    }
    if d.motion.is_some() || d.has_axis_words() || d.non_modal.is_some() {
        return Err(GcodeError::invalid(
            line,
            col,
            "M19 takes R, Q and P: not with motion, G4 or other codes that use words",
        ));
    }
    Ok(())
}
