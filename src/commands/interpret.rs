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

mod fixed;

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

/// The numbered call lines, built in a buffer that goes to the writer in large pieces (a
/// million lines of moves would otherwise be a million small writes).
struct Calls<'w> {
    out: &'w mut dyn Write,
    buf: Vec<u8>,
    n: u64,
}

impl Calls<'_> {
    /// Bytes gathered before they are written.
    const CHUNK: usize = 1 << 16;

    /// Starts call line `n + 1`: the number (5 wide) and the `N.....` of `rs274`.
    fn begin(&mut self) {
        self.n += 1;
        fixed::push_u64_padded(&mut self.buf, self.n, 5);
        self.buf.extend_from_slice(b" N..... ");
    }

    /// Ends the line; writes the buffer once it is large.
    fn end(&mut self) -> std::io::Result<()> {
        self.buf.push(b'\n');
        if self.buf.len() >= Self::CHUNK {
            self.out.write_all(&self.buf)?;
            self.buf.clear();
        }
        Ok(())
    }

    /// One call given as text.
    fn text(&mut self, text: &str) -> std::io::Result<()> {
        self.begin();
        self.buf.extend_from_slice(text.as_bytes());
        self.end()
    }

    /// `NAME(v, v, …)` with every value at 4 decimals.
    fn numbers(&mut self, name: &str, values: &[f64]) -> std::io::Result<()> {
        self.begin();
        self.buf.extend_from_slice(name.as_bytes());
        self.buf.push(b'(');
        for (i, v) in values.iter().enumerate() {
            if i > 0 {
                self.buf.extend_from_slice(b", ");
            }
            fixed::push_fixed4(&mut self.buf, *v);
        }
        self.buf.push(b')');
        self.end()
    }

    /// A move to `p` (mm) and `a` (deg): `NAME(x, y, z, a, b, c)`.
    fn point(&mut self, name: &str, p: &[f64; 3], a: &[f64; 3]) -> std::io::Result<()> {
        self.numbers(name, &[p[0], p[1], p[2], a[0], a[1], a[2]])
    }

    /// `SET_FEED_RATE(f)` when `f` (mm/min) differs from the rate in force, `feed`, which it
    /// becomes: LinuxCNC writes the call only on a change.
    fn feed_rate(&mut self, feed: &mut Option<f64>, feed_mm_per_min: f64) -> std::io::Result<()> {
        if *feed != Some(feed_mm_per_min) {
            *feed = Some(feed_mm_per_min);
            self.numbers("SET_FEED_RATE", &[feed_mm_per_min])?;
        }
        Ok(())
    }

    /// Writes what is left.
    fn finish(self) -> std::io::Result<()> {
        self.out.write_all(&self.buf)?;
        self.out.flush()
    }
}

