#!/usr/bin/env python3
"""Writes the G-code programs of trajectories/ (run from the repository root or this folder).

Face diagonals follow the reference study: XY, YZ, XZ measured every 67.10 / 54.10 / 75 mm
(X steps 60 mm, Y steps 30 mm, Z steps 45 mm). Body diagonals follow ISO 230-6 over the working
volume. At each measurement point the machine dwells as a laser reading would (G4).
Machine coordinates of the reference machine: X 0…560, Y 0…400, Z −450…0 mm (Z up).
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
DWELL_S = 4
FEED = 2000


def header(lines, title, what):
    lines.append("%")
    lines.append(f"( {title} )")
    for w in what:
        lines.append(f"( {w} )")
    lines.append("G21 G17 G90 G54")


def diagonal(name, title, what, start, step, n_steps):
    lines = []
    header(lines, title, what)
    lines.append(f"G0 X{start[0]:.3f} Y{start[1]:.3f} Z{start[2]:.3f}")
    lines.append(f"G4 P{DWELL_S} (point 0)")
    for k in range(1, n_steps + 1):
        p = [start[i] + k * step[i] for i in range(3)]
        lines.append(f"G1 X{p[0]:.3f} Y{p[1]:.3f} Z{p[2]:.3f} F{FEED}")
        lines.append(f"G4 P{DWELL_S} (point {k})")
    lines.append("M30")
    lines.append("%")
    with open(os.path.join(HERE, name), "w") as f:
        f.write("\n".join(lines) + "\n")


def face_diagonals():
    diagonal("diag_xy.ngc", "XY face diagonal test - reference study",
             ["Measured every 67.10 mm along the diagonal: X steps 60 mm, Y steps 30 mm, Z fixed at -225.",
              f"10 points, dwell {DWELL_S} s at each point as a laser reading would."],
             [10.0, 60.0, -225.0], [60.0, 30.0, 0.0], 9)
    diagonal("diag_yz.ngc", "YZ face diagonal test - reference study",
             ["Measured every 54.10 mm along the diagonal: Y steps 30 mm, Z steps 45 mm, X fixed at 280.",
              f"10 points, dwell {DWELL_S} s at each point as a laser reading would."],
             [280.0, 65.0, -430.0], [0.0, 30.0, 45.0], 9)
    diagonal("diag_xz.ngc", "XZ face diagonal test - reference study",
             ["Measured every 75.00 mm along the diagonal: X steps 60 mm, Z steps 45 mm, Y fixed at 200.",
              f"10 points, dwell {DWELL_S} s at each point as a laser reading would."],
             [10.0, 200.0, -430.0], [60.0, 0.0, 45.0], 9)


def body_diagonals():
    lo = [20.0, 20.0, -430.0]
    hi = [540.0, 380.0, -30.0]
    n = 10
    for code in ["PPP", "NPP", "PNP", "PPN"]:
        start = [lo[i] if code[i] == "P" else hi[i] for i in range(3)]
        end = [hi[i] if code[i] == "P" else lo[i] for i in range(3)]
        step = [(end[i] - start[i]) / n for i in range(3)]
        length = sum((end[i] - start[i]) ** 2 for i in range(3)) ** 0.5
        diagonal(f"diag_{code.lower()}.ngc", f"Body diagonal {code} - ISO 230-6",
                 [f"From X{start[0]:.0f} Y{start[1]:.0f} Z{start[2]:.0f} to X{end[0]:.0f} Y{end[1]:.0f} Z{end[2]:.0f}:"
                  f" {length:.1f} mm, measured every {length / n:.2f} mm.",
                  "Direction code: P = the axis increases along the diagonal, N = it decreases.",
                  f"{n + 1} points, dwell {DWELL_S} s at each point as a laser reading would."],
                 start, step, n)


def warmup(name, title, rpm, hours, feed):
    """Spindle at `rpm` with the axes moving over most of their travel, in 10-minute blocks."""
    lines = []
    header(lines, title, [f"{hours} h of spindle at {rpm} rpm with axis motion at F{feed} over most of the travel,",
                          "in 10-minute blocks of about 5 min of motion and 5 min of spindle-only dwell.",
                          "Thermal loading program: run before a diagonal test with --warmup."])
    lines.append("G0 X20 Y20 Z-100")
    lines.append(f"S{rpm} M3")
    # One motion loop: a rectangle in XY with Z strokes, ~4 passes of 2×(520+360) mm + Z moves.
    loop = [("X540", "Y20", "Z-100"), ("X540", "Y380", "Z-300"), ("X20", "Y380", "Z-100"), ("X20", "Y20", "Z-300")]
    loop_len = 2 * (520 + 360)
    loop_s = loop_len / feed * 60.0
    loops_per_block = max(1, int(300 / loop_s))
    blocks = int(hours * 6)
    for b in range(blocks):
        lines.append(f"( block {b + 1} of {blocks} )")
        for _ in range(loops_per_block):
            for (x, y, z) in loop:
                lines.append(f"G1 {x} {y} {z} F{feed}")
        lines.append(f"G4 P{600 - loops_per_block * loop_s:.0f}")
    lines.append("M5")
    lines.append("G0 X280 Y200 Z-100")
    lines.append("M30")
    lines.append("%")
    with open(os.path.join(HERE, name), "w") as f:
        f.write("\n".join(lines) + "\n")


def cooldown(name, hours):
    lines = []
    header(lines, f"Cool-down: {hours} h at rest", [f"Spindle off, axes parked, {hours} h dwell: the machine cools towards ambient."])
    lines.append("M5")
    lines.append("G0 X280 Y200 Z-50")
    lines.append(f"G4 P{hours * 3600}")
    lines.append("M30")
    lines.append("%")
    with open(os.path.join(HERE, name), "w") as f:
        f.write("\n".join(lines) + "\n")


def pocket_chatter():
    """The chatter check's example (vmc-twin chatter, stock pocket_chatter.stock.toml): a pocket
    whose first pass is a full slot and whose side steps meet the end wall ahead (unstable at
    this depth and speed with the default tool), between climb passes 2 mm wide (stable)."""
    lines = [
        "(A 56 x 40 mm pocket, 1 mm deep, in a 100 x 80 x 20 mm block whose top is Z0:)",
        "(pocket_chatter.stock.toml. Cleared with the machine's default tool, D16 mm, 2 teeth,)",
        "(at 10000 rpm by one-way climb passes along -X, 2 mm apart: a full slot first, then)",
        "(passes at a_e/D = 2/16, each entered by a 2 mm sideways step at the pocket's end.)",
        "G21 G90 G17 G94",
        "G0 Z5",
        "G0 X72 Y28",
        "M3 S10000",
        "G1 Z-1 F300 (plunge)",
        "G1 X28 F800 (first pass: a full slot)",
    ]
    for y in range(28, 52, 2):
        lines += ["G0 Z5", f"G0 X72 Y{y}", "G0 Z-1",
                  f"G1 Y{y + 2} F400 (step over at the end wall)",
                  "G1 X28 F800 (climb pass, 2 mm wide)"]
    lines += ["G0 Z5", "M5", "M2"]
    with open(os.path.join(HERE, "pocket_chatter.ngc"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    face_diagonals()
    body_diagonals()
    warmup("warmup_4h_8000rpm.ngc", "Warm-up: 4 h at 8000 rpm with axis motion", 8000, 4, 4000)
    warmup("warmup_2h_4000rpm.ngc", "Warm-up: 2 h at 4000 rpm with axis motion", 4000, 2, 3000)
    cooldown("cooldown_4h.ngc", 4)
    pocket_chatter()
