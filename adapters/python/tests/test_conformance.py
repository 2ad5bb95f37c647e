"""Stop on disconnect, radians and a monotonic clock, checked on the fake cell (which passes)
and on its deliberately broken variants (each caught by its check)."""
import unittest

from conformance import check_clock, check_stop_on_disconnect, check_units
from helpers import HEARTBEAT_S, FakeCell


class ConformanceTest(unittest.TestCase):
    def run_checks(self, broken=None, stop=True):
        cell = FakeCell(*(["--break", broken] if broken else []))
        try:
            found = {"units": check_units(cell.address), "clock": check_clock(cell.address)}
            if stop:
                found["stop"] = check_stop_on_disconnect(cell.address, HEARTBEAT_S)
            return found
        finally:
            cell.close()

    def test_the_fake_cell_passes(self):
        self.assertEqual(self.run_checks(stop=False), {"units": [], "clock": []})

    def test_a_killed_clients_move_stops(self):
        # SIGKILL of a client 0.7 s into a 2.5 s move: a new session within the heartbeat
        # timeout + MARGIN_S, the old one refused, the robot still and short of the target.
        cell = FakeCell()
        try:
            self.assertEqual(check_stop_on_disconnect(cell.address, HEARTBEAT_S), [])
        finally:
            cell.close()

    def test_degrees_are_caught(self):
        found = self.run_checks("units", stop=False)
        self.assertTrue(any("not radians" in p for p in found["units"]), found)
        self.assertTrue(any("reads 11.4" in p for p in found["units"]), found)  # 0.2 rad in deg
        self.assertEqual(found["clock"], [])

    def test_a_move_that_ignores_stop_is_caught(self):
        cell = FakeCell("--break", "no-stop")
        try:
            found = check_stop_on_disconnect(cell.address, HEARTBEAT_S)
        finally:
            cell.close()
        self.assertNotEqual(found, [])
        self.assertTrue(all("still moving" in p or "not stopped" in p for p in found), found)

    def test_a_clock_that_steps_back_is_caught(self):
        cell = FakeCell("--break", "clock")
        try:
            found = check_clock(cell.address)
        finally:
            cell.close()
        self.assertTrue(any("went back" in p for p in found), found)


if __name__ == "__main__":
    unittest.main()
