"""Unit tests of the comp check's readers and classification (no LinuxCNC needed).

    python3 -m unittest discover -s deploy/linuxcnc -p 'test_*.py'
"""

import tempfile
import unittest
from pathlib import Path

from assemble import InputError, JointTable, read_comp_file, read_comp_tables, read_machine
from comp_check import Arrival, classify, dead_band_mm, joint_positions

REPO = Path(__file__).resolve().parents[2]


def write(folder, name, text):
    path = Path(folder) / name
    path.write_text(text)
    return path


def table(nominal, forward, reverse):
    return JointTable(0, Path("t.comp"), "t.comp", 1, nominal, forward, reverse)


class ReadCompFile(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()

    def tearDown(self):
        self.dir.cleanup()

    def refused(self, text, fragment):
        path = write(self.dir.name, "j.comp", text)
        with self.assertRaises(InputError) as e:
            read_comp_file(path, 0, 1)
        self.assertIn(fragment, str(e.exception))

    def test_a_header_line_is_refused_with_its_line_number(self):
        self.refused("# nominal forward reverse\n0 0 0\n1 0 0\n", "j.comp:1: 4 fields")

    def test_an_empty_line_before_more_points_is_refused(self):
        self.refused("0 0 0\n\n1 0 0\n", "j.comp:2: empty line before more points")

    def test_a_fourth_column_is_refused(self):
        self.refused("0 0 0 0\n1 0 0\n", "j.comp:1: 4 fields")

    def test_words_nan_and_python_digit_separators_are_not_numbers(self):
        for bad in ("nan", "inf", "1_0", "0x1"):
            self.refused(f"0 0 0\n1 {bad} 0\n", f"j.comp:2: `{bad}` is not a number")

    def test_nominal_positions_must_ascend(self):
        self.refused("0 0 0\n0 0 0\n", "j.comp:2: nominal 0.0 is not above the previous 0.0")

    def test_more_than_256_points_are_refused(self):
        text = "".join(f"{i} 0 0\n" for i in range(257))
        self.refused(text, "j.comp:257: more than 256 points")

    def test_a_type_0_file_read_as_type_1_is_refused_as_a_trim_beyond_1_mm(self):
        self.refused("0 0.001 0\n100 100.002 99.999\n", "COMP_FILE_TYPE 1: is the type right?")

    def test_trailing_empty_lines_are_accepted(self):
        path = write(self.dir.name, "j.comp", "0 0.001 -0.002\n10 0.003 0.004\n\n\n")
        t = read_comp_file(path, 0, 1)
        self.assertEqual(t.nominal_mm, [0.0, 10.0])

    def test_type_0_positions_become_the_trims_linuxcnc_stores(self):
        path = write(self.dir.name, "j.comp", "0 0.004 -0.003\n70 70.0065 69.9982\n")
        t = read_comp_file(path, 0, 0)
        self.assertAlmostEqual(t.forward_trim_mm[0], -0.004, places=12)
        self.assertAlmostEqual(t.reverse_trim_mm[1], 0.0018, places=12)


class TrimAndPositions(unittest.TestCase):
    def test_the_trim_is_linear_between_points_and_held_beyond_the_ends(self):
        t = table([50.0, 120.0], [0.005, -0.002], [0.001, -0.008])
        self.assertEqual(t.trim_mm(0.0, True), 0.005)
        self.assertEqual(t.trim_mm(400.0, False), -0.008)
        self.assertAlmostEqual(t.trim_mm(85.0, True), 0.0015, places=15)
        self.assertAlmostEqual(t.trim_mm(85.0, False), -0.0035, places=15)

    def test_every_joint_of_the_reference_machine_gets_eight_stops_inside_its_travel(self):
        machine = read_machine(REPO / "machines/vmc-reference.toml")
        tables = read_comp_tables(REPO / "deploy/linuxcnc/fixtures/type1")
        for j, axis in enumerate(machine.axes):
            stops = joint_positions(axis, tables.get(j))
            self.assertEqual(len(stops), 8)
            self.assertEqual(stops, sorted(set(stops)))
            self.assertEqual((stops[0], stops[-1]), (axis.min_mm, axis.max_mm))

    def test_the_reference_machine_file_gives_the_configuration_its_limits(self):
        machine = read_machine(REPO / "machines/vmc-reference.toml")
        x, y, z = machine.axes
        self.assertEqual((x.min_mm, x.max_mm, y.max_mm, z.min_mm, z.max_mm),
                         (0.0, 560.0, 400.0, -450.0, 0.0))
        self.assertEqual((x.vel_mm_s, z.vel_mm_s, z.acc_mm_s2), (500.0, 400.0, 1500.0))


class Classify(unittest.TestCase):
    INI = {("EMCMOT", "SERVO_PERIOD"): "1000000", ("JOINT_0", "MAX_ACCELERATION"): "2000"}

    def arrival(self, measured_at, start=12.0):
        return Arrival(2, 0, "reverse", 10.0, 10.0 + measured_at, 10.0, start)

    def test_the_dead_band_is_half_the_acceleration_times_the_period_squared(self):
        lo, hi = dead_band_mm(self.INI, 0)
        self.assertAlmostEqual(lo, 0.0005, places=15)
        self.assertAlmostEqual(hi, 0.001, places=15)

    def test_the_table_value_is_ok_and_a_value_held_in_the_band_is_held(self):
        t = table([0.0, 560.0], [0.002, 0.002], [0.0012, 0.0012])
        band = dead_band_mm(self.INI, 0)
        ok = self.arrival(0.0012)
        self.assertEqual(classify(ok, 0.0012, t, 0.002, 12.0, band, 1e-6)[0], "ok")
        held = self.arrival(0.002)
        self.assertEqual(classify(held, 0.002, t, 0.002, 12.0, band, 1e-6)[0], "held")

    def test_a_gap_outside_the_band_or_a_value_never_applied_is_a_mismatch(self):
        t = table([0.0, 560.0], [0.002, 0.002], [0.0002, 0.0002])
        band = dead_band_mm(self.INI, 0)
        # 1.8 um above the band.
        self.assertEqual(classify(self.arrival(0.002), 0.002, t, 0.002, 12.0, band, 1e-6)[0],
                         "mismatch")
        t = table([0.0, 560.0], [0.002, 0.002], [0.0012, 0.0012])
        # In the band, but never applied before this arrival.
        self.assertEqual(classify(self.arrival(0.0019), 0.0019, t, 0.002, 12.0, band, 1e-6)[0],
                         "mismatch")


if __name__ == "__main__":
    unittest.main()
