#!/usr/bin/env python3
"""The compensation end to end through LinuxCNC's motion controller, measured by the twin.

For every thermal state (a list of warm-up programs run on the twin) and every program:

1. the twin's own reference: `vmc-twin run PROGRAM --warmup ... --model MODEL --compensate`
   (its summary.json: RMS |E| before and after, the reduction) — and its samples.csv gives the
   sensor readings at the program's start state (the readings held at the first measurement
   point, a few seconds after the warm-up ends);
2. a headless LinuxCNC of the machine (assemble.py, run-headless.sh) with the HAL component
   `vmc_comp` (the trained model, loaded from the model file) in the servo thread between each
   joint's `motor-pos-cmd` and its simulated drive: the component reads the commanded position,
   the commanded joint speeds (`joint.N.vel-cmd` × 60, mm/min) and `spindle.0.speed-out`, and
   the drive is commanded `motor-pos-cmd + corr`; the sensor readings are those of step 1, set
   once with `setp` before the servo thread starts (a sample on the first period) and held
   for the program; the `sampler` component logs, every servo period, the commanded joint
   positions before the component, its corrections and the spindle speed (`halsampler -t`,
   columns n,x,y,z,cx,cy,cz,s);
3. the twin measures that log: `vmc-twin replay LOG --format halsampler --columns
   n,x,y,z,cx,cy,cz,s --period-ms 1 --warmup ...` (the same thermal state).

Prints one row per program and state (RMS |E| before/after and the reduction, through LinuxCNC
and by `run --compensate`, and the difference in percentage points) and writes them to
`OUT/end-to-end.csv`. Exit status 0 when every row meets the acceptance (reduction through
LinuxCNC >= --min-reduction and within --max-gap-points of run --compensate), 1 when a row
does not or a step failed, 2 on bad input, 77 when LinuxCNC or the component cannot run here.

Units: mm, mm/min, rpm, °C; figures in µm.
"""

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import assemble

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
#: The halsampler columns the HAL file logs, in pin order after the sample number.
LOG_COLUMNS = "n,x,y,z,cx,cy,cz,s"
DEFAULT_PROGRAMS = ["trajectories/diag_xy.ngc", "trajectories/diag_ppp.ngc"]
DEFAULT_STATES = [
    "2h-4000rpm=trajectories/warmup_2h_4000rpm.ngc",
    "4h-8000rpm=trajectories/warmup_4h_8000rpm.ngc",
]


class StepError(Exception):
    """A step that failed: a message naming it."""


def model_sensors(model_path):
    """The sensor names of a model file, in its input order."""
    try:
        doc = json.loads(Path(model_path).read_text())
    except (OSError, ValueError) as e:
        raise assemble.InputError(f"{model_path}: cannot read the model file: {e}") from e
    sensors = doc.get("sensors") if isinstance(doc, dict) else None
    if not isinstance(sensors, list) or not sensors:
        raise assemble.InputError(f"{model_path}: no `sensors` list in the model file")
    names = [s.get("name") if isinstance(s, dict) else s for s in sensors]
    if not all(isinstance(n, str) for n in names):
        raise assemble.InputError(f"{model_path}: a sensor without a name")
    return names


def start_readings(samples_csv, names):
    """The readings (°C) held at the first measurement point of a run's samples.csv."""
    with open(samples_csv, newline="") as f:
        rows = csv.DictReader(f)
        first = next(rows, None)
    if first is None:
        raise StepError(f"{samples_csv}: no measurement point")
    missing = [n for n in names if f"{n}_degc" not in first]
    if missing:
        raise StepError(f"{samples_csv}: no reading of {', '.join(missing)}")
    return [float(first[f"{n}_degc"]) for n in names]


