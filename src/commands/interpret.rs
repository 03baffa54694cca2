//! `vmc-twin interpret`: the canonical machine actions of a program, one per line, in the call
//! syntax of LinuxCNC's `rs274` stand-alone interpreter, so that they can be compared with a
//! controller's.
//!
//! Lengths are printed in mm with 4 decimals, as `rs274` prints a G21 program. Unlike `rs274`,
//! coordinates are machine coordinates (work offsets and G92 included); they agree with
//! `rs274`'s when no work offset or G92 offset is active. Only the motion, spindle, tool,
//! coolant, pause, message and end calls are printed (no state-setting calls such as
//! `SET_G5X_OFFSET`).
//!
//! Every move prints the rotary axes A, B, C too (degrees, machine coordinates), as `rs274`
//! does: `STRAIGHT_FEED(x, y, z, a, b, c)`; they are 0 in a program without rotary words.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};

use vmc_gcode::interp::{
    self, CanonKind, CanonMove, InterpConfig, OrientDirection, PauseKind, Plane, SpindleDir,
};

/// What to interpret, validated.
pub struct InterpretConfig {
    /// The G-code program.
    pub program: PathBuf,
    /// Start position and work offsets.
    pub interp: InterpConfig,
}

/// Tool lengths and diameters, mm, by tool number.
pub use vmc_machine::tools::ToolData;

/// Reads a tool table (TOML, see `docs/usage.md`) as (tool number, length in mm) and
/// (tool number, diameter in mm) pairs, lengths as written (as `rs274` reads its table).
///
/// # Errors
/// As [`vmc_machine::tools::ToolTable::load`].
pub fn load_tools(path: &std::path::Path) -> Result<ToolData> {
    Ok(vmc_machine::tools::ToolTable::load(path)?.absolute_data())
}

/// Interprets the program and prints its canonical calls.
///
/// # Errors
/// An unreadable or invalid program (with line and column).
pub fn interpret(cfg: &InterpretConfig, out: &mut dyn Write) -> Result<()> {
    let file = cfg.program.display().to_string();
    let text = vmc_machine::read::read_text(&cfg.program)
        .with_context(|| format!("{file}: cannot read program"))?;
    let moves = interp::run_program(&text, &cfg.interp)
        .map_err(|e| anyhow::anyhow!("{}", e.display_in(&file)))?;
    write_calls(&moves, out)?;
    Ok(())
}

