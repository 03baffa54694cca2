#!/usr/bin/env python3
"""Run folders of the headless LinuxCNC configuration of a vmc-twin machine.

A run folder holds everything one LinuxCNC session reads and writes: the INI file made from
`vmc-machine.ini.in` (travel, velocities, accelerations and home of the machine file, the
`COMP_FILE`/`COMP_FILE_TYPE` lines of an export folder's `comp-tables.ini`, the driver's
settings), `vmc-sim.hal`, `driver.py`, the compensation files, an empty tool table and, after
the run, the driver's CSV. LinuxCNC reads compensation tables once, at start, so a run folder
is one thermal state.

Also the readers the comparison shares: the machine file's axes, `comp-tables.ini`, and the
compensation files read exactly as strictly as LinuxCNC needs them (its loader stops without a
word at the first line that is not three numbers, so any such line is refused here, with its
line number).

Units: mm, mm/s, mm/s^2 (the machine file's rapid rates in mm/min are divided by 60).

Usage:
    assemble.py --machine machines/vmc-reference.toml --run-dir RUN [--tables EXPORT_DIR]
                [--program FILE.ngc] [--hal FILE.hal ...] [--set KEY=VALUE ...]

e.g. a program run, sampled every 0.1 s:
    assemble.py --machine M --run-dir RUN --tables EXPORT --program warmup.ngc \
                --set MODE=program --set CSV=RUN/program.csv --set SAMPLE_S=0.1
    run-headless.sh RUN/vmc-machine.ini
"""

import argparse
import math
import os
import re
import shutil
import sys
import tomllib
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
TEMPLATE = HERE / "vmc-machine.ini.in"
AXES = "XYZ"
#: Most points LinuxCNC reads from one compensation file.
MAX_COMP_POINTS = 256
#: Largest |trim| accepted, mm: a larger one is a mistake (a type-0 file read as type 1).
MAX_TRIM_MM = 1.0
#: A number as LinuxCNC's fscanf("%lf") reads it and as a table writer prints it (no NaN,
#: infinities, hex floats or Python's digit separators).
NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
#: The INI file name inside a run folder.
INI_NAME = "vmc-machine.ini"
#: Servo thread period, ns (1 ms, the usual period of a LinuxCNC machine).
DEFAULT_SERVO_PERIOD_NS = 1_000_000


class InputError(Exception):
    """Bad input: a message naming the file (and line) that is wrong."""


@dataclass
class Axis:
    """One linear axis of the machine, driven by the joint of the same index."""

    name: str
    min_mm: float
    max_mm: float
    home_mm: float
    vel_mm_s: float
    acc_mm_s2: float


@dataclass
class Machine:
    """What the LinuxCNC configuration takes from a vmc-twin machine file."""

    name: str
    path: Path
    axes: list


@dataclass
class JointTable:
    """A joint's compensation file as LinuxCNC stores it: trims (mm) per nominal (mm)."""

    joint: int
    source: Path
    file_name: str
    file_type: int
    nominal_mm: list
    forward_trim_mm: list
    reverse_trim_mm: list

    def trim_mm(self, commanded_mm, forward):
        """The trim LinuxCNC applies at `commanded_mm` after a move in the given direction:
        linear between points, the end values beyond the ends."""
        xs = self.nominal_mm
        ys = self.forward_trim_mm if forward else self.reverse_trim_mm
        if commanded_mm <= xs[0]:
            return ys[0]
        if commanded_mm >= xs[-1]:
            return ys[-1]
        k = max(i for i in range(len(xs) - 1) if xs[i] <= commanded_mm)
        slope = (ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k])
        return ys[k] + slope * (commanded_mm - xs[k])


