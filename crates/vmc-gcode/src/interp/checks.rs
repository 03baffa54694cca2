//! Word checks that need no modal state (values, G10, I/O M codes) and the names used in
//! messages, for the modal state machine (`exec`).

use super::arc::ArcError;
use super::decode::{Decoded, Motion};
use super::Plane;
use crate::syntax::{Block, GcodeError, Word};

/// The words an I/O or override M code needs (it claims P, E, L and Q).
pub(super) fn check_io(line: usize, col: usize, m: u32, d: &Decoded) -> Result<(), GcodeError> {
    let need = |ok: bool, what: &str| {
        if ok {
            Ok(())
        } else {
            Err(GcodeError::invalid(line, col, format!("M{m} needs {what}")))
        }
    };
    if d.non_modal.is_some() || matches!(d.motion, Some((Motion::Arc { .. }, _))) {
        return Err(GcodeError::unsupported(
            line,
            col,
            format!("M{m} in a block with G4, G10, G28, G30, G53, G92 or an arc is not supported"),
        ));
    }
    match m {
        62..=65 => need(d.p.is_some(), "a P word (output number)"),
        66 => need(
            d.p.is_some() || d.e.is_some(),
            "a P or E word (input number)",
        ),
        67 | 68 => need(
            d.e.is_some() && d.q.is_some(),
            "E (output number) and Q (value)",
        ),
        _ => Ok(()),
    }
}

/// G10 needs L2 or L20 and P0…P9 (0: the active coordinate system; R is its XY rotation), or
/// L1/L10/L11 and P a tool number (Z its length, R its radius; X and Y tool offsets are not
/// supported: the machine's tools are offset along Z only).
pub(super) fn check_g10(line: usize, col: usize, d: &Decoded) -> Result<(), GcodeError> {
    let l = match d.l {
        Some(l) if l.value == 2.0 || l.value == 20.0 => l,
        Some(l) if [1.0, 10.0, 11.0].contains(&l.value) => return check_g10_tool(line, col, d),
        Some(l) => {
            let msg = format!(
                "G10 L{} is not a valid G10 form (L1, L2, L10, L11 or L20)",
                l.value
            );
            return Err(GcodeError::invalid(line, l.col, msg));
        }
        None => {
            return Err(GcodeError::invalid(
                line,
                col,
                "G10 needs an L word (L1, L2, L10, L11 or L20)",
            ))
        }
    };
    if let Some(r) = d.r.filter(|_| l.value == 20.0) {
        return Err(GcodeError::invalid(line, r.col, "R not allowed in G10 L20"));
    }
    let Some(p) = d.p else {
        return Err(GcodeError::invalid(
            line,
            col,
            "G10 needs a P word (coordinate system 0-9)",
        ));
    };
    if p.value.fract() != 0.0 || !(0.0..=9.0).contains(&p.value) {
        let msg = format!(
            "G10 L{} P{}: P must be a coordinate system 0-9",
            l.value, p.value
        );
        return Err(GcodeError::invalid(line, p.col, msg));
    }
    if let Some(w) = d.ijk.iter().flatten().chain(&d.q).next() {
        return Err(GcodeError::invalid(
            line,
            w.col,
            format!("{} word with G10 L{}", w.letter, l.value),
        ));
    }
    Ok(())
}

/// G10 L1/L10/L11: P a whole tool number; Z and R only (R with L1: a radius ≥ 0).
fn check_g10_tool(line: usize, col: usize, d: &Decoded) -> Result<(), GcodeError> {
    let l = d.l.map_or(1.0, |l| l.value);
    let Some(p) = d.p else {
        let msg = format!("G10 L{l} needs a P word (tool number)");
        return Err(GcodeError::invalid(line, col, msg));
    };
    if p.value < 1.0 || p.value.fract() != 0.0 {
        let msg = format!("G10 L{l} P{}: P must be a tool number >= 1", p.value);
        return Err(GcodeError::invalid(line, p.col, msg));
    }
    if let Some(w) = [d.axes[0], d.axes[1], d.abc[0], d.abc[1], d.abc[2]]
        .into_iter()
        .flatten()
        .next()
    {
        let msg = format!(
            "G10 L{l} {} (a tool offset other than along Z) is not supported",
            w.letter
        );
        return Err(GcodeError::unsupported(line, w.col, msg));
    }
    if let Some(w) = d.ijk.iter().flatten().chain(&d.q).next() {
        let msg = format!("G10 L{l} {} (lathe tool angles) is not supported", w.letter);
        return Err(GcodeError::unsupported(line, w.col, msg));
    }
    if let Some(r) = d.r {
        if r.value < 0.0 {
            return Err(GcodeError::invalid(
                line,
                r.col,
                "G10 tool radius R must not be negative",
            ));
        }
    }
    Ok(())
}

