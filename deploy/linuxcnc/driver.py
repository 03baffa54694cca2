#!/usr/bin/python3
"""Headless "display" of the vmc-twin LinuxCNC configuration: drives the machine without a GUI.

LinuxCNC starts the `[DISPLAY] DISPLAY` program with `-ini <file>` once the controller runs and
shuts itself down when that program exits, so this script is the whole session: it resets the
e-stop, switches the machine on, homes every joint in place, does what `[VMC_DRIVER] MODE`
says, switches the machine off and exits (0 on success, 1 with a message on stderr).

Modes (settings in `[VMC_DRIVER]`):

- `comp-check`: for stop i, every joint j goes to `POSITIONS_j[i]` (mm, machine coordinates)
  twice, first approaching from below (a move up from `APPROACH_MM` below), then from above;
  after each arrival it waits until motion and the compensation ramp have settled and reads
  `joint.N.pos-cmd`, `joint.N.motor-pos-cmd` and `joint.N.motor-offset` from HAL. One CSV row
  per joint and arrival, in order:
  `joint,direction,pos_cmd_mm,motor_pos_cmd_mm,target_mm,start_mm,motor_offset_mm`, direction
  `forward`/`reverse` (the final move's), or `none` when the approach start would leave the
  travel (the joint then stays at its target during the final move); start: where the final
  move began.
- `program`: runs the G-code file `PROGRAM` in AUTO mode and samples every joint's
  `pos-cmd` and `motor-pos-cmd` every `SAMPLE_S` seconds (wall clock; programs run in real
  time). CSV: `time_s,pos_cmd_<j>_mm,motor_pos_cmd_<j>_mm,...`. With `HALSAMPLER = FILE`
  the servo-rate log of a `sampler` component loaded by the HAL files (`sampler.0`, loaded
  with its `enable` pin at 0) is written too: `halsampler -t` copies its FIFO into FILE, the
  sampler is enabled just before the program starts and disabled when it has ended, and the
  session fails if the FIFO overflowed (`sampler.0.overruns`).

`CSV` is the output file; `TIMEOUT_S` bounds the session. Values are read with the `hal`
module as doubles (`halcmd getp` prints 7 significant digits only, 10 um at 500 mm).

It runs under the distribution's Python (`/usr/bin/python3`), which has LinuxCNC's `linuxcnc`
and `hal` modules.
"""

import signal
import subprocess
import sys
import time

import hal
import linuxcnc

JOINTS = 3
AXES = "XYZ"
POLL_S = 0.002
#: Consecutive identical HAL reads (POLL_S apart, with vel-cmd 0) that mean "settled": about
#: 60 servo periods, far longer than the compensation ramp of a few-um trim.
SETTLED_READS = 30


class DriverError(Exception):
    """What stopped the session."""


