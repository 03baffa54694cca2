//! Comparison of our canonical moves with the output of LinuxCNC's stand-alone interpreter
//! `rs274 -g` (the corpus fixtures and the differential fuzzing test): its calls (traverses,
//! feeds, arcs and probe moves) are parsed, turned from its program coordinates into machine
//! coordinates (work offset, G92, XY rotation, tool length), and compared move for move within
//! 1e-4 of the program's unit (it prints 4 decimals). The rotary axes A, B, C (degrees, program coordinates plus the A, B, C
//! of its G5x and G92 offsets) are compared with the same tolerance (at least 1e-4°).

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use vmc_gcode::interp::{CanonKind, CanonMove, InterpConfig, Plane};

/// One motion of the reference output, lengths converted to mm, angles in degrees.
#[derive(Debug, Clone, PartialEq)]
pub enum RefMove {
    /// X, Y, Z (mm), A, B, C (degrees).
    Traverse([f64; 6]),
    /// X, Y, Z (mm), A, B, C (degrees).
    Feed([f64; 6]),
    /// A probe move's target: X, Y, Z (mm), A, B, C (degrees).
    Probe([f64; 6]),
    /// first_end, second_end, first_centre, second_centre, axis_end (mm), A, B, C (degrees),
    /// rotation, plane.
    Arc([f64; 8], i64, Plane),
}

/// A reference move with its comparison tolerance (1e-4 program unit, in mm).
pub type Tolerant = (RefMove, f64);

pub fn args(line: &str) -> Vec<f64> {
    let open = line.find('(').expect("canonical call has '('");
    let close = line.rfind(')').expect("canonical call has ')'");
    line[open + 1..close]
        .split(',')
        .map(|a| {
            a.trim()
                .parse::<f64>()
                .unwrap_or_else(|_| panic!("bad number in {line:?}"))
        })
        .collect()
}

/// Where `rs274`'s program coordinates are on the machine: its G5x offset, G92 offset and XY
/// rotation (as its `SET_G5X_OFFSET`, `SET_G92_OFFSET`, `SET_XY_ROTATION` calls report them)
/// and the tool length, all lengths in mm.
#[derive(Debug, Clone, Copy, Default)]
pub struct RefFrame {
    g5x_mm: [f64; 3],
    g92_mm: [f64; 3],
    /// A, B, C of the G5x and G92 offsets, degrees.
    g5x_abc_deg: [f64; 3],
    g92_abc_deg: [f64; 3],
    rotation_deg: f64,
    tlo_mm: f64,
    /// How far the printed G5x, G92 and tool length values may be from the true ones, mm:
    /// half a unit of their 4th decimal, in the units they were printed in.
    rounding_mm: [f64; 3],
}

impl RefFrame {
    /// `p_machine = rot(p_program + g92) + g5x + tool length (Z)`.
    pub fn machine_from_program(&self, p_mm: [f64; 3]) -> [f64; 3] {
        let q = [0, 1, 2].map(|a| p_mm[a] + self.g92_mm[a]);
        let (sin, cos) = self.rotation_deg.to_radians().sin_cos();
        let (x, y) = if self.rotation_deg == 0.0 {
            (q[0], q[1])
        } else {
            (q[0] * cos - q[1] * sin, q[0] * sin + q[1] * cos)
        };
        [
            x + self.g5x_mm[0],
            y + self.g5x_mm[1],
            q[2] + self.g5x_mm[2] + self.tlo_mm,
        ]
    }
}

impl RefFrame {
    /// Machine angles of program angles: `a_machine = a_program + g5x + g92`.
    pub fn machine_abc(&self, abc_deg: [f64; 3]) -> [f64; 3] {
        [0, 1, 2].map(|a| abc_deg[a] + self.g5x_abc_deg[a] + self.g92_abc_deg[a])
    }

    /// The tolerance of a point `p_mm` (program coordinates) on the machine: `own_mm` (its own
    /// printing) plus the rounding of the printed offsets and of the rotation (4 decimals of a
    /// degree, at the point's distance from the origin).
    fn tolerance_mm(&self, own_mm: f64, p_mm: [f64; 3]) -> f64 {
        let reach_mm = (p_mm[0] + self.g92_mm[0]).hypot(p_mm[1] + self.g92_mm[1]);
        let rotation_rad = if self.rotation_deg == 0.0 {
            0.0
        } else {
            0.5e-4_f64.to_radians()
        };
        own_mm + self.rounding_mm.iter().sum::<f64>() + reach_mm * rotation_rad
    }
}

/// The A, B, C arguments of a motion call from index `first`; 0 where the stored outputs of
/// the fuzzing test left them out (all three 0).
fn angles(args: &[f64], first: usize) -> [f64; 3] {
    [0, 1, 2].map(|i| args.get(first + i).copied().unwrap_or(0.0))
}