/// Largest magnitude accepted for any number (1e9 mm = 1000 km): keeps every later
/// computation finite.
const MAX_ABS_VALUE: f64 = 1e9;

/// Sign, integrality and range of the values themselves.
pub(super) fn check_values(block: &Block, d: &Decoded) -> Result<(), GcodeError> {
    let inv = |w: &Word, msg: String| GcodeError::invalid(block.line, w.col, msg);
    if let Some(w) = block.words.iter().find(|w| w.value.abs() > MAX_ABS_VALUE) {
        return Err(inv(
            w,
            format!(
                "{} word value out of range (|value| > {MAX_ABS_VALUE:e})",
                w.letter
            ),
        ));
    }
    if let Some(w) = [d.f, d.s].into_iter().flatten().find(|w| w.value < 0.0) {
        return Err(inv(&w, format!("{} word must not be negative", w.letter)));
    }
    if let Some(t) = d.t.filter(|t| t.value < 0.0 || t.value.fract() != 0.0) {
        return Err(inv(&t, "T word must be a non-negative integer".to_string()));
    }
    Ok(())
}

pub(super) const AXES: [char; 3] = ['X', 'Y', 'Z'];
pub(super) const IJK: [char; 3] = ['I', 'J', 'K'];

/// (first, second, normal) axis indices of a plane, LinuxCNC's ARC_FEED order.
pub(super) fn plane_axes(plane: Plane) -> (usize, usize, usize) {
    match plane {
        Plane::Xy => (0, 1, 2),
        Plane::Zx => (2, 0, 1),
        Plane::Yz => (1, 2, 0),
    }
}

pub(super) fn plane_names(plane: Plane) -> (&'static str, &'static str) {
    match plane {
        Plane::Xy => ("XY", "I/J"),
        Plane::Zx => ("ZX", "I/K"),
        Plane::Yz => ("YZ", "J/K"),
    }
}

pub(super) fn motion_name(m: Motion) -> &'static str {
    match m {
        Motion::Rapid => "G0",
        Motion::Linear => "G1",
        Motion::Arc { clockwise: true } => "G2",
        Motion::Arc { clockwise: false } => "G3",
        Motion::Cancel => "G80",
        Motion::Cycle(c) => super::decode::cycle_name(c),
        Motion::Probe(k) => k.code(),
    }
}

/// Message for an arc error; lengths shown in program units (`k` mm per unit).
pub(super) fn arc_error_msg(e: &ArcError, k: f64) -> String {
    match *e {
        ArcError::ZeroRadius { r1_mm, r2_mm } => {
            format!(
                "zero-radius arc (radius to start {:.4}, to end {:.4})",
                r1_mm / k,
                r2_mm / k
            )
        }
        ArcError::RadiusMismatch { r1_mm, r2_mm } => format!(
            "radius to end of arc differs from radius to start (r1 = {:.4}, r2 = {:.4})",
            r1_mm / k,
            r2_mm / k
        ),
        ArcError::RadiusFormFullCircle => {
            "R-form arc ends where it starts (use I/J/K for a full circle)".to_string()
        }
        ArcError::RadiusTooSmall {
            r_mm,
            half_chord_mm,
        } => format!(
            "arc radius R{:.4} too small to reach the end point (half chord {:.4})",
            r_mm / k,
            half_chord_mm / k
        ),
    }
}