class Session:
    """The NML channels, the HAL component and the session's deadline."""

    def __init__(self, ini_path):
        self.ini = linuxcnc.ini(ini_path)
        self.deadline = time.monotonic() + float(self.setting("TIMEOUT_S", "300"))
        self.stat = linuxcnc.stat()
        self.cmd = linuxcnc.command()
        self.err = linuxcnc.error_channel()
        # A HAL component of our own makes the HAL shared memory readable with hal.get_value.
        self.comp = hal.component("vmc-driver")
        self.comp.ready()

    def setting(self, key, default=None):
        """A `[VMC_DRIVER]` setting (the default when absent; an error when no default)."""
        value = self.ini.find("VMC_DRIVER", key)
        if value is None:
            if default is None:
                raise DriverError(f"[VMC_DRIVER] {key} is missing")
            return default
        return value

    def remaining_s(self):
        left = self.deadline - time.monotonic()
        if left <= 0:
            raise DriverError("the session took longer than TIMEOUT_S")
        return left

    def check_errors(self):
        """Raises on an error message from the controller; prints other messages."""
        while True:
            msg = self.err.poll()
            if not msg:
                return
            kind, text = msg
            if kind in (linuxcnc.NML_ERROR, linuxcnc.OPERATOR_ERROR):
                raise DriverError(f"LinuxCNC: {text.strip()}")
            print(f"driver: LinuxCNC says: {text.strip()}", flush=True)

    def wait_for(self, what, done):
        """Polls the status until `done(stat)`, failing on an error or the deadline."""
        while True:
            self.stat.poll()
            self.check_errors()
            if done(self.stat):
                return
            if time.monotonic() > self.deadline:
                raise DriverError(f"timed out waiting for {what}")
            time.sleep(POLL_S)

    def command(self, what, send):
        """Sends a command and waits until LinuxCNC has carried it out."""
        send()
        status = self.cmd.wait_complete(self.remaining_s())
        self.check_errors()
        if status == -1:
            raise DriverError(f"{what}: no answer from LinuxCNC before the deadline")
        if status == linuxcnc.RCS_ERROR:
            raise DriverError(f"{what}: refused by LinuxCNC")

    def start(self):
        """E-stop reset, machine on, every joint homed in place, MDI mode."""
        c, ln = self.cmd, linuxcnc
        while True:
            try:
                self.stat.poll()
                break
            except ln.error:
                self.remaining_s()
                time.sleep(0.1)
        self.command("estop reset", lambda: c.state(ln.STATE_ESTOP_RESET))
        self.command("machine on", lambda: c.state(ln.STATE_ON))
        self.wait_for("machine on", lambda s: s.task_state == ln.STATE_ON)
        self.command("manual mode", lambda: c.mode(ln.MODE_MANUAL))
        self.command("joint mode", lambda: c.teleop_enable(0))
        self.command("home", lambda: c.home(-1))
        self.wait_for("homing", lambda s: all(s.homed[j] for j in range(JOINTS)))
        self.command("MDI mode", lambda: c.mode(ln.MODE_MDI))
        self.wait_for("MDI mode", lambda s: s.task_mode == ln.MODE_MDI)

    def stop(self):
        self.command("machine off", lambda: self.cmd.state(linuxcnc.STATE_OFF))

    def mdi(self, line):
        """Runs one MDI line and waits until the motion has ended."""
        self.command(line, lambda: self.cmd.mdi(line))
        self.wait_for(
            f"`{line}` to finish",
            lambda s: s.state == linuxcnc.RCS_DONE
            and s.interp_state == linuxcnc.INTERP_IDLE
            and s.queue == 0
            and s.inpos,
        )

    def read_joints(self):
        """(pos-cmd, motor-pos-cmd, motor-offset, vel-cmd) of every joint, mm and mm/s."""
        g = hal.get_value
        return tuple(
            (
                g(f"joint.{j}.pos-cmd"),
                g(f"joint.{j}.motor-pos-cmd"),
                g(f"joint.{j}.motor-offset"),
                g(f"joint.{j}.vel-cmd"),
            )
            for j in range(JOINTS)
        )

    def settled_joints(self):
        """The joints' values once vel-cmd is 0 and nothing has changed for SETTLED_READS
        reads: the compensation ramps in at half the joint's velocity and acceleration."""
        last, same = None, 0
        while same < SETTLED_READS:
            now = self.read_joints()
            moving = any(v[3] != 0.0 for v in now)
            same = same + 1 if (now == last and not moving) else 0
            last = now
            self.remaining_s()
            time.sleep(POLL_S)
        return last


def goto_line(targets_mm):
    """An MDI line moving every joint to its target in machine coordinates."""
    words = " ".join(f"{AXES[j]}{targets_mm[j]:.6f}" for j in range(JOINTS))
    return f"G90 G53 G0 {words}"


def comp_check(session):
    """Every stop approached from below and from above; one CSV row per joint and arrival."""
    positions = []
    for j in range(JOINTS):
        text = session.setting(f"POSITIONS_{j}")
        try:
            positions.append([float(v) for v in text.split()])
        except ValueError as e:
            raise DriverError(f"[VMC_DRIVER] POSITIONS_{j}: {e}") from e
    stops = len(positions[0])
    if stops == 0 or any(len(p) != stops for p in positions):
        raise DriverError("[VMC_DRIVER] POSITIONS_0..2 must list the same number (> 0)")
    approach_mm = float(session.setting("APPROACH_MM", "2.0"))
    limits = []
    for j in range(JOINTS):
        lo = float(session.ini.find(f"JOINT_{j}", "MIN_LIMIT"))
        hi = float(session.ini.find(f"JOINT_{j}", "MAX_LIMIT"))
        limits.append((lo, hi))
    rows = []
    for i in range(stops):
        target = [positions[j][i] for j in range(JOINTS)]
        for direction, sign in (("forward", -1.0), ("reverse", 1.0)):
            start = [
                min(max(target[j] + sign * approach_mm, limits[j][0]), limits[j][1])
                for j in range(JOINTS)
            ]
            session.mdi(goto_line(start))
            session.mdi(goto_line(target))
            values = session.settled_joints()
            for j in range(JOINTS):
                # "none": the joint could not approach from that side (its start would leave
                # the travel), so it did not move in the final move; kept for the record.
                moved = direction if start[j] != target[j] else "none"
                pos_cmd, motor_pos_cmd, motor_offset, _ = values[j]
                rows.append(
                    f"{j},{moved},{pos_cmd!r},{motor_pos_cmd!r},{target[j]!r},"
                    f"{start[j]!r},{motor_offset!r}"
                )
    header = "joint,direction,pos_cmd_mm,motor_pos_cmd_mm,target_mm,start_mm,motor_offset_mm"
    return header, rows