/// Writes the canonical calls of `moves` (see the module documentation).
///
/// # Errors
/// A failed write.
pub fn write_calls(moves: &[CanonMove], out: &mut dyn Write) -> std::io::Result<()> {
    let mut n = 0usize;
    let mut call = |out: &mut dyn Write, text: String| {
        n += 1;
        writeln!(out, "{n:5} N..... {text}")
    };
    call(out, "USE_LENGTH_UNITS(CANON_UNITS_MM)".to_string())?;
    let (mut feed, mut plane, mut speed) = (None, Plane::Xy, None);
    let mut coolant = (false, false);
    let point = |p: &[f64; 3], a: &[f64; 3]| {
        format!(
            "{:.4}, {:.4}, {:.4}, {:.4}, {:.4}, {:.4}",
            p[0], p[1], p[2], a[0], a[1], a[2]
        )
    };
    for m in moves {
        match &m.kind {
            CanonKind::Traverse {
                end_mm,
                end_abc_deg,
            } => {
                let p = point(end_mm, end_abc_deg);
                call(out, format!("STRAIGHT_TRAVERSE({p})"))?;
            }
            CanonKind::Feed {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
            } => {
                if feed != Some(*feed_mm_per_min) {
                    feed = Some(*feed_mm_per_min);
                    call(out, format!("SET_FEED_RATE({feed_mm_per_min:.4})"))?;
                }
                let p = point(end_mm, end_abc_deg);
                call(out, format!("STRAIGHT_FEED({p})"))?;
            }
            CanonKind::Probe {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
                ..
            } => {
                if feed != Some(*feed_mm_per_min) {
                    feed = Some(*feed_mm_per_min);
                    call(out, format!("SET_FEED_RATE({feed_mm_per_min:.4})"))?;
                }
                call(out, "TURN_PROBE_ON()".to_string())?;
                call(out, interp::straight_probe_call(*end_mm, *end_abc_deg))?;
                call(out, "TURN_PROBE_OFF()".to_string())?;
            }
            CanonKind::Arc {
                end_mm,
                end_abc_deg,
                center_mm,
                plane: p,
                clockwise,
                extra_turns,
                feed_mm_per_min,
            } => {
                if feed != Some(*feed_mm_per_min) {
                    feed = Some(*feed_mm_per_min);
                    call(out, format!("SET_FEED_RATE({feed_mm_per_min:.4})"))?;
                }
                if *p != plane {
                    plane = *p;
                    let name = match p {
                        Plane::Xy => "XY",
                        Plane::Zx => "XZ",
                        Plane::Yz => "YZ",
                    };
                    call(out, format!("SELECT_PLANE(CANON_PLANE_{name})"))?;
                }
                let (a1, a2, ax) = match p {
                    Plane::Xy => (0, 1, 2),
                    Plane::Zx => (2, 0, 1),
                    Plane::Yz => (1, 2, 0),
                };
                let turns = 1 + i64::from(*extra_turns);
                let rotation = if *clockwise { -turns } else { turns };
                call(
                    out,
                    format!(
                        "ARC_FEED({:.4}, {:.4}, {:.4}, {:.4}, {rotation}, {:.4}, {:.4}, {:.4}, {:.4})",
                        end_mm[a1],
                        end_mm[a2],
                        center_mm[a1],
                        center_mm[a2],
                        end_mm[ax],
                        end_abc_deg[0],
                        end_abc_deg[1],
                        end_abc_deg[2],
                    ),
                )?;
            }
            CanonKind::Dwell { duration_s } => call(out, format!("DWELL({duration_s:.4})"))?,
            CanonKind::Spindle { dir, rpm } => {
                if speed != Some(*rpm) {
                    speed = Some(*rpm);
                    call(out, format!("SET_SPINDLE_SPEED(0, {rpm:.4})"))?;
                }
                let text = match dir {
                    SpindleDir::Cw => "START_SPINDLE_CLOCKWISE(0)",
                    SpindleDir::Ccw => "START_SPINDLE_COUNTERCLOCKWISE(0)",
                    SpindleDir::Off => "STOP_SPINDLE_TURNING(0)",
                };
                call(out, text.to_string())?;
            }
            CanonKind::ToolChange { tool } => call(out, format!("CHANGE_TOOL({tool})"))?,
            CanonKind::Coolant { mist, flood } => {
                if !*mist && !*flood {
                    call(out, "MIST_OFF()".to_string())?;
                    call(out, "FLOOD_OFF()".to_string())?;
                } else if *mist && !coolant.0 {
                    call(out, "MIST_ON()".to_string())?;
                } else if *flood && !coolant.1 {
                    call(out, "FLOOD_ON()".to_string())?;
                }
                coolant = (*mist, *flood);
            }
            CanonKind::Pause(kind) => {
                if *kind == PauseKind::PalletShuttle {
                    call(out, "PALLET_SHUTTLE()".to_string())?;
                }
                let text = match kind {
                    PauseKind::Optional => "OPTIONAL_PROGRAM_STOP()",
                    _ => "PROGRAM_STOP()",
                };
                call(out, text.to_string())?;
            }
            CanonKind::SpindleOrient {
                angle_deg,
                direction,
                timeout_s,
            } => {
                let p = match direction {
                    OrientDirection::Shortest => 0,
                    OrientDirection::Clockwise => 1,
                    OrientDirection::CounterClockwise => 2,
                };
                call(out, format!("ORIENT_SPINDLE(0, {angle_deg:.4}, {p})"))?;
                if let Some(q) = timeout_s {
                    call(out, format!("SPINDLE.0.WAIT_ORIENT_COMPLETE({q:.4})"))?;
                }
            }
            CanonKind::Io { m, p, e, l, q } => {
                let n = |v: &Option<f64>| v.map_or(0.0, |v| v);
                let text = match m {
                    62 => format!("SET_MOTION_OUTPUT_BIT({})", n(p)),
                    63 => format!("CLEAR_MOTION_OUTPUT_BIT({})", n(p)),
                    64 => format!("SET_AUX_OUTPUT_BIT({})", n(p)),
                    65 => format!("CLEAR_AUX_OUTPUT_BIT({})", n(p)),
                    66 => format!(
                        "WAIT({}, {}, {}, {:.4})",
                        n(p).max(n(e)),
                        u8::from(e.is_some()),
                        n(l),
                        n(q)
                    ),
                    67 => format!("SET_MOTION_OUTPUT_VALUE({}, {:.4})", n(e), n(q)),
                    68 => format!("SET_AUX_OUTPUT_VALUE({}, {:.4})", n(e), n(q)),
                    _ => format!("M{m}(P {})", n(p)),
                };
                call(out, text)?;
            }
            CanonKind::Message(text) => call(out, format!("MESSAGE(\"{text}\")"))?,
            CanonKind::ProgramEnd => call(out, "PROGRAM_END()".to_string())?,
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calls_read_like_rs274() {
        let moves = interp::run_program(
            "G0 X1 Y1\nS1000 M3\nG1 X2 F100\nG2 X3 Y2 I1 J0\nG4 P2\nM8\nM30",
            &InterpConfig::default(),
        )
        .unwrap();
        let mut out = Vec::new();
        write_calls(&moves, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let calls: Vec<&str> = text.lines().map(|l| &l[13..]).collect();
        assert_eq!(
            calls,
            vec![
                "USE_LENGTH_UNITS(CANON_UNITS_MM)",
                "STRAIGHT_TRAVERSE(1.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "SET_SPINDLE_SPEED(0, 1000.0000)",
                "START_SPINDLE_CLOCKWISE(0)",
                "SET_FEED_RATE(100.0000)",
                "STRAIGHT_FEED(2.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000)",
                "ARC_FEED(3.0000, 2.0000, 3.0000, 1.0000, -1, 0.0000, 0.0000, 0.0000, 0.0000)",
                "DWELL(2.0000)",
                "FLOOD_ON()",
                "PROGRAM_END()",
            ]
        );
    }
}