def hal_text(model_in_run, readings):
    """The HAL file of the compensated machine: vmc_comp between motor-pos-cmd and the drive.

    vmc-sim.hal (loaded first) nets each joint's motor-pos-cmd to its motor-pos-fb (signal
    jN-motor): the motion controller sees its own command as the feedback, so the correction
    never comes back into the controller's command (no loop). The drive's position is
    `drive-<axis>.out` = motor-pos-cmd + corr."""
    lines = [
        "# The vmc_comp compensation component between each joint's motor-pos-cmd and its",
        "# simulated drive (written by end_to_end.py). Functions run in this order in the",
        "# servo thread after the motion controller: feeds, component, drive sums, sampler.",
        f"loadrt vmc_comp model={model_in_run}",
        "loadrt scale names=feed-x,feed-y,feed-z",
        "loadrt sum2 names=drive-x,drive-y,drive-z",
        "# The servo-rate log: x y z (commanded, before the component), cx cy cz (corrections),",
        "# s (commanded spindle speed); enabled by the driver while the program runs.",
        "loadrt sampler depth=16384 cfg=fffffff",
        "setp sampler.0.enable 0",
    ]
    for axis in "xyz":
        lines.append(f"addf feed-{axis} servo-thread")
    lines.append("addf vmc-comp.0 servo-thread")
    for axis in "xyz":
        lines.append(f"addf drive-{axis} servo-thread")
    lines.append("addf sampler.0 servo-thread")
    for j, axis in enumerate("xyz"):
        lines += [
            f"# {axis.upper()}: joint {j}; joint.{j}.vel-cmd is mm/s, the component takes mm/min",
            f"setp feed-{axis}.gain 60",
            f"net j{j}-vel joint.{j}.vel-cmd => feed-{axis}.in",
            f"net j{j}-feed feed-{axis}.out => vmc-comp.0.feed-{axis}",
            f"net j{j}-motor => vmc-comp.0.pos-cmd-{axis} drive-{axis}.in0 sampler.0.pin.{j}",
            f"net corr-{axis} vmc-comp.0.corr-{axis} => drive-{axis}.in1 sampler.0.pin.{j + 3}",
            f"net drive-{axis}-pos drive-{axis}.out",
        ]
    lines.append(
        "net spindle-rpm spindle.0.speed-out => vmc-comp.0.spindle-speed-rpm sampler.0.pin.6"
    )
    lines.append("# The sensor readings of the program's start state, held; one sample at start.")
    for k, value in enumerate(readings):
        lines.append(f"setp vmc-comp.0.temp-{k:02d} {value!r}")
    lines.append("setp vmc-comp.0.sample 1")
    return "\n".join(lines) + "\n"


def run_command(argv, log_path, what):
    """Runs a command with its output in a log file; StepError with the log's tail on failure."""
    with open(log_path, "w") as log:
        status = subprocess.run(argv, stdout=log, stderr=subprocess.STDOUT).returncode
    if status != 0:
        tail = Path(log_path).read_text().splitlines()[-15:]
        raise StepError(f"{what} failed (status {status}, {log_path}):\n  " + "\n  ".join(tail))


def summary(path):
    """RMS |E| before and after (µm) and the reduction of a summary.json."""
    doc = json.loads(Path(path).read_text())
    if doc.get("after") is None or doc.get("reduction") is None:
        raise StepError(f"{path}: no compensated figures")
    return doc["before"]["rms_um"][3], doc["after"]["rms_um"][3], doc["reduction"]


def twin_args(args, warmups):
    """The options that set the twin's machine, realisation and thermal state."""
    out = ["--seed", str(args.seed)]
    if args.machine:
        out += ["--machine", str(args.machine)]
    for w in warmups:
        out += ["--warmup", str(w)]
    return out


