//! Feed rate modes G93 (inverse time), G94 (units per minute), G95 (units per revolution):
//! every feed move leaves the interpreter with an equivalent feed in mm/min.
//!
//! - G94: the F word, in program units per minute.
//! - G95: F (program units per revolution) × the programmed spindle speed S (rpm).
//! - G93: the move takes 1/F minutes: feed = path length × F. The path length of an arc is
//!   that of its helix: √((radius · swept angle)² + (axis travel)²).
//!
//! Rotary axes (LinuxCNC's rule): the feed applies to the XYZ path whenever X, Y or Z moves,
//! the rotary axes following in step; a straight move of A, B, C alone
//! ([`super::rotary_only`]) has its feed along the angle √(ΔA² + ΔB² + ΔC²), in deg/min
//! (G94: F; G95: F × S; G93: angle × F). Angles are never scaled by G20.
//!
//! Selecting any of G93, G94, G95 sets the feed rate to 0 (LinuxCNC does), so a feed move must
//! then get a new F; under G93 every G1/G2/G3 block needs its own F.

use super::checks::{motion_name, plane_axes};
use super::decode::{Decoded, FeedMode, Motion};
use super::CanonKind;
use crate::syntax::{Block, GcodeError};
use std::f64::consts::TAU;

/// Checks a feed move (G1, G2, G3 or a canned cycle) against the feed mode the block sees:
/// G93 needs F in the block and refuses cycles; G95 needs a spindle speed.
pub(super) fn check_move(
    block: &Block,
    d: &Decoded,
    col: usize,
    m: Motion,
    current: FeedMode,
    rpm: f64,
) -> Result<(), GcodeError> {
    let mode = d.feed_mode.map_or(current, |f| f.0);
    let name = motion_name(m);
    let inv = |msg: String| Err(GcodeError::invalid(block.line, col, msg));
    match mode {
        FeedMode::InverseTime if matches!(m, Motion::Cycle(_)) => inv(format!(
            "{name} (canned cycle) in G93 inverse time feed mode"
        )),
        FeedMode::InverseTime if d.f.is_none() => inv(format!(
            "{name} in G93 inverse time feed mode needs an F word in its block"
        )),
        FeedMode::PerRevolution if d.s.map_or(rpm, |s| s.value) <= 0.0 => inv(format!(
            "{name} in G95 feed per revolution mode with spindle speed S0"
        )),
        _ => Ok(()),
    }
}

/// Rewrites the feed of every Feed/Arc action of one block from the modal F value.
/// `start`: the tool position (mm) and rotary angles (degrees) before the block; `f`: the F
/// value (G94/G95: mm or degrees per minute or per revolution; G93: 1/minutes); `rpm`:
/// programmed spindle speed; `mm_per_unit`: 25.4 under G20, 1 under G21 (the F value of
/// G94/G95 is stored in mm; a move of the rotary axes alone reads it unscaled, in degrees,
/// as LinuxCNC's angular feed does).
pub(super) fn apply(
    mode: FeedMode,
    kinds: &mut [CanonKind],
    start: ([f64; 3], [f64; 3]),
    f: f64,
    rpm: f64,
    mm_per_unit: f64,
) {
    let (mut pos, mut abc) = start;
    for kind in kinds.iter_mut() {
        match kind {
            CanonKind::Traverse {
                end_mm,
                end_abc_deg,
            } => (pos, abc) = (*end_mm, *end_abc_deg),
            CanonKind::Feed {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
            }
            | CanonKind::Probe {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
                ..
            } => {
                if super::rotary_only(pos, *end_mm, abc, *end_abc_deg) {
                    let unscale = match mode {
                        FeedMode::InverseTime => 1.0,
                        _ => mm_per_unit,
                    };
                    *feed_mm_per_min = rate(mode, f, rpm, dist(abc, *end_abc_deg)) / unscale;
                } else if mode != FeedMode::PerMinute {
                    *feed_mm_per_min = rate(mode, f, rpm, dist(pos, *end_mm));
                }
                (pos, abc) = (*end_mm, *end_abc_deg);
            }
            CanonKind::Arc {
                end_mm,
                center_mm,
                plane,
                clockwise,
                extra_turns,
                feed_mm_per_min,
                end_abc_deg,
            } => {
                if mode == FeedMode::PerMinute {
                    (pos, abc) = (*end_mm, *end_abc_deg);
                    continue;
                }
                let (a1, a2, ax) = plane_axes(*plane);
                let v0 = [pos[a1] - center_mm[a1], pos[a2] - center_mm[a2]];
                let v1 = [end_mm[a1] - center_mm[a1], end_mm[a2] - center_mm[a2]];
                let radius = v0[0].hypot(v0[1]);
                let mut sweep = v1[1].atan2(v1[0]) - v0[1].atan2(v0[0]);
                if *clockwise {
                    sweep = -sweep;
                }
                // Within (0, 2π]: an arc ending where it starts is a full turn.
                sweep = sweep.rem_euclid(TAU);
                if sweep <= 1e-12 {
                    sweep = TAU;
                }
                sweep += TAU * f64::from(*extra_turns);
                let length = (radius * sweep).hypot(end_mm[ax] - pos[ax]);
                *feed_mm_per_min = rate(mode, f, rpm, length);
                (pos, abc) = (*end_mm, *end_abc_deg);
            }
            _ => {}
        }
    }
}

fn rate(mode: FeedMode, f: f64, rpm: f64, length_mm: f64) -> f64 {
    match mode {
        FeedMode::PerMinute => f,
        FeedMode::PerRevolution => f * rpm,
        // A move of no length takes no time whatever the rate: keep it positive.
        FeedMode::InverseTime if length_mm <= 0.0 => f,
        FeedMode::InverseTime => length_mm * f,
    }
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::interp::Plane;

    #[test]
    fn inverse_time_helix_feed_matches_linuxcnc() {
        // rs274: `G93 G2 X10 Y10 Z0 I5 J5 F3` from (0, 0, 10) → SET_FEED_RATE(73.0843).
        let mut kinds = [CanonKind::Arc {
            end_mm: [10.0, 10.0, 0.0],
            end_abc_deg: [0.0; 3],
            center_mm: [5.0, 5.0, 10.0],
            plane: Plane::Xy,
            clockwise: true,
            extra_turns: 0,
            feed_mm_per_min: 0.0,
        }];
        apply(
            FeedMode::InverseTime,
            &mut kinds,
            ([0.0, 0.0, 10.0], [0.0; 3]),
            3.0,
            0.0,
            1.0,
        );
        let CanonKind::Arc {
            feed_mm_per_min, ..
        } = kinds[0]
        else {
            unreachable!()
        };
        assert!(
            (feed_mm_per_min - 73.0843).abs() < 1e-4,
            "{feed_mm_per_min}"
        );
    }
}
