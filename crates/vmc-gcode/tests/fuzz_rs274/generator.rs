//! A seeded generator of valid milling programs for differential testing against LinuxCNC's
//! `rs274`: random mixes of the words the interpreter supports — lines and arcs in G17, G18
//! and G19 (centre and radius forms, full turns), G90/G91, G20/G21, work offsets G54…G59.3
//! with G10 L2/L20 (and their XY rotation R), G92/G92.1/G92.2/G92.3, G52, tool length offsets
//! G43 H / G43.1 / G49 with tool changes, G28/G30, canned cycles G73 G81 G82 G83 G85 G89 with
//! G98/G99, cutter radius compensation G41/G42 on convex contours (rectangles with an outward
//! arc side, the entry and exit moves well longer than the radius), expressions with
//! parameters and functions, and O-word `sub`/`call`/`if`/`while`/`repeat`; rotary words
//! A, B, C on lines (also `G53`) and arcs, in work offsets (`G10 L2/L20`), `G92`, `G52` and
//! `G28`/`G30`, and now and then on a canned cycle (which both must refuse); `G80` in the
//! same block as G0/G1 or a canned cycle (the other code wins); probe moves G38.2–G38.5
//! (absolute or incremental, with rotary words now and then, some of no length, one as the
//! exit move after G40) followed by moves that start from where the probe left the tool or
//! read #5061–#5063 and #5070.
//!
//! Deterministic: program `i` of seed `s` is the same text on every machine (SplitMix64, no
//! dependency whose stream could change). Numbers are written with at most 3 decimals.

use std::fmt::Write as _;

/// SplitMix64: a small, well-mixed generator with a stable stream.
pub struct Rng(u64);