def linuxcnc_run(args, case_dir, program, readings):
    """One LinuxCNC session of the program with the component; gives the servo log's path."""
    run_dir = case_dir / "linuxcnc"
    hal_path = case_dir / "vmc-comp.hal"
    log_path = run_dir / "servo.log"
    hal_path.write_text(hal_text(run_dir / "model.json", readings))
    machine = assemble.read_machine(args.machine or REPO / "machines/vmc-reference.toml")
    settings = [
        ("MODE", "program"),
        ("CSV", str(run_dir / "program.csv")),
        ("SAMPLE_S", "1.0"),
        ("HALSAMPLER", str(log_path)),
        ("TIMEOUT_S", str(args.timeout - 30)),
    ]
    ini, _ = assemble.assemble(machine, run_dir, None, settings, program, hal_files=[hal_path])
    shutil.copyfile(args.model, run_dir / "model.json")
    (run_dir / "modules").mkdir()
    shutil.copyfile(args.module, run_dir / "modules/vmc_comp.so")
    # rtapi_app (a fallback user when root) reads the model file at loadrt.
    for p in [run_dir, *run_dir.rglob("*")]:
        p.chmod(p.stat().st_mode | 0o055 if p.is_dir() else p.stat().st_mode | 0o044)
    started = time.monotonic()
    run_command(
        [str(HERE / "run-headless.sh"), "--timeout", str(args.timeout), str(ini)],
        case_dir / "linuxcnc.log",
        f"the LinuxCNC session of {program.name}",
    )
    if not log_path.is_file() or log_path.stat().st_size == 0:
        raise StepError(f"{log_path}: the session wrote no servo log")
    return log_path, time.monotonic() - started


def one_case(args, state, warmups, program):
    """Reference, LinuxCNC session and replay of one program in one thermal state."""
    case_dir = args.out / state / program.stem
    case_dir.mkdir(parents=True)
    common = twin_args(args, warmups)
    twin_dir = case_dir / "twin"
    run_command(
        [args.vmc, "run", str(program), *common, "--model", str(args.model), "--compensate",
         *args.run_option, "--out", str(twin_dir)],
        case_dir / "twin.log",
        f"vmc-twin run {program.name} --compensate",
    )
    readings = start_readings(twin_dir / "samples.csv", model_sensors(args.model))
    log_path, session_s = linuxcnc_run(args, case_dir, program, readings)
    replay_dir = case_dir / "replay"
    replay = [args.vmc, "replay", str(log_path), "--format", "halsampler", "--columns",
              LOG_COLUMNS, "--period-ms", "1", *common, "--out", str(replay_dir)]
    if args.rrd and not any(args.out.rglob("*.rrd")):
        replay += ["--rrd", str(case_dir / "replay.rrd")]
    run_command(replay, case_dir / "replay.log", f"vmc-twin replay of {program.name}")
    lc = summary(replay_dir / "summary.json")
    tw = summary(twin_dir / "summary.json")
    return {
        "program": program.name,
        "state": state,
        "linuxcnc_before_um": lc[0],
        "linuxcnc_after_um": lc[1],
        "linuxcnc_reduction": lc[2],
        "twin_before_um": tw[0],
        "twin_after_um": tw[1],
        "twin_reduction": tw[2],
        "gap_points": 100.0 * (lc[2] - tw[2]),
        "session_s": session_s,
    }


