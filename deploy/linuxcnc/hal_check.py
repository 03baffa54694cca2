#!/usr/bin/python3
"""Drives a loaded vmc_comp instance through HAL and logs what it gives back, at full precision.

Run by halrun (loadusr -w) after the component is loaded and its thread started; LinuxCNC's
`hal` module exists for the distribution's /usr/bin/python3 only.

    hal_check.py STEPS_CSV OUT_CSV [--prefix vmc-comp.0] [--period-s S] [--timeout-s S]

STEPS_CSV, one step a line (no header):
    sample,T0,T1,...      new readings, then a rising edge of `sample`; waits for the sample
    position,X,Y,Z        new commanded position; waits two periods, then reads the outputs

OUT_CSV (header line): kind,clock_s,sample_clock_s,samples,state,iters,corr_x,corr_y,corr_z,
counts_x,counts_y,counts_z,thread_time (the servo thread's time of its latest period, CPU
clocks) — one line per step, floats as Python's repr (every bit), then a
line `tmax,F,T` with the function's and the thread's tmax (HAL's units: CPU clocks).
Exit status 0, 1 when a wait times out, 2 bad input.
"""

import sys
import time

import hal

PERIODS_TO_SETTLE = 3


def wait_for(cond, timeout_s):
    end = time.monotonic() + timeout_s
    while not cond():
        if time.monotonic() > end:
            return False
        time.sleep(0.0005)
    return True


def main(argv):
    args = list(argv)
    prefix, timeout_s, period_s = "vmc-comp.0", 5.0, 1e-3
    if "--period-s" in args:
        i = args.index("--period-s")
        period_s = float(args[i + 1])
        del args[i:i + 2]
    if "--prefix" in args:
        i = args.index("--prefix")
        prefix = args[i + 1]
        del args[i:i + 2]
    if "--timeout-s" in args:
        i = args.index("--timeout-s")
        timeout_s = float(args[i + 1])
        del args[i:i + 2]
    if len(args) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    steps_path, out_path = args
    comp = hal.component("vmc-hal-check")
    comp.ready()

    def get(pin):
        return hal.get_value(prefix + "." + pin)

    def settle():
        start = get("clock-s")
        return wait_for(lambda: get("clock-s") >= start + PERIODS_TO_SETTLE * period_s * 0.999,
                        timeout_s)

    # The first periods: the function has run (and shown the model's sensor count).
    if not settle():
        return timeout(0)
    n_sensors = int(get("sensors"))
    rows = []
    with open(steps_path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            fields = line.strip().split(",")
            if fields == [""]:
                continue
            kind, values = fields[0], fields[1:]
            try:
                nums = [float(v) for v in values]
            except ValueError:
                print(f"hal_check: {steps_path}:{number}: not numbers: {line.strip()}",
                      file=sys.stderr)
                return 2
            if kind == "sample" and len(nums) == n_sensors:
                for k, v in enumerate(nums):
                    hal.set_p(f"{prefix}.temp-{k:02d}", repr(v))
                before = get("samples")
                if not settle():
                    return timeout(number)
                hal.set_p(prefix + ".sample", "1")
                if not wait_for(lambda: get("samples") > before, timeout_s):
                    return timeout(number)
                hal.set_p(prefix + ".sample", "0")
            elif kind == "position" and len(nums) == 3:
                for axis, v in zip("xyz", nums):
                    hal.set_p(f"{prefix}.pos-cmd-{axis}", repr(v))
            else:
                print(f"hal_check: {steps_path}:{number}: expected sample with {n_sensors} "
                      f"readings or position with 3: {line.strip()}", file=sys.stderr)
                return 2
            if not settle():
                return timeout(number)
            rows.append([kind] + [repr(float(get(p))) if "clock" in p or "corr" in p
                                  else str(int(get(p))) for p in
                                  ("clock-s", "sample-clock-s", "samples", "state",
                                   "solve-iters", "corr-x", "corr-y", "corr-z",
                                   "counts-x", "counts-y", "counts-z")]
                        + [str(int(hal.get_value("servo.time")))])
    with open(out_path, "w", encoding="utf-8") as f:
        f.write("kind,clock_s,sample_clock_s,samples,state,iters,corr_x,corr_y,corr_z,"
                "counts_x,counts_y,counts_z,thread_time\n")
        for r in rows:
            f.write(",".join(r) + "\n")
        f.write("tmax,%d,%d\n" % (get("tmax"), hal.get_value("servo.tmax")))
    return 0


def timeout(number):
    print(f"hal_check: step {number}: the component did not answer in time", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