/// Writes the canonical calls of `moves` (see the module documentation).
///
/// # Errors
/// A failed write.
pub fn write_calls(moves: &[CanonMove], out: &mut dyn Write) -> std::io::Result<()> {
    let mut calls = Calls {
        out,
        buf: Vec::with_capacity(Calls::CHUNK + 256),
        n: 0,
    };
    let c = &mut calls;
    c.text("USE_LENGTH_UNITS(CANON_UNITS_MM)")?;
    let (mut feed, mut plane, mut speed) = (None, Plane::Xy, None);
    let mut coolant = (false, false);
    for m in moves {
        match &m.kind {
            CanonKind::Traverse {
                end_mm,
                end_abc_deg,
            } => {
                c.point("STRAIGHT_TRAVERSE", end_mm, end_abc_deg)?;
            }
            CanonKind::Feed {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
            } => {
                c.feed_rate(&mut feed, *feed_mm_per_min)?;
                c.point("STRAIGHT_FEED", end_mm, end_abc_deg)?;
            }
            CanonKind::Probe {
                end_mm,
                end_abc_deg,
                feed_mm_per_min,
                ..
            } => {
                c.feed_rate(&mut feed, *feed_mm_per_min)?;
                c.text("TURN_PROBE_ON()")?;
                c.text(&interp::straight_probe_call(*end_mm, *end_abc_deg))?;
                c.text("TURN_PROBE_OFF()")?;
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
                c.feed_rate(&mut feed, *feed_mm_per_min)?;
                if *p != plane {
                    plane = *p;
                    let name = match p {
                        Plane::Xy => "XY",
                        Plane::Zx => "XZ",
                        Plane::Yz => "YZ",
                    };
                    c.text(&format!("SELECT_PLANE(CANON_PLANE_{name})"))?;
                }
                let (a1, a2, ax) = match p {
                    Plane::Xy => (0, 1, 2),
                    Plane::Zx => (2, 0, 1),
                    Plane::Yz => (1, 2, 0),
                };
                let turns = 1 + i64::from(*extra_turns);
                let rotation = if *clockwise { -turns } else { turns };
                arc_call(
                    c,
                    [end_mm[a1], end_mm[a2], center_mm[a1], center_mm[a2]],
                    rotation,
                    [end_mm[ax], end_abc_deg[0], end_abc_deg[1], end_abc_deg[2]],
                )?;
            }
            CanonKind::Dwell { duration_s } => c.text(&format!("DWELL({duration_s:.4})"))?,
            CanonKind::Spindle { dir, rpm } => {
                if speed != Some(*rpm) {
                    speed = Some(*rpm);
                    c.text(&format!("SET_SPINDLE_SPEED(0, {rpm:.4})"))?;
                }
                let text = match dir {
                    SpindleDir::Cw => "START_SPINDLE_CLOCKWISE(0)",
                    SpindleDir::Ccw => "START_SPINDLE_COUNTERCLOCKWISE(0)",
                    SpindleDir::Off => "STOP_SPINDLE_TURNING(0)",
                };
                c.text(text)?;
            }
            CanonKind::ToolChange { tool } => c.text(&format!("CHANGE_TOOL({tool})"))?,
            CanonKind::Coolant { mist, flood } => {
                if !*mist && !*flood {
                    c.text("MIST_OFF()")?;
                    c.text("FLOOD_OFF()")?;
                } else if *mist && !coolant.0 {
                    c.text("MIST_ON()")?;
                } else if *flood && !coolant.1 {
                    c.text("FLOOD_ON()")?;
                }
                coolant = (*mist, *flood);
            }
            CanonKind::Pause(kind) => {
                if *kind == PauseKind::PalletShuttle {
                    c.text("PALLET_SHUTTLE()")?;
                }
                let text = match kind {
                    PauseKind::Optional => "OPTIONAL_PROGRAM_STOP()",
                    _ => "PROGRAM_STOP()",
                };
                c.text(text)?;
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
                c.text(&format!("ORIENT_SPINDLE(0, {angle_deg:.4}, {p})"))?;
                if let Some(q) = timeout_s {
                    c.text(&format!("SPINDLE.0.WAIT_ORIENT_COMPLETE({q:.4})"))?;
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
                c.text(&text)?;
            }
            CanonKind::Message(text) => c.text(&format!("MESSAGE(\"{text}\")"))?,
            CanonKind::ProgramEnd => c.text("PROGRAM_END()")?,
        }
    }
    calls.finish()
}

/// `ARC_FEED(first end, second end, first centre, second centre, rotation, axis end, a, b, c)`.
fn arc_call(
    c: &mut Calls<'_>,
    in_plane: [f64; 4],
    rotation: i64,
    rest: [f64; 4],
) -> std::io::Result<()> {
    c.begin();
    c.buf.extend_from_slice(b"ARC_FEED(");
    for v in in_plane {
        fixed::push_fixed4(&mut c.buf, v);
        c.buf.extend_from_slice(b", ");
    }
    if rotation < 0 {
        c.buf.push(b'-');
    }
    fixed::push_u64(&mut c.buf, rotation.unsigned_abs());
    for v in rest {
        c.buf.extend_from_slice(b", ");
        fixed::push_fixed4(&mut c.buf, v);
    }
    c.buf.push(b')');
    c.end()
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