def read_machine(path):
    """The axes of a vmc-twin machine file (TOML): travel, home, rapid rate, acceleration."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text())
    except OSError as e:
        raise InputError(f"{path}: cannot read the machine file: {e.strerror}") from e
    except tomllib.TOMLDecodeError as e:
        raise InputError(f"{path}: not a TOML file: {e}") from e

    def triple(section, key):
        try:
            values = doc[section][key]
        except (KeyError, TypeError) as e:
            raise InputError(f"{path}: [{section}] {key} is missing") from e
        if (
            not isinstance(values, list)
            or len(values) != 3
            or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)
        ):
            raise InputError(f"{path}: [{section}] {key} must be three finite numbers")
        return [float(v) for v in values]

    lo, hi = triple("axes", "travel_min_mm"), triple("axes", "travel_max_mm")
    home = triple("axes", "home_mm")
    rapid = triple("motion", "rapid_mm_per_min")
    acc = triple("motion", "max_accel_mm_per_s2")
    axes = []
    for k, name in enumerate(AXES):
        if not lo[k] < hi[k]:
            raise InputError(f"{path}: axis {name}: travel_min_mm must be below travel_max_mm")
        if not lo[k] <= home[k] <= hi[k]:
            raise InputError(f"{path}: axis {name}: home_mm {home[k]} is outside the travel")
        if rapid[k] <= 0 or acc[k] <= 0:
            raise InputError(f"{path}: axis {name}: rapid rate and acceleration must be > 0")
        axes.append(Axis(name, lo[k], hi[k], home[k], rapid[k] / 60.0, acc[k]))
    name = doc.get("machine", {}).get("name", path.stem)
    return Machine(str(name), path, axes)


def parse_number(text, where):
    """A number of a compensation file, or an InputError naming `where`."""
    if not NUMBER.match(text):
        raise InputError(f"{where}: `{text}` is not a number")
    return float(text)


def read_comp_file(path, joint, file_type):
    """A compensation file as LinuxCNC loads it, refusing every line its loader would stop at.

    Type 1 holds trims, type 0 measured positions (the loader stores nominal - value)."""
    try:
        text = Path(path).read_text()
    except OSError as e:
        raise InputError(f"{path}: cannot read the compensation file: {e.strerror}") from e
    nominal, forward, reverse = [], [], []
    blank_at = None
    for i, raw in enumerate(text.splitlines(), start=1):
        where = f"{path}:{i}"
        fields = raw.split()
        if not fields:
            blank_at = blank_at or i
            continue
        if blank_at is not None:
            raise InputError(
                f"{path}:{blank_at}: empty line before more points "
                "(LinuxCNC would stop reading there)"
            )
        if len(fields) != 3:
            raise InputError(
                f"{where}: {len(fields)} fields, a point line has three "
                "(nominal forward reverse); LinuxCNC stops at any other line"
            )
        x, a, b = (parse_number(f, where) for f in fields)
        if nominal and x <= nominal[-1]:
            raise InputError(f"{where}: nominal {x} is not above the previous {nominal[-1]}")
        if len(nominal) == MAX_COMP_POINTS:
            raise InputError(f"{where}: more than {MAX_COMP_POINTS} points")
        fwd, rev = (a, b) if file_type == 1 else (x - a, x - b)
        for label, trim in (("forward", fwd), ("reverse", rev)):
            if abs(trim) > MAX_TRIM_MM:
                raise InputError(
                    f"{where}: {label} trim {trim:.6f} mm is beyond {MAX_TRIM_MM} mm "
                    f"(COMP_FILE_TYPE {file_type}: is the type right?)"
                )
        nominal.append(x)
        forward.append(fwd)
        reverse.append(rev)
    if len(nominal) < 2:
        raise InputError(f"{path}: {len(nominal)} points, a table needs at least 2")
    return JointTable(joint, Path(path), Path(path).name, file_type, nominal, forward, reverse)


def read_comp_tables(export_dir):
    """The joint tables named by `comp-tables.ini` of an export folder, by joint number."""
    export_dir = Path(export_dir)
    ini = export_dir / "comp-tables.ini"
    try:
        lines = ini.read_text().splitlines()
    except OSError as e:
        raise InputError(f"{ini}: cannot read: {e.strerror}") from e
    sections = {}
    joint = None
    for i, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line[0] in "#;":
            continue
        header = re.fullmatch(r"\[JOINT_(\d+)\]", line)
        if header:
            joint = int(header.group(1))
            if joint >= len(AXES):
                raise InputError(f"{ini}:{i}: joint {joint}: this machine has joints 0 to 2")
            if joint in sections:
                raise InputError(f"{ini}:{i}: a second [JOINT_{joint}] section")
            sections[joint] = {}
            continue
        if line.startswith("["):
            raise InputError(f"{ini}:{i}: `{line}`: only [JOINT_n] sections are expected")
        key, eq, value = line.partition("=")
        key, value = key.strip(), value.strip()
        if not eq or key not in ("COMP_FILE", "COMP_FILE_TYPE") or joint is None:
            raise InputError(
                f"{ini}:{i}: `{line}`: expected COMP_FILE = ... or COMP_FILE_TYPE = 0|1 "
                "inside a [JOINT_n] section"
            )
        if key in sections[joint]:
            raise InputError(f"{ini}:{i}: {key} given twice for joint {joint}")
        sections[joint][key] = (value, i)
    tables = {}
    for joint, keys in sorted(sections.items()):
        for key in ("COMP_FILE", "COMP_FILE_TYPE"):
            if key not in keys:
                raise InputError(f"{ini}: [JOINT_{joint}] has no {key}")
        type_text, type_line = keys["COMP_FILE_TYPE"]
        if type_text not in ("0", "1"):
            raise InputError(f"{ini}:{type_line}: COMP_FILE_TYPE `{type_text}` is not 0 or 1")
        path = export_dir / keys["COMP_FILE"][0]
        tables[joint] = read_comp_file(path, joint, int(type_text))
    if not tables:
        raise InputError(f"{ini}: no [JOINT_n] section")
    return tables


def fmt_mm(value):
    """A length as the INI file and G-code get it: 6 decimals (1 nm), no trailing zeros."""
    text = f"{value:.6f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def ini_text(machine, run_dir, tables, settings, servo_period_ns, hal_files=()):
    """The INI file of a run folder from the template; `hal_files` (names in the run folder)
    are loaded after vmc-sim.hal, in order."""
    values = {
        "EXTRA_HALFILES": "\n".join(f"HALFILE = {run_dir / name}" for name in hal_files),
        "SERVO_PERIOD_NS": str(servo_period_ns),
        "MACHINE": machine.name,
        "MACHINE_FILE": str(machine.path),
        "RUN_DIR": str(run_dir),
        "TRAJ_VEL_MM_S": fmt_mm(max(a.vel_mm_s for a in machine.axes)),
        "TRAJ_ACC_MM_S2": fmt_mm(max(a.acc_mm_s2 for a in machine.axes)),
    }
    for a in machine.axes:
        values[f"{a.name}_MIN_MM"] = fmt_mm(a.min_mm)
        values[f"{a.name}_MAX_MM"] = fmt_mm(a.max_mm)
        values[f"{a.name}_HOME_MM"] = fmt_mm(a.home_mm)
        values[f"{a.name}_VEL_MM_S"] = fmt_mm(a.vel_mm_s)
        values[f"{a.name}_ACC_MM_S2"] = fmt_mm(a.acc_mm_s2)
    for joint in range(len(AXES)):
        t = tables.get(joint)
        values[f"JOINT_{joint}_COMP"] = (
            f"COMP_FILE = {run_dir / t.file_name}\nCOMP_FILE_TYPE = {t.file_type}"
            if t
            else "# no compensation table for this joint"
        )
    values["DRIVER_SETTINGS"] = "\n".join(f"{k} = {v}" for k, v in settings)

    def fill(match):
        key = match.group(1)
        if key not in values:
            raise InputError(f"{TEMPLATE}: unknown placeholder @{key}@")
        return values[key]

    return re.sub(r"@([A-Z0-9_]+)@", fill, TEMPLATE.read_text())


def assemble(machine, run_dir, export_dir, settings, program=None,
             servo_period_ns=DEFAULT_SERVO_PERIOD_NS, hal_files=()):
    """Writes a run folder; gives its INI file and the joint tables it loads.

    A G-code `program` is copied into the folder and named by the PROGRAM setting: the
    session may see nothing outside its run folder (run-headless.sh gives it a private /tmp).
    `hal_files` are copied in too and loaded after vmc-sim.hal (e.g. a compensation component
    between the joints' motor-pos-cmd and the drives)."""
    run_dir = Path(run_dir).resolve()
    settings = list(settings)
    tables = read_comp_tables(export_dir) if export_dir else {}
    for key, value in settings:
        if not re.fullmatch(r"[A-Z][A-Z0-9_]*", key) or "\n" in value:
            raise InputError(f"driver setting `{key}`: KEY must be upper case, one line")
    run_dir.mkdir(parents=True, exist_ok=True)
    if any(run_dir.iterdir()):
        raise InputError(f"{run_dir}: the run folder must be new or empty")
    for t in tables.values():
        if (run_dir / t.file_name).exists():
            raise InputError(f"{t.file_name}: two joints name the same file")
        shutil.copyfile(t.source, run_dir / t.file_name)
    if export_dir:
        shutil.copyfile(Path(export_dir) / "comp-tables.ini", run_dir / "comp-tables.ini")
    shutil.copyfile(HERE / "vmc-sim.hal", run_dir / "vmc-sim.hal")
    shutil.copyfile(HERE / "driver.py", run_dir / "driver.py")
    os.chmod(run_dir / "driver.py", 0o755)
    if program:
        copy = run_dir / Path(program).name
        if copy.exists():
            raise InputError(f"{program}: its name is taken in the run folder")
        try:
            shutil.copyfile(program, copy)
        except OSError as e:
            raise InputError(f"{program}: cannot read the program: {e.strerror}") from e
        settings = [(k, v) for k, v in settings if k != "PROGRAM"] + [("PROGRAM", str(copy))]
    hal_names = []
    for hal_file in hal_files:
        name = Path(hal_file).name
        if name in ("vmc-sim.hal", INI_NAME) or (run_dir / name).exists():
            raise InputError(f"{hal_file}: its name is taken in the run folder")
        try:
            shutil.copyfile(hal_file, run_dir / name)
        except OSError as e:
            raise InputError(f"{hal_file}: cannot read the HAL file: {e.strerror}") from e
        hal_names.append(name)
    (run_dir / "tool.tbl").write_text("")
    # The interpreter's parameter file: LinuxCNC complains at shutdown when there is none.
    (run_dir / "vmc.var").write_text("")
    ini = run_dir / INI_NAME
    if not 100_000 <= servo_period_ns <= 10_000_000:
        raise InputError(f"servo period {servo_period_ns} ns: expected 100000 to 10000000")
    ini.write_text(ini_text(machine, run_dir, tables, settings, servo_period_ns, hal_names))
    return ini, tables


def parse_setting(text):
    """`KEY=VALUE` of --set."""
    key, eq, value = text.partition("=")
    if not eq:
        raise argparse.ArgumentTypeError(f"`{text}` is not KEY=VALUE")
    return key.strip(), value.strip()


def main(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--machine", required=True, help="vmc-twin machine file (TOML)")
    p.add_argument("--run-dir", required=True, help="new or empty folder for the run")
    p.add_argument("--tables", help="export folder with comp-tables.ini and joint*.comp")
    p.add_argument("--program", help="G-code file to copy in and run (MODE = program)")
    p.add_argument("--hal", action="append", default=[], metavar="FILE",
                   help="a HAL file to copy in and load after vmc-sim.hal (repeatable)")
    p.add_argument("--servo-period-ns", type=int, default=DEFAULT_SERVO_PERIOD_NS)
    p.add_argument("--set", action="append", default=[], type=parse_setting,
                   metavar="KEY=VALUE", help="a [VMC_DRIVER] setting (repeatable)")
    args = p.parse_args(argv)
    try:
        machine = read_machine(args.machine)
        ini, _ = assemble(machine, args.run_dir, args.tables, args.set, args.program,
                          args.servo_period_ns, args.hal)
    except InputError as e:
        print(f"assemble: error: {e}", file=sys.stderr)
        return 1
    print(ini)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
