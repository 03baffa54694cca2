#!/usr/bin/env python3
"""Checks that LinuxCNC applies an export folder's joint compensation tables as written.

Two steps around one headless LinuxCNC session (comp-check.sh runs prepare, the session
through run-headless.sh, and compare):

- `prepare`: a run folder (assemble.py) whose driver visits, per joint, eight positions of its
  travel: both ends, table points, midpoints between table points, points beyond a table
  that does not cover the travel, two irregular fractions; each approached from below and
  from above (the ends from inside only).
- `compare`: for every arrival of the driver's CSV, the measured trim
  `joint.N.motor-pos-cmd - joint.N.pos-cmd` against the table's value at `pos-cmd` in the
  direction of the last move (forward column after a positive move, reverse after a
  negative one; a type-0 file read as LinuxCNC stores it, nominal - value; a joint without a
  table must show 0). An arrival is `ok` within the tolerance (default 1e-6 mm); `held` when
  LinuxCNC's compensation ramp stopped short in its dead band (see `dead_band_mm`): the gap
  lies in that band and the measured trim is one the controller had applied before this
  arrival; otherwise a `mismatch`. Prints a table; exit status 1 on a mismatch, a pos-cmd
  that missed its target, a joint with a table lacking an arrival in either direction, or
  (with --strict) a held arrival.

Units: mm; differences printed in nm.
"""

import argparse
import csv
import sys
from dataclasses import dataclass
from pathlib import Path

from assemble import (
    AXES,
    DEFAULT_SERVO_PERIOD_NS,
    INI_NAME,
    InputError,
    assemble,
    fmt_mm,
    read_comp_tables,
    read_machine,
)

#: Positions visited per joint (every move sets all three joints, so all have the same count).
STOPS = 8
#: Fractions of the travel used when a table gives fewer distinct positions.
FILL_FRACTIONS = (0.382, 0.707, 0.1, 0.9, 0.55, 0.25, 0.8, 0.45, 0.65, 0.05)
CSV_NAME = "comp-check.csv"
DEFAULT_TOL_MM = 1e-6