impl Rng {
    /// A generator for program `index` of `seed`.
    pub fn new(seed: u64, index: u64) -> Self {
        let mut r = Rng(seed ^ index.wrapping_mul(0xA076_1D64_78BD_642F));
        r.next();
        r
    }

    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n`.
    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }

    /// Uniform in `lo..hi`, rounded to 3 decimals.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.next() >> 11) as f64 / (1u64 << 53) as f64;
        round3(lo + (hi - lo) * u)
    }

    fn pick<'a, T>(&mut self, items: &'a [T]) -> &'a T {
        &items[self.below(items.len() as u64) as usize]
    }
}

fn round3(v: f64) -> f64 {
    let r = (v * 1000.0).round() / 1000.0;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// A number as G-code text (up to 3 decimals, no exponent).
fn n(v: f64) -> String {
    let s = format!("{:.3}", round3(v));
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}

/// What the generator knows of the interpreter's state.
struct State {
    /// mm per program unit (1 or 25.4).
    unit_mm: f64,
    /// Active work offset index 0…8.
    coord: usize,
    /// XY rotation of each system, degrees.
    rotation_deg: [f64; 9],
    /// The program position, if known (program units, after an absolute anchor move).
    known: Option<[f64; 3]>,
    incremental: bool,
    plane: u8,
    next_label: u32,
}

impl State {
    /// A length of `mm` in program units.
    fn len(&self, mm: f64) -> f64 {
        mm / self.unit_mm
    }

    fn rotated(&self) -> bool {
        self.rotation_deg[self.coord] != 0.0
    }
}

/// Program `index` of `seed`: a complete program ending with M2.
pub fn program(seed: u64, index: u64) -> String {
    let mut rng = Rng::new(seed, index);
    let mut st = State {
        unit_mm: 1.0,
        coord: 0,
        rotation_deg: [0.0; 9],
        known: None,
        incremental: false,
        plane: 17,
        next_label: 100,
    };
    let mut out = String::new();
    let mut subs = String::new();
    let units = if rng.chance(0.3) { "G20" } else { "G21" };
    st.unit_mm = if units == "G20" { 25.4 } else { 1.0 };
    // Now and then a Fanuc-style safe-start line: G0 beside G80 (a traverse to where the tool
    // is).
    let safe_start = if rng.chance(0.2) { "G0 " } else { "" };
    let _ = writeln!(out, "{safe_start}G17 {units} G90 G94 G40 G49 G80");
    // The tool change comes before any rotation: after M6 the stand-alone rs274 reads the
    // position back from its canonical layer without the rotation (a quirk of that layer; a
    // machine reports its real position).
    if rng.chance(0.5) {
        let _ = writeln!(out, "T1 M6");
        let _ = writeln!(out, "G0 G43 H1 Z{}", n(st.len(rng.range(0.0, 30.0))));
    }
    // Work offsets, some rotated.
    for p in 1..=rng.below(4) + 1 {
        let p = if rng.chance(0.2) {
            6 + rng.below(3) + 1
        } else {
            p
        };
        let r = if rng.chance(0.35) {
            format!(" R{}", n(rng.range(-90.0, 90.0)))
        } else {
            String::new()
        };
        if !r.is_empty() {
            st.rotation_deg[p as usize - 1] = 1.0;
        }
        let _ = writeln!(
            out,
            "G10 L2 P{p} X{} Y{} Z{}{r}",
            n(st.len(rng.range(-200.0, 200.0))),
            n(st.len(rng.range(-200.0, 200.0))),
            n(st.len(rng.range(-50.0, 50.0)))
        );
    }
    let _ = writeln!(
        out,
        "F{} S{} M3",
        n(st.len(rng.range(100.0, 2000.0))),
        1000 + rng.below(9000)
    );
    let steps = 6 + rng.below(14);
    for _ in 0..steps {
        step(&mut rng, &mut st, &mut out, &mut subs);
    }
    let _ = writeln!(out, "G40 G80 G90 G49 G92.1 G17");
    let _ = writeln!(out, "M5 M9");
    let _ = writeln!(out, "M2");
    if !subs.is_empty() {
        // Subroutines are defined first, as LinuxCNC reads them before their calls.
        return subs + &out;
    }
    out
}

/// An absolute anchor move (the generator then knows where the tool is).
fn anchor(rng: &mut Rng, st: &mut State, out: &mut String) -> [f64; 3] {
    let p = [
        st.len(rng.range(-60.0, 60.0)),
        st.len(rng.range(-60.0, 60.0)),
        st.len(rng.range(-10.0, 30.0)),
    ]
    .map(round3);
    let g = if rng.chance(0.5) { "G0" } else { "G1" };
    let _ = writeln!(out, "G90 {g} X{} Y{} Z{}", n(p[0]), n(p[1]), n(p[2]));
    st.incremental = false;
    st.known = Some(p);
    p
}

/// Rotary words (degrees, never scaled by G20): each of A, B, C with probability `p`.
fn rotary(rng: &mut Rng, p: f64, span_deg: f64) -> String {
    let mut words = String::new();
    for axis in ['A', 'B', 'C'] {
        if rng.chance(p) {
            let _ = write!(words, " {axis}{}", n(rng.range(-span_deg, span_deg)));
        }
    }
    words
}

fn step(rng: &mut Rng, st: &mut State, out: &mut String, subs: &mut String) {
    match rng.below(18) {
        0..=2 => lines(rng, st, out),
        17 => probe(rng, st, out),
        3..=5 => arc(rng, st, out),
        6 => offsets(rng, st, out),
        7 => g92(rng, st, out),
        8 | 9 => cycle(rng, st, out),
        10 => compensated_contour(rng, st, out),
        11 => expressions(rng, st, out),
        12 => subroutine(rng, st, out, subs),
        13 => control_flow(rng, st, out),
        14 => units(rng, st, out),
        15 => tool_length(rng, st, out),
        _ => home(rng, st, out),
    }
}

/// A motion code, now and then with a G80 beside it (before or after) that gives way to it.
fn with_g80(rng: &mut Rng, g: &str) -> String {
    match rng.below(10) {
        0 => format!("G80 {g}"),
        1 => format!("{g} G80"),
        _ => g.to_string(),
    }
}

fn lines(rng: &mut Rng, st: &mut State, out: &mut String) {
    for _ in 0..1 + rng.below(4) {
        let g = *rng.pick(&["G0", "G1"]);
        let g = with_g80(rng, g);
        let inc = rng.chance(0.3);
        let dist = if inc { "G91" } else { "G90" };
        let mut words = String::new();
        for (axis, span) in [('X', 80.0), ('Y', 80.0), ('Z', 20.0)] {
            if rng.chance(0.6) {
                let v = if inc {
                    rng.range(-span / 4.0, span / 4.0)
                } else {
                    rng.range(-span, span)
                };
                let _ = write!(words, " {axis}{}", n(st.len(v)));
            }
        }
        if rng.chance(0.35) {
            words += &rotary(rng, 0.5, if inc { 45.0 } else { 360.0 });
        }
        let _ = writeln!(out, "{dist} {g}{words}");
        st.incremental = inc;
        st.known = None;
    }
}

fn plane_code(rng: &mut Rng, st: &State) -> u8 {
    if st.rotated() {
        17
    } else {
        *rng.pick(&[17, 17, 18, 19])
    }
}

/// An arc from an anchored point, in the centre (I/J/K) or radius (R) form, absolute or
/// incremental, maybe a helix, maybe with extra turns.
fn arc(rng: &mut Rng, st: &mut State, out: &mut String) {
    let start = anchor(rng, st, out);
    let plane = plane_code(rng, st);
    let (a1, a2, ax, l1, l2, la) = match plane {
        17 => (0, 1, 2, 'I', 'J', 'Z'),
        18 => (2, 0, 1, 'K', 'I', 'Y'),
        _ => (1, 2, 0, 'J', 'K', 'X'),
    };
    let letters = ['X', 'Y', 'Z'];
    let radius = st.len(rng.range(3.0, 40.0));
    let a0 = rng.range(0.0, std::f64::consts::TAU);
    let sweep = rng.range(0.3, 6.0);
    let cw = rng.chance(0.5);
    let centre = [start[a1] - radius * a0.cos(), start[a2] - radius * a0.sin()];
    let a_end = if cw { a0 - sweep } else { a0 + sweep };
    let end = [
        round3(centre[0] + radius * a_end.cos()),
        round3(centre[1] + radius * a_end.sin()),
    ];
    let helix = rng
        .chance(0.3)
        .then(|| round3(start[ax] + st.len(rng.range(-5.0, 5.0))));
    let inc = rng.chance(0.3);
    let g = if cw { "G2" } else { "G3" };
    let mut line = format!("G{plane} {} {g}", if inc { "G91" } else { "G90" });
    let coord = |v: f64, s: f64| if inc { n(v - s) } else { n(v) };
    let _ = write!(
        line,
        " {}{} {}{}",
        letters[a1],
        coord(end[0], start[a1]),
        letters[a2],
        coord(end[1], start[a2])
    );
    if let Some(h) = helix {
        let _ = write!(line, " {la}{}", coord(h, start[ax]));
    }
    if rng.chance(0.25) {
        line += &rotary(rng, 0.5, 180.0);
    }
    let short = (end[0] - start[a1]).hypot(end[1] - start[a2]) > st.len(0.5);
    if rng.chance(0.3) && short {
        // Radius form: negative R for the arc longer than half a turn.
        let r = if (sweep % std::f64::consts::TAU) > std::f64::consts::PI {
            -radius
        } else {
            radius
        };
        let _ = write!(line, " R{}", n(r));
    } else {
        let _ = write!(
            line,
            " {l1}{} {l2}{}",
            n(centre[0] - start[a1]),
            n(centre[1] - start[a2])
        );
        if rng.chance(0.15) {
            let _ = write!(line, " P{}", 2 + rng.below(2));
        }
    }
    let _ = writeln!(out, "{line}");
    let _ = writeln!(out, "G17 G90");
    st.plane = 17;
    st.incremental = false;
    st.known = None;
}

fn offsets(rng: &mut Rng, st: &mut State, out: &mut String) {
    if rng.chance(0.5) {
        let coords = [
            "G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3",
        ];
        let i = rng.below(9) as usize;
        let _ = writeln!(out, "{}", coords[i]);
        st.coord = i;
    } else {
        let l = *rng.pick(&[2, 20]);
        let p = rng.below(10);
        let mut line = format!("G10 L{l} P{p}");
        for (axis, span) in [('X', 100.0), ('Y', 100.0), ('Z', 30.0)] {
            if rng.chance(0.6) {
                let _ = write!(line, " {axis}{}", n(st.len(rng.range(-span, span))));
            }
        }
        if rng.chance(0.4) {
            line += &rotary(rng, 0.5, 90.0);
        }
        let index = if p == 0 { st.coord } else { p as usize - 1 };
        if index == st.coord && l == 2 {
            // Turning the active system: the G92 offset is cleared first. LinuxCNC turns the
            // current position without it (as if G92 were not rotated) while it places points
            // with it rotated; the twin keeps one frame, `Rz(R)·(p + g92) + g5x`.
            let _ = writeln!(out, "G92.1");
        }
        // R with L20 is refused by LinuxCNC: now and then, to check that we refuse it too.
        if rng.chance(if l == 2 { 0.3 } else { 0.02 }) {
            let _ = write!(line, " R{}", n(rng.range(-180.0, 180.0)));
            st.rotation_deg[index] = 1.0;
        } else if line.ends_with(&format!("P{p}")) {
            let _ = write!(line, " X0");
        }
        let _ = writeln!(out, "{line}");
    }
    st.known = None;
}

fn g92(rng: &mut Rng, st: &mut State, out: &mut String) {
    let line = match rng.below(5) {
        0 | 1 => format!(
            "G92 X{} Y{}{}",
            n(st.len(rng.range(-50.0, 50.0))),
            n(st.len(rng.range(-50.0, 50.0))),
            rotary(rng, 0.2, 90.0)
        ),
        2 => format!(
            "G52 X{} Z{}{}",
            n(st.len(rng.range(-20.0, 20.0))),
            n(st.len(rng.range(-5.0, 5.0))),
            rotary(rng, 0.2, 30.0)
        ),
        3 => rng.pick(&["G92.1", "G92.2"]).to_string(),
        _ => "G92.3".to_string(),
    };
    let _ = writeln!(out, "{line}");
    st.known = None;
}

fn cycle(rng: &mut Rng, st: &mut State, out: &mut String) {
    let start = anchor(rng, st, out);
    let code = *rng.pick(&["G81", "G82", "G83", "G73", "G85", "G89"]);
    let code = with_g80(rng, code);
    let ret = *rng.pick(&["G98", "G99"]);
    let r = round3(start[2] - st.len(rng.range(0.0, 8.0)));
    let z = round3(r - st.len(rng.range(1.0, 15.0)));
    let mut words = String::new();
    if code.contains("G82") || code.contains("G89") {
        let _ = write!(words, " P{}", n(rng.range(0.0, 1.0)));
    }
    if code.contains("G83") || code.contains("G73") {
        let _ = write!(words, " Q{}", n(st.len(rng.range(1.0, 5.0))));
    }
    let x = st.len(rng.range(-60.0, 60.0));
    let y = st.len(rng.range(-60.0, 60.0));
    if rng.chance(0.03) {
        // LinuxCNC refuses rotary words in a canned cycle block.
        let _ = write!(words, " C{}", n(rng.range(-90.0, 90.0)));
    }
    let _ = writeln!(
        out,
        "{ret} {code} X{} Y{} Z{} R{}{words}",
        n(x),
        n(y),
        n(z),
        n(r)
    );
    for _ in 0..rng.below(3) {
        let _ = writeln!(
            out,
            "X{} Y{}",
            n(st.len(rng.range(-60.0, 60.0))),
            n(st.len(rng.range(-60.0, 60.0)))
        );
    }
    if rng.chance(0.3) {
        // Incremental repeats along X.
        // In G91, R is measured from the initial level and Z from R.
        let _ = writeln!(
            out,
            "G91 X{} Y0 R{} Z{} L{}",
            n(st.len(rng.range(2.0, 10.0))),
            n(st.len(rng.range(-3.0, 0.0))),
            n(st.len(rng.range(-10.0, -1.0))),
            2 + rng.below(3)
        );
        let _ = writeln!(out, "G90");
    }
    let _ = writeln!(out, "G80");
    st.known = None;
}

/// A convex contour with cutter compensation: a rectangle (one side an outward arc), the
/// tool outside (G41 going clockwise, G42 counter-clockwise), entry and exit moves of 20 mm.
fn compensated_contour(rng: &mut Rng, st: &mut State, out: &mut String) {
    let _ = writeln!(out, "G17 G90");
    let (w, h) = (st.len(rng.range(30.0, 70.0)), st.len(rng.range(30.0, 70.0)));
    let (cx, cy) = (
        st.len(rng.range(-40.0, 40.0)),
        st.len(rng.range(-40.0, 40.0)),
    );
    let z = st.len(rng.range(-5.0, 5.0));
    let (x0, x1, y0, y1) = (
        round3(cx - w / 2.0),
        round3(cx + w / 2.0),
        round3(cy - h / 2.0),
        round3(cy + h / 2.0),
    );
    let away = st.len(20.0);
    let left = rng.chance(0.5);
    let _ = writeln!(out, "G0 X{} Y{} Z{}", n(x0 - away), n(y0 - away), n(z));
    let d = if rng.chance(0.5) {
        " D1".to_string()
    } else {
        String::new()
    };
    let bulge = round3(w.max(h) * 1.5);
    if left {
        // Clockwise: up the left side, right along the top (an arc), down, back left.
        let _ = writeln!(out, "G41{d} G1 X{} Y{}", n(x0), n(y0));
        let _ = writeln!(out, "Y{}", n(y1));
        if rng.chance(0.5) {
            let _ = writeln!(out, "G2 X{} Y{} R{}", n(x1), n(y1), n(bulge));
        } else {
            let _ = writeln!(out, "X{}", n(x1));
        }
        let _ = writeln!(out, "G1 Y{}", n(y0));
        let _ = writeln!(out, "X{}", n(x0));
        let _ = writeln!(out, "{} X{} Y{}", exit(rng), n(x0 - away), n(y0 - away));
    } else {
        // Counter-clockwise: right along the bottom, up, left along the top (an arc), down.
        let _ = writeln!(out, "G42{d} G1 X{} Y{}", n(x0), n(y0));
        let _ = writeln!(out, "X{}", n(x1));
        let _ = writeln!(out, "Y{}", n(y1));
        if rng.chance(0.5) {
            let _ = writeln!(out, "G3 X{} Y{} R{}", n(x0), n(y1), n(bulge));
        } else {
            let _ = writeln!(out, "X{}", n(x0));
        }
        let _ = writeln!(out, "G1 Y{}", n(y0));
        let _ = writeln!(out, "{} X{} Y{}", exit(rng), n(x0 - away), n(y0 - away));
    }
    st.known = None;
}

/// The codes of a compensated contour's exit move: a feed, or now and then a probe move
/// (which leaves from the compensated point as the exit move does).
fn exit(rng: &mut Rng) -> &'static str {
    if rng.chance(0.15) {
        rng.pick::<&str>(&["G40 G38.3", "G40 G38.5"])
    } else {
        "G40 G1"
    }
}

/// A probe move from an anchored point (the stand-alone `rs274` backs the tool off from the
/// target toward the point its canonical layer last moved to, which the anchor makes the
/// interpreter's), then a move that depends on where it left the tool or on #5061….
fn probe(rng: &mut Rng, st: &mut State, out: &mut String) {
    let start = anchor(rng, st, out);
    let code = *rng.pick(&["G38.2", "G38.3", "G38.4", "G38.5"]);
    let inc = rng.chance(0.3);
    let mut words = String::new();
    for (i, (axis, span)) in [('X', 30.0), ('Y', 30.0), ('Z', 15.0)]
        .into_iter()
        .enumerate()
    {
        if rng.chance(0.5) || (i == 2 && words.is_empty()) {
            let d = st.len(rng.range(-span, span));
            let v = if inc { d } else { start[i] + d };
            let _ = write!(words, " {axis}{}", n(v));
        }
    }
    if rng.chance(0.15) {
        words += &rotary(rng, 0.5, 90.0);
    }
    if rng.chance(0.05) {
        // To where the tool is: refused for G38.2/G38.4, a move of no length for .3/.5.
        words = if inc {
            " Z0".to_string()
        } else {
            format!(" Z{}", n(start[2]))
        };
    }
    let dist = if inc { "G91" } else { "G90" };
    let _ = writeln!(out, "{dist} {}{words}", with_g80(rng, code));
    match rng.below(4) {
        0 => {
            let _ = writeln!(
                out,
                "G91 G1 X{} Y{}",
                n(st.len(rng.range(-5.0, 5.0))),
                n(st.len(rng.range(-5.0, 5.0)))
            );
        }
        1 => {
            let _ = writeln!(out, "G90 G1 Y{}", n(st.len(rng.range(-40.0, 40.0))));
        }
        2 => {
            let _ = writeln!(
                out,
                "G90 G0 X[#5061 + {}] Y#5062 Z[#5063 + {}]",
                n(st.len(rng.range(-5.0, 5.0))),
                n(st.len(rng.range(0.0, 5.0)))
            );
        }
        _ => {
            let _ = writeln!(out, "#7 = #5070");
            let _ = writeln!(out, "G90 G0 Z[#5063 + #7 + {}]", n(st.len(2.0)));
        }
    }
    st.incremental = false;
    st.known = None;
}

/// A random expression of `depth` over numbers and parameters #1 and #<_g>, bounded values.
fn expr(rng: &mut Rng, depth: u32) -> String {
    if depth == 0 || rng.chance(0.3) {
        return match rng.below(4) {
            0 => "#1".to_string(),
            1 => "#<_g>".to_string(),
            _ => n(rng.range(-20.0, 20.0)),
        };
    }
    match rng.below(8) {
        0 => format!("[{} + {}]", expr(rng, depth - 1), expr(rng, depth - 1)),
        1 => format!("[{} - {}]", expr(rng, depth - 1), expr(rng, depth - 1)),
        2 => format!("[{} * {}]", expr(rng, depth - 1), n(rng.range(-2.0, 2.0))),
        3 => format!("[{} / {}]", expr(rng, depth - 1), n(rng.range(1.0, 4.0))),
        4 => format!(
            "[{} * SIN[{}]]",
            n(rng.range(1.0, 20.0)),
            expr(rng, depth - 1)
        ),
        5 => format!(
            "[{} * COS[{}]]",
            n(rng.range(1.0, 20.0)),
            expr(rng, depth - 1)
        ),
        6 => format!("ABS[{}]", expr(rng, depth - 1)),
        _ => format!(
            "[ATAN[{}]/[{}] / 10]",
            expr(rng, depth - 1),
            n(rng.range(1.0, 5.0))
        ),
    }
}

fn expressions(rng: &mut Rng, st: &mut State, out: &mut String) {
    let _ = writeln!(out, "#1 = {}", n(rng.range(-10.0, 10.0)));
    let _ = writeln!(out, "#<_g> = {}", expr(rng, 2));
    let _ = writeln!(out, "#1 = [{} MOD 30]", expr(rng, 2));
    let _ = writeln!(out, "G90 G1 X{} Y{}", expr(rng, 3), expr(rng, 2));
    let _ = writeln!(out, "G0 Z[{} + #1]", n(st.len(rng.range(0.0, 10.0))));
    st.incremental = false;
    st.known = None;
}

fn subroutine(rng: &mut Rng, st: &mut State, out: &mut String, subs: &mut String) {
    let label = st.next_label;
    st.next_label += 1;
    let named = rng.chance(0.5);
    let name = if named {
        format!("o<fuzz{label}>")
    } else {
        format!("o{label}")
    };
    let _ = writeln!(subs, "{name} sub");
    let _ = writeln!(subs, "#<local> = [#1 * 2]");
    let _ = writeln!(subs, "G91 G1 X#1 Y#2");
    let _ = writeln!(subs, "G90 G0 Z[#<local> + 1]");
    if rng.chance(0.5) {
        let inner = st.next_label;
        st.next_label += 1;
        let _ = writeln!(subs, "o{inner} if [#1 GT 0]");
        let _ = writeln!(subs, "  {name} return [#1]");
        let _ = writeln!(subs, "o{inner} endif");
    }
    let _ = writeln!(subs, "{name} endsub [#2]");
    for _ in 0..1 + rng.below(3) {
        let _ = writeln!(
            out,
            "{name} call [{}] [{}]",
            n(st.len(rng.range(-15.0, 15.0))),
            n(st.len(rng.range(-15.0, 15.0)))
        );
        let _ = writeln!(out, "G0 X[#<_value> * 2]");
    }
    st.incremental = false;
    st.known = None;
}

fn control_flow(rng: &mut Rng, st: &mut State, out: &mut String) {
    let label = st.next_label;
    st.next_label += 1;
    let count = 1 + rng.below(4);
    match rng.below(3) {
        0 => {
            let _ = writeln!(out, "#3 = 0");
            let _ = writeln!(out, "o{label} while [#3 LT {count}]");
            let _ = writeln!(
                out,
                "  G1 X[#3 * {}] Y{}",
                n(st.len(rng.range(1.0, 10.0))),
                n(st.len(rng.range(-30.0, 30.0)))
            );
            let _ = writeln!(out, "  #3 = [#3 + 1]");
            let _ = writeln!(out, "o{label} endwhile");
        }
        1 => {
            let _ = writeln!(out, "#4 = {}", n(rng.range(-5.0, 5.0)));
            let _ = writeln!(out, "o{label} if [#4 GT 1]");
            let _ = writeln!(out, "  G0 X{}", n(st.len(rng.range(-30.0, 30.0))));
            let _ = writeln!(out, "o{label} elseif [#4 LT -1]");
            let _ = writeln!(out, "  G0 Y{}", n(st.len(rng.range(-30.0, 30.0))));
            let _ = writeln!(out, "o{label} else");
            let _ = writeln!(out, "  G1 Z{}", n(st.len(rng.range(-5.0, 5.0))));
            let _ = writeln!(out, "o{label} endif");
        }
        _ => {
            let _ = writeln!(out, "o{label} repeat [{count}]");
            let _ = writeln!(
                out,
                "  G91 G1 X{} Y{}",
                n(st.len(rng.range(-5.0, 5.0))),
                n(st.len(rng.range(-5.0, 5.0)))
            );
            let _ = writeln!(out, "o{label} endrepeat");
            let _ = writeln!(out, "G90");
        }
    }
    st.incremental = false;
    st.known = None;
}

fn units(rng: &mut Rng, st: &mut State, out: &mut String) {
    // The tool length offset is cancelled first: LinuxCNC keeps an active one in the old
    // units across G20/G21, so that the next G43/G43.1/G49 shifts the position by a mix of
    // both (an inconsistency not reproduced here).
    let _ = writeln!(out, "G49");
    let _ = writeln!(out, "G90 G0 Z{}", n(st.len(rng.range(0.0, 30.0))));
    st.incremental = false;
    let inch = rng.chance(0.5);
    let _ = writeln!(out, "{}", if inch { "G20" } else { "G21" });
    st.unit_mm = if inch { 25.4 } else { 1.0 };
    let _ = writeln!(out, "F{}", n(st.len(rng.range(100.0, 2000.0))));
    st.known = None;
}

fn tool_length(rng: &mut Rng, st: &mut State, out: &mut String) {
    let never_rotated = st.rotation_deg.iter().all(|r| *r == 0.0);
    let line = match rng.below(5) {
        0 if never_rotated => format!("T{} M6", 1 + rng.below(4)),
        0 => format!("T{}", 1 + rng.below(4)),
        1 => format!("G43 H{}", 1 + rng.below(4)),
        2 => "G43".to_string(),
        3 => format!("G43.1 Z{}", n(st.len(rng.range(0.0, 100.0)))),
        _ => "G49".to_string(),
    };
    let _ = writeln!(out, "{line}");
    if !line.starts_with('T') {
        // A Z move right after a tool length change: LinuxCNC keeps the tool tip's program Z
        // (the spindle moves by the change at the next move, whatever its axes), the twin keeps
        // the spindle until the next Z move; both agree from the next Z word on.
        let _ = writeln!(out, "G90 G0 Z{}", n(st.len(rng.range(0.0, 30.0))));
        st.incremental = false;
    }
    st.known = None;
}

fn home(rng: &mut Rng, st: &mut State, out: &mut String) {
    let line = match rng.below(6) {
        0 => "G28.1".to_string(),
        1 => "G30.1".to_string(),
        2 => format!(
            "G28 Z{}{}",
            n(st.len(rng.range(0.0, 20.0))),
            rotary(rng, 0.3, 90.0)
        ),
        3 => format!("G28{}", rotary(rng, 0.7, 90.0)),
        4 => format!(
            "G53 G0 Z{}{}",
            n(st.len(rng.range(0.0, 20.0))),
            rotary(rng, 0.5, 180.0)
        ),
        _ => format!(
            "G30 X{} Y{}{}",
            n(st.len(rng.range(-20.0, 20.0))),
            n(st.len(rng.range(-20.0, 20.0))),
            rotary(rng, 0.3, 90.0)
        ),
    };
    let _ = writeln!(out, "G90 {line}");
    st.incremental = false;
    st.known = None;
}