/// The plane's (first, second, axis) coordinate indices, as `ARC_FEED` orders them.
pub fn arc_axes(plane: Plane) -> [usize; 3] {
    match plane {
        Plane::Xy => [0, 1, 2],
        Plane::Zx => [2, 0, 1],
        Plane::Yz => [1, 2, 0],
    }
}

pub fn parse_expected(text: &str) -> Vec<Tolerant> {
    let (mut mm_per_unit, mut plane) = (1.0, Plane::Xy);
    // rs274 prints program coordinates, tool-tip positions; ours are the spindle's (tip + tool
    // length) in machine coordinates.
    let mut frame = RefFrame::default();
    let mut moves = Vec::new();
    for line in text.lines() {
        let tol = 1e-4 * mm_per_unit;
        if let Some(rest) = line.split("USE_TOOL_LENGTH_OFFSET(").nth(1) {
            let z = rest.split([' ', ',']).filter(|t| !t.is_empty()).nth(2);
            frame.tlo_mm = z.and_then(|z| z.parse::<f64>().ok()).unwrap_or(0.0) * mm_per_unit;
            frame.rounding_mm[2] = 0.5e-4 * mm_per_unit;
        } else if line.contains("SET_G5X_OFFSET(") {
            let a = args(line);
            frame.g5x_mm = [a[1], a[2], a[3]].map(|v| v * mm_per_unit);
            frame.g5x_abc_deg = [a[4], a[5], a[6]];
            frame.rounding_mm[0] = 0.5e-4 * mm_per_unit;
        } else if line.contains("SET_G92_OFFSET(") {
            let a = args(line);
            frame.g92_mm = [a[0], a[1], a[2]].map(|v| v * mm_per_unit);
            frame.g92_abc_deg = [a[3], a[4], a[5]];
            frame.rounding_mm[1] = 0.5e-4 * mm_per_unit;
        } else if line.contains("SET_XY_ROTATION(") {
            frame.rotation_deg = args(line)[0];
        } else if line.contains("USE_LENGTH_UNITS(CANON_UNITS_INCHES)") {
            mm_per_unit = 25.4;
        } else if line.contains("USE_LENGTH_UNITS(CANON_UNITS_MM)") {
            mm_per_unit = 1.0;
        } else if line.contains("USE_LENGTH_UNITS(") {
            panic!("unexpected length units: {line}");
        } else if line.contains("SELECT_PLANE(CANON_PLANE_XY)") {
            plane = Plane::Xy;
        } else if line.contains("SELECT_PLANE(CANON_PLANE_XZ)") {
            plane = Plane::Zx;
        } else if line.contains("SELECT_PLANE(CANON_PLANE_YZ)") {
            plane = Plane::Yz;
        } else if line.contains("STRAIGHT_TRAVERSE(")
            || line.contains("STRAIGHT_FEED(")
            || line.contains("STRAIGHT_PROBE(")
        {
            let a = args(line);
            let p_mm = [a[0], a[1], a[2]].map(|v| v * mm_per_unit);
            let tol = frame.tolerance_mm(tol, p_mm);
            let p = frame.machine_from_program(p_mm);
            let abc = frame.machine_abc(angles(&a, 3));
            let p = [p[0], p[1], p[2], abc[0], abc[1], abc[2]];
            let m = if line.contains("STRAIGHT_TRAVERSE(") {
                RefMove::Traverse(p)
            } else if line.contains("STRAIGHT_PROBE(") {
                RefMove::Probe(p)
            } else {
                RefMove::Feed(p)
            };
            moves.push((m, tol));
        } else if line.contains("ARC_FEED(") {
            let a = args(line);
            let [i1, i2, ia] = arc_axes(plane);
            let (mut end, mut centre) = ([0.0; 3], [0.0; 3]);
            end[i1] = a[0];
            end[i2] = a[1];
            end[ia] = a[5];
            centre[i1] = a[2];
            centre[i2] = a[3];
            centre[ia] = a[5];
            let tol = frame.tolerance_mm(tol, end.map(|v| v * mm_per_unit));
            let end = frame.machine_from_program(end.map(|v| v * mm_per_unit));
            let centre = frame.machine_from_program(centre.map(|v| v * mm_per_unit));
            let abc = frame.machine_abc(angles(&a, 6));
            let lengths = [
                end[i1], end[i2], centre[i1], centre[i2], end[ia], abc[0], abc[1], abc[2],
            ];
            moves.push((RefMove::Arc(lengths, a[4] as i64, plane), tol));
        }
    }
    moves
}

