"""Unit tests of the end-to-end script's pieces that need no LinuxCNC: the start readings, the
HAL wiring it writes, the states it parses and the run folder it assembles.

    python3 -m unittest discover -s deploy/linuxcnc -p 'test_*.py'
"""

import argparse
import tempfile
import unittest
from pathlib import Path

from assemble import InputError, assemble, read_machine
from end_to_end import StepError, hal_text, parse_state, start_readings

REPO = Path(__file__).resolve().parents[2]


class StartReadings(unittest.TestCase):
    def test_the_first_rows_readings_are_taken_in_the_models_order(self):
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "samples.csv"
            path.write_text("time_s,A_degc,B_degc\n1.0,20.5,21.25\n2.0,30,31\n")
            self.assertEqual(start_readings(path, ["B", "A"]), [21.25, 20.5])

    def test_a_sensor_the_run_did_not_log_is_named(self):
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / "samples.csv"
            path.write_text("time_s,A_degc\n1.0,20.5\n")
            with self.assertRaises(StepError) as e:
                start_readings(path, ["A", "Amb"])
            self.assertIn("no reading of Amb", str(e.exception))


class HalText(unittest.TestCase):
    def setUp(self):
        self.text = hal_text(Path("/run/model.json"), [20.0, 21.5])
        self.lines = self.text.splitlines()

    def test_the_sampler_logs_commands_then_corrections_then_the_spindle(self):
        pins = {}
        for line in self.lines:
            for word in line.split():
                if word.startswith("sampler.0.pin."):
                    pins[int(word.rsplit(".", 1)[1])] = line.split()[1]
        self.assertEqual(
            [pins[k] for k in range(7)],
            ["j0-motor", "j1-motor", "j2-motor", "corr-x", "corr-y", "corr-z", "spindle-rpm"],
        )

    def test_the_drive_gets_the_command_plus_the_correction_and_the_component_the_command(self):
        self.assertIn("net j0-motor => vmc-comp.0.pos-cmd-x drive-x.in0 sampler.0.pin.0",
                      self.lines)
        self.assertIn("net corr-x vmc-comp.0.corr-x => drive-x.in1 sampler.0.pin.3", self.lines)

    def test_the_component_runs_after_the_feeds_and_before_the_drives_and_the_sampler(self):
        order = [l.split()[1] for l in self.lines if l.startswith("addf ")]
        self.assertLess(order.index("feed-z"), order.index("vmc-comp.0"))
        self.assertLess(order.index("vmc-comp.0"), order.index("drive-x"))
        self.assertEqual(order[-1], "sampler.0")

    def test_the_readings_are_set_before_the_sample_bit(self):
        self.assertIn("setp vmc-comp.0.temp-01 21.5", self.lines)
        self.assertGreater(self.lines.index("setp vmc-comp.0.sample 1"),
                           self.lines.index("setp vmc-comp.0.temp-01 21.5"))


class States(unittest.TestCase):
    def test_a_state_names_its_warm_ups_in_order(self):
        name, warmups = parse_state("hot=a.ngc+b.ngc")
        self.assertEqual((name, warmups), ("hot", [Path("a.ngc"), Path("b.ngc")]))

    def test_a_state_without_a_name_or_warm_up_is_refused(self):
        for bad in ("a.ngc", "=a.ngc", "hot="):
            with self.assertRaises(argparse.ArgumentTypeError):
                parse_state(bad)


class Assemble(unittest.TestCase):
    def test_a_hal_file_is_copied_in_and_loaded_after_the_simulated_drives(self):
        machine = read_machine(REPO / "machines/vmc-reference.toml")
        with tempfile.TemporaryDirectory() as d:
            hal = Path(d) / "extra.hal"
            hal.write_text("# nothing\n")
            ini, _ = assemble(machine, Path(d) / "run", None, [("MODE", "program")],
                              hal_files=[hal])
            text = ini.read_text()
            self.assertTrue((Path(d) / "run/extra.hal").is_file())
            self.assertLess(text.index("vmc-sim.hal"), text.index("extra.hal"))

    def test_a_hal_file_named_like_the_simulated_drives_is_refused(self):
        machine = read_machine(REPO / "machines/vmc-reference.toml")
        with tempfile.TemporaryDirectory() as d:
            hal = Path(d) / "vmc-sim.hal"
            hal.write_text("# nothing\n")
            with self.assertRaises(InputError):
                assemble(machine, Path(d) / "run", None, [], hal_files=[hal])


if __name__ == "__main__":
    unittest.main()