def parse_state(text):
    """`NAME=WARMUP[+WARMUP...]` of --state."""
    name, eq, programs = text.partition("=")
    if not eq or not name or not programs:
        raise argparse.ArgumentTypeError(f"`{text}` is not NAME=WARMUP[+WARMUP...]")
    return name, [Path(p) for p in programs.split("+")]


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--model", required=True, type=Path, help="trained hybrid model (JSON)")
    p.add_argument("--out", required=True, type=Path, help="new folder for the runs")
    p.add_argument("--program", action="append", type=Path, help="program (repeatable)")
    p.add_argument("--state", action="append", type=parse_state,
                   help="thermal state NAME=WARMUP[+WARMUP...] (repeatable)")
    p.add_argument("--machine", type=Path, help="machine file (default: the reference)")
    p.add_argument("--seed", type=int, default=1, help="machine realisation (default 1)")
    p.add_argument("--vmc", default=str(REPO / "target/release/vmc-twin"), help="vmc-twin binary")
    p.add_argument("--module", type=Path, default=REPO / "target/linuxcnc/vmc_comp.so",
                   help="the HAL module (build-comp.sh)")
    p.add_argument("--run-option", action="append", default=[],
                   help="an extra option of the reference `run` (repeatable)")
    p.add_argument("--rrd", action="store_true", help="a Rerun recording of the first replay")
    p.add_argument("--timeout", type=int, default=600, help="per LinuxCNC session, s")
    p.add_argument("--min-reduction", type=float, default=0.80)
    p.add_argument("--max-gap-points", type=float, default=2.0)
    args = p.parse_args(argv)
    args.program = args.program or [REPO / p for p in DEFAULT_PROGRAMS]
    args.state = args.state or [parse_state(s) for s in DEFAULT_STATES]
    args.state = [(n, [w if w.is_absolute() else Path.cwd() / w for w in ws])
                  for n, ws in args.state]
    return args


def check_inputs(args):
    """Bad input (2) or not available here (77), before anything runs."""
    for f in [args.model, *args.program, *(w for _, ws in args.state for w in ws)]:
        if not f.is_file():
            raise assemble.InputError(f"{f}: no such file")
    if len({n for n, _ in args.state}) != len(args.state):
        raise assemble.InputError("two --state with the same name")
    if args.out.exists() and any(args.out.iterdir()):
        raise assemble.InputError(f"{args.out}: the output folder must be new or empty")
    if not Path(args.vmc).is_file():
        raise assemble.InputError(f"{args.vmc}: no vmc-twin binary (cargo build --release)")
    if not args.module.is_file():
        raise assemble.InputError(f"{args.module}: no HAL module (build-comp.sh)")


def report(rows, args):
    """The table, the CSV and whether every row meets the acceptance."""
    print(f"{'program':<14} {'state':<14} {'LinuxCNC: before':>16} {'after':>7} "
          f"{'reduction':>9}   {'run --compensate: before':>24} {'after':>7} {'reduction':>9}"
          f" {'gap':>7}  session")
    ok = True
    for r in rows:
        meets = (r["linuxcnc_reduction"] >= args.min_reduction
                 and abs(r["gap_points"]) <= args.max_gap_points)
        ok = ok and meets
        print(f"{r['program']:<14} {r['state']:<14} {r['linuxcnc_before_um']:>13.2f} µm "
              f"{r['linuxcnc_after_um']:>7.2f} {100 * r['linuxcnc_reduction']:>8.1f}%   "
              f"{r['twin_before_um']:>21.2f} µm {r['twin_after_um']:>7.2f} "
              f"{100 * r['twin_reduction']:>8.1f}% {r['gap_points']:>+5.1f} pt  "
              f"{r['session_s']:.0f} s {'ok' if meets else 'NOT MET'}")
    with open(args.out / "end-to-end.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"acceptance: reduction >= {100 * args.min_reduction:.0f} % through LinuxCNC and within "
          f"{args.max_gap_points:g} points of run --compensate: {'met' if ok else 'NOT met'}")
    return ok


def main(argv):
    args = parse_args(argv)
    try:
        check_inputs(args)
        args.out.mkdir(parents=True, exist_ok=True)
        args.out = args.out.resolve()
        args.model = args.model.resolve()
        rows = []
        for state, warmups in args.state:
            for program in args.program:
                print(f"end-to-end: {program.name} after {state} ...", flush=True)
                rows.append(one_case(args, state, warmups, program.resolve()))
        return 0 if report(rows, args) else 1
    except assemble.InputError as e:
        print(f"end-to-end: error: {e}", file=sys.stderr)
        return 2
    except StepError as e:
        print(f"end-to-end: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    os.environ.setdefault("PYTHONDONTWRITEBYTECODE", "1")
    sys.exit(main(sys.argv[1:]))