/// Our motions in the reference's form.
pub fn ours(moves: &[CanonMove]) -> Vec<RefMove> {
    moves
        .iter()
        .filter_map(|m| match m.kind {
            CanonKind::Traverse {
                end_mm: p,
                end_abc_deg: a,
            } => Some(RefMove::Traverse([p[0], p[1], p[2], a[0], a[1], a[2]])),
            CanonKind::Feed {
                end_mm: p,
                end_abc_deg: a,
                ..
            } => Some(RefMove::Feed([p[0], p[1], p[2], a[0], a[1], a[2]])),
            CanonKind::Probe {
                end_mm: p,
                end_abc_deg: a,
                ..
            } => Some(RefMove::Probe([p[0], p[1], p[2], a[0], a[1], a[2]])),
            CanonKind::Arc {
                end_mm,
                end_abc_deg: a,
                center_mm,
                plane,
                clockwise,
                extra_turns,
                ..
            } => {
                let (a1, a2, ax) = match plane {
                    Plane::Xy => (0, 1, 2),
                    Plane::Zx => (2, 0, 1),
                    Plane::Yz => (1, 2, 0),
                };
                let turns = 1 + i64::from(extra_turns);
                let rotation = if clockwise { -turns } else { turns };
                let lengths = [
                    end_mm[a1],
                    end_mm[a2],
                    center_mm[a1],
                    center_mm[a2],
                    end_mm[ax],
                    a[0],
                    a[1],
                    a[2],
                ];
                Some(RefMove::Arc(lengths, rotation, plane))
            }
            _ => None,
        })
        .collect()
}

pub fn same(ours: &RefMove, reference: &Tolerant) -> bool {
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() <= reference.1);
    match (ours, &reference.0) {
        (RefMove::Traverse(a), RefMove::Traverse(b))
        | (RefMove::Feed(a), RefMove::Feed(b))
        | (RefMove::Probe(a), RefMove::Probe(b)) => close(a, b),
        (RefMove::Arc(a, ra, pa), RefMove::Arc(b, rb, pb)) => ra == rb && pa == pb && close(a, b),
        _ => false,
    }
}

/// `None` if the sequences agree, else a description of the first difference.
pub fn compare(ours: &[RefMove], reference: &[Tolerant]) -> Option<String> {
    for (i, (o, r)) in ours.iter().zip(reference).enumerate() {
        if !same(o, r) {
            return Some(format!("move {i}: ours {o:?}, reference {:?}", r.0));
        }
    }
    (ours.len() != reference.len()).then(|| {
        format!(
            "ours has {} moves, reference {}",
            ours.len(),
            reference.len()
        )
    })
}

/// The tool table of `tests/data/linuxcnc/tool.tbl` (inches there) in mm. `rs274` prints
/// tool-tip positions and reports the length offset in a call of its own, which
/// `parse_expected` adds back.
pub fn fixture_config() -> InterpConfig {
    InterpConfig {
        tool_lengths_mm: vec![(1, 150.0), (2, 100.0), (3, 80.0), (4, 120.0)],
        // As rs274 reads the table: the inch values times 25.4.
        tool_diameters_mm: vec![
            (1, 0.472441 * 25.4),
            (2, 0.236220 * 25.4),
            (3, 0.118110 * 25.4),
            (4, 0.787402 * 25.4),
        ],
        ..InterpConfig::default()
    }
}

/// The `rs274` binary: `$RS274` if set, else `rs274` on the PATH; `None` if it cannot run.
pub fn rs274_binary() -> Option<PathBuf> {
    let bin = std::env::var_os("RS274").map_or_else(|| PathBuf::from("rs274"), PathBuf::from);
    let runs = Command::new(&bin)
        .arg("-g")
        .arg("/dev/null")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok();
    runs.then_some(bin)
}

/// The tool table `rs274` reads for the fixtures (inches, see [`fixture_config`]).
pub fn fixture_tool_table() -> PathBuf {
    // Shared with the application's tests, whose manifest is at the workspace root.
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let own = here.join("tests/data/linuxcnc/tool.tbl");
    if own.is_file() {
        own
    } else {
        here.join("crates/vmc-gcode/tests/data/linuxcnc/tool.tbl")
    }
}

/// What `rs274 -g -t TOOLS program` printed: `Ok(calls)` (one per line, without the line
/// counter) if it accepted the program, `Err(message)` if it stopped with an error.
///
/// `rs274` keeps its tool table in a memory-mapped file `$HOME/.tool.mmap`: two runs at the
/// same moment with the same `HOME` overwrite each other's tools (spurious refusals, wrong
/// tool lengths and radii). It runs with `HOME` set to the program's folder, which the caller
/// keeps to itself.
pub fn run_rs274(bin: &Path, program: &Path) -> Result<String, String> {
    let out = Command::new(bin)
        .arg("-g")
        .arg("-t")
        .arg(fixture_tool_table())
        .arg(program)
        .current_dir(program.parent().unwrap_or(Path::new(".")))
        .env("HOME", program.parent().unwrap_or(Path::new(".")))
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run rs274: {e}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let calls: Vec<&str> = stdout
        .lines()
        .filter_map(|l| l.trim_start().split_once(' ').map(|(_, rest)| rest))
        // The block's N number, or "N....." for a block without one.
        .filter(|l| l.starts_with('N'))
        .collect();
    let message: Vec<&str> = stderr
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && *l != "executing")
        .collect();
    if out.status.success() && message.is_empty() {
        Ok(calls.join("\n"))
    } else {
        Err(message.join(" | "))
    }
}