def joint_positions(axis, table):
    """STOPS positions of one joint's travel (mm, 1 nm grid, ascending), the ones that test
    the table first: ends, table points, midpoints, beyond the table's ends."""
    lo, hi = axis.min_mm, axis.max_mm
    wanted = [lo, hi]
    if table:
        xs = table.nominal_mm
        inside = [x for x in xs if lo < x < hi]
        if inside:
            wanted += [inside[0], inside[len(inside) // 2]]
        m = len(xs) // 2
        wanted += [(xs[0] + xs[1]) / 2, (xs[m - 1] + xs[m]) / 2]
        if xs[0] > lo:
            wanted.append((lo + xs[0]) / 2)
        if xs[-1] < hi:
            wanted.append((xs[-1] + hi) / 2)
    wanted += [lo + f * (hi - lo) for f in FILL_FRACTIONS]
    chosen = []
    for x in wanted:
        x = round(x, 6)
        if lo <= x <= hi and x not in chosen:
            chosen.append(x)
        if len(chosen) == STOPS:
            break
    return sorted(chosen)


def prepare(machine_file, export_dir, run_dir, approach_mm, timeout_s,
            servo_period_ns=DEFAULT_SERVO_PERIOD_NS):
    """The run folder of a comp check; gives its INI file."""
    machine = read_machine(machine_file)
    tables = read_comp_tables(export_dir)
    settings = [("MODE", "comp-check"), ("CSV", str(Path(run_dir).resolve() / CSV_NAME))]
    for j, axis in enumerate(machine.axes):
        positions = joint_positions(axis, tables.get(j))
        settings.append((f"POSITIONS_{j}", " ".join(fmt_mm(x) for x in positions)))
    settings += [("APPROACH_MM", fmt_mm(approach_mm)), ("TIMEOUT_S", str(timeout_s))]
    ini, _ = assemble(machine, run_dir, export_dir, settings,
                      servo_period_ns=servo_period_ns)
    return ini


def read_ini(path):
    """The first value of every `KEY = VALUE` of a LinuxCNC INI file, by (section, key)."""
    values, section = {}, None
    try:
        text = Path(path).read_text()
    except OSError as e:
        raise InputError(f"{path}: cannot read the run's INI file: {e.strerror}") from e
    for raw in text.splitlines():
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        if line.startswith("[") and line.endswith("]"):
            section = line[1:-1]
            continue
        key, eq, value = line.partition("=")
        if eq:
            values.setdefault((section, key.strip()), value.strip())
    return values


@dataclass
class Arrival:
    """One row of the driver's CSV: a joint settled after a move (mm)."""

    line: int
    joint: int
    direction: str
    pos_cmd_mm: float
    motor_pos_cmd_mm: float
    target_mm: float
    start_mm: float


def read_arrivals(path):
    """The driver's CSV rows, in order."""
    rows = []
    try:
        with open(path, newline="") as f:
            for line, r in enumerate(csv.DictReader(f), start=2):
                try:
                    row = Arrival(line, int(r["joint"]), r["direction"],
                                  *(float(r[k]) for k in ("pos_cmd_mm", "motor_pos_cmd_mm",
                                                          "target_mm", "start_mm")))
                except (KeyError, TypeError, ValueError) as e:
                    raise InputError(f"{path}:{line}: not a comp-check row ({e})") from e
                if row.direction not in ("forward", "reverse", "none"):
                    raise InputError(f"{path}:{line}: direction `{row.direction}`")
                if not 0 <= row.joint < len(AXES):
                    raise InputError(f"{path}:{line}: joint {row.joint} is not 0 to 2")
                rows.append(row)
    except OSError as e:
        raise InputError(f"{path}: cannot read the measurements: {e.strerror}") from e
    return rows


def dead_band_mm(ini, joint):
    """LinuxCNC's compensation ramp (control.c, compute_screw_comp) moves the applied trim
    towards the table's at half the joint's acceleration a; from rest it jumps to the target
    when the gap is at most a*T^2/2 and accelerates when it is above a*T^2, and in between it
    stays where it is, for as long as the gap stays there. Gives that band (lo, hi], mm."""
    try:
        period_s = float(ini[("EMCMOT", "SERVO_PERIOD")]) * 1e-9
        acc_mm_s2 = 0.5 * float(ini[(f"JOINT_{joint}", "MAX_ACCELERATION")])
    except (KeyError, ValueError) as e:
        raise InputError(f"the run's INI file lacks {e}") from e
    return acc_mm_s2 * period_s**2 / 2, acc_mm_s2 * period_s**2


def classify(arrival, measured, table, prev_trim, prev_pos, band, tol_mm):
    """`ok` (the table's value), `held` (LinuxCNC's ramp stopped in its dead band at a value
    the applied trim really had before: the last settled one, or the table's at the approach
    start after the move there) or `mismatch`."""
    forward = arrival.direction == "forward"
    expected = table.trim_mm(arrival.pos_cmd_mm, forward) if table else 0.0
    gap = abs(measured - expected)
    if gap <= tol_mm:
        return "ok", expected
    earlier = [prev_trim]
    if table and arrival.start_mm != prev_pos:
        earlier.append(table.trim_mm(arrival.start_mm, arrival.start_mm > prev_pos))
    lo, hi = band
    eps = 1e-12  # the band's ends, as compared in double precision by the controller
    if lo - eps < gap <= hi + eps and any(abs(measured - v) <= tol_mm for v in earlier):
        return "held", expected
    return "mismatch", expected


def compare(run_dir, tol_mm, strict=False, out=sys.stdout):
    """Prints the comparison; gives (passed, counts by status, max |measured - table| of the
    arrivals at the table's value and of the held ones, mm)."""
    run_dir = Path(run_dir)
    tables = read_comp_tables(run_dir)
    ini = read_ini(run_dir / INI_NAME)
    arrivals = read_arrivals(run_dir / CSV_NAME)
    bands = [dead_band_mm(ini, j) for j in range(len(AXES))]
    prev_trim = [0.0] * len(AXES)  # homed in place: no compensation applied yet
    prev_pos = [float(ini.get((f"JOINT_{j}", "HOME"), "0")) for j in range(len(AXES))]
    print(f"{'joint':>5} {'dir':>7} {'pos_cmd_mm':>12} {'table_mm':>11} {'measured_mm':>11} "
          f"{'diff_nm':>9}", file=out)
    counts = {"ok": 0, "held": 0, "mismatch": 0}
    worst = {"ok": 0.0, "held": 0.0, "mismatch": 0.0}
    seen, missed = set(), False
    for a in arrivals:
        j = a.joint
        measured = a.motor_pos_cmd_mm - a.pos_cmd_mm
        if a.direction != "none":
            status, expected = classify(a, measured, tables.get(j), prev_trim[j], prev_pos[j],
                                        bands[j], tol_mm)
            counts[status] += 1
            worst[status] = max(worst[status], abs(measured - expected))
            seen.add((j, a.direction))
            flag = {"ok": "", "held": "  held", "mismatch": "  MISMATCH"}[status]
            if abs(a.pos_cmd_mm - a.target_mm) > tol_mm:
                missed, flag = True, flag + f"  pos-cmd missed the target {a.target_mm}"
            print(f"{j:>2} {AXES[j]:>2} {a.direction:>7} {a.pos_cmd_mm:12.6f} {expected:11.6f} "
                  f"{measured:11.6f} {(measured - expected) * 1e6:9.3f}{flag}", file=out)
        prev_trim[j], prev_pos[j] = measured, a.pos_cmd_mm
    uncovered = [(j, d) for j in sorted(tables) for d in ("forward", "reverse")
                 if (j, d) not in seen]
    for j, d in uncovered:
        print(f"joint {j}: no {d} arrival", file=out)
    passed = (counts["mismatch"] == 0 and not missed and not uncovered
              and not (strict and counts["held"]))
    print(f"{sum(counts.values())} arrivals: {counts['ok']} at the table's value (max "
          f"|measured - table| {worst['ok'] * 1e6:.3f} nm), {counts['held']} held by "
          f"LinuxCNC's compensation ramp (dead band; up to {worst['held'] * 1e6:.3f} nm of "
          f"the table not applied), {counts['mismatch']} mismatches; tolerance "
          f"{tol_mm * 1e6:g} nm: {'OK' if passed else 'FAILED'}", file=out)
    if counts["held"]:
        print("dead band of the ramp (lo, hi] in nm per joint: "
              + ", ".join(f"{AXES[j]} ({lo * 1e6:.3f}, {hi * 1e6:.3f}]"
                          for j, (lo, hi) in enumerate(bands)), file=out)
    return passed, counts, worst


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="step", required=True)
    pp = sub.add_parser("prepare", help="write the run folder")
    pp.add_argument("--machine", required=True)
    pp.add_argument("--tables", required=True, help="export folder (comp-tables.ini)")
    pp.add_argument("--run-dir", required=True)
    pp.add_argument("--approach-mm", type=float, default=2.0)
    pp.add_argument("--timeout-s", type=float, default=240.0)
    pp.add_argument("--servo-period-ns", type=int, default=DEFAULT_SERVO_PERIOD_NS)
    pc = sub.add_parser("compare", help="compare the run's measurements with its tables")
    pc.add_argument("--run-dir", required=True)
    pc.add_argument("--tol-mm", type=float, default=DEFAULT_TOL_MM)
    pc.add_argument("--strict", action="store_true",
                    help="an arrival held by LinuxCNC's ramp dead band fails the check too")
    args = p.parse_args(argv)
    try:
        if args.step == "prepare":
            if not args.approach_mm > 0:
                raise InputError("--approach-mm must be a positive number")
            print(prepare(args.machine, args.tables, args.run_dir, args.approach_mm,
                          args.timeout_s, args.servo_period_ns))
            return 0
        passed, _, _ = compare(args.run_dir, args.tol_mm, args.strict)
        return 0 if passed else 1
    except InputError as e:
        print(f"comp-check: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