class ServoLog:
    """`halsampler -t` copying the FIFO of `sampler.0` into a file while the program runs."""

    def __init__(self, path):
        self.path = path
        self.proc = subprocess.Popen(["halsampler", "-t", "-c", "0", path])
        hal.set_p("sampler.0.enable", "1")

    def finish(self, session):
        """Stops sampling, waits until halsampler has emptied the FIFO, ends halsampler."""
        hal.set_p("sampler.0.enable", "0")
        while hal.get_value("sampler.0.curr-depth") > 0:
            session.remaining_s()
            time.sleep(0.05)
        # curr-depth 0: halsampler has taken the last sample; let it write it out.
        time.sleep(0.3)
        self.proc.send_signal(signal.SIGTERM)
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired as e:
            self.proc.kill()
            raise DriverError("halsampler did not stop") from e
        overruns = hal.get_value("sampler.0.overruns")
        if overruns:
            raise DriverError(f"the servo log lost samples: sampler.0.overruns = {overruns}")


def run_program(session):
    """Runs PROGRAM in AUTO mode, sampling the joints every SAMPLE_S seconds (and, with
    HALSAMPLER, every servo period through the HAL sampler)."""
    c, ln = session.cmd, linuxcnc
    program = session.setting("PROGRAM")
    sample_s = float(session.setting("SAMPLE_S", "0.1"))
    log_path = session.setting("HALSAMPLER", "")
    session.command("auto mode", lambda: c.mode(ln.MODE_AUTO))
    session.command("open program", lambda: c.program_open(program))
    servo_log = ServoLog(log_path) if log_path else None
    # Not `command`: wait_complete on AUTO_RUN would wait for the whole program.
    c.auto(ln.AUTO_RUN, 0)
    columns = []
    for j in range(JOINTS):
        columns += [f"pos_cmd_{j}_mm", f"motor_pos_cmd_{j}_mm"]
    rows = []
    t0 = time.monotonic()
    next_s, started = 0.0, False
    while True:
        session.stat.poll()
        session.check_errors()
        s = session.stat
        now_s = time.monotonic() - t0
        if now_s >= next_s:
            cells = [f"{now_s:.3f}"]
            for v in session.read_joints():
                cells += [repr(v[0]), repr(v[1])]
            rows.append(",".join(cells))
            next_s += sample_s
        idle = s.interp_state == ln.INTERP_IDLE and s.state == ln.RCS_DONE
        started = started or not idle
        # A program too short to be seen running ends the wait after a second.
        if idle and (started or now_s > 1.0):
            break
        session.remaining_s()
        time.sleep(POLL_S)
    if servo_log:
        servo_log.finish(session)
    return "time_s," + ",".join(columns), rows


def main(argv):
    if len(argv) < 2 or argv[0] != "-ini":
        print("driver: usage: driver.py -ini FILE (LinuxCNC starts it as its display)",
              file=sys.stderr)
        return 2
    t0 = time.monotonic()
    try:
        session = Session(argv[1])
        out = session.setting("CSV")
        mode = session.setting("MODE")
        session.start()
        print(f"driver: machine on and homed after {time.monotonic() - t0:.2f} s", flush=True)
        if mode == "comp-check":
            header, rows = comp_check(session)
        elif mode == "program":
            header, rows = run_program(session)
        else:
            raise DriverError(f"[VMC_DRIVER] MODE `{mode}`: expected comp-check or program")
        session.stop()
        with open(out, "w") as f:
            f.write(header + "\n" + "".join(r + "\n" for r in rows))
        print(f"driver: {len(rows)} rows written to {out} after {time.monotonic() - t0:.2f} s",
              flush=True)
        return 0
    except (DriverError, linuxcnc.error, OSError, ValueError) as e:
        print(f"driver: error: {e}", file=sys.stderr, flush=True)
        return 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
