#!/usr/bin/python3
"""A fake two-robot, six-joint cell with a simulated camera and clock, served with CellServer:
the adapter to try the protocol, the Python client and a conformance checker against.

  /usr/bin/python3 adapters/python/fake_hardware.py --listen 127.0.0.1:0 [--heartbeat-timeout S]
      [--tls-cert F --tls-key F] [--client-ca F] [--token-file F] [--joint-speed RAD_S]
      [--break units|no-stop|clock]

The robots move in real time at --joint-speed (all joints arrive together, linear in joint
space), so a long move can be seen stopping part-way. The camera renders a fixed synthetic
640 x 480 image (fake_image below). The --break variants are deliberately broken adapters that
a conformance checker must catch:
  units    joint readings and limits reported in degrees instead of radians (the targets
           are taken in radians, as the protocol has them: a move reads back 57 times too far)
  no-stop  stop is ignored: a move runs on after the session has ended
  clock    the clock steps backwards now and then
"""
import math
import os
import sys
import threading
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from twinbench_cell.drivers import (CameraDriver, Frame, MoveOutcome, MoveStatus,  # noqa: E402
                                    RobotDriver, RobotInfo)
from twinbench_cell.server import serve_main  # noqa: E402

IMAGE_WIDTH, IMAGE_HEIGHT = 640, 480
# The joint limits of both robots [rad], base to flange.
LIMITS_RAD = [(-2.9, 2.9), (-2.0, 2.0), (-2.5, 2.5), (-3.0, 3.0), (-2.0, 2.0), (-3.1, 3.1)]
# Squares of the synthetic image: (x, y, size, (r, g, b)).
SQUARES = [(100, 80, 60, (255, 255, 255)), (400, 300, 90, (0, 0, 0)), (500, 60, 40, (255, 0, 0))]


def fake_pixel(x, y):
    """The fake camera's pixel (x, y) as (r, g, b): a gradient (red along x, green along y,
    blue 128) under three squares."""
    for sx, sy, size, colour in SQUARES:
        if sx <= x < sx + size and sy <= y < sy + size:
            return colour
    return (x * 255 // (IMAGE_WIDTH - 1), y * 255 // (IMAGE_HEIGHT - 1), 128)


def fake_image():
    """The whole synthetic frame as RGB bytes (built row-wise; fake_pixel says what it is)."""
    base = bytearray(3 * IMAGE_WIDTH)
    base[0::3] = bytes(x * 255 // (IMAGE_WIDTH - 1) for x in range(IMAGE_WIDTH))
    base[2::3] = bytes([128]) * IMAGE_WIDTH
    out = bytearray()
    for y in range(IMAGE_HEIGHT):
        row = bytearray(base)
        row[1::3] = bytes([y * 255 // (IMAGE_HEIGHT - 1)]) * IMAGE_WIDTH
        for sx, sy, size, colour in SQUARES:
            if sy <= y < sy + size:
                row[3 * sx:3 * (sx + size)] = bytes(colour) * size
        out += row
    return bytes(out)


class FakeRobots(RobotDriver):
    name = "fake two-robot cell (adapters/python/fake_hardware.py)"
    has_clock = True

    def __init__(self, joint_speed_rad_s=1.0, broken=None):
        self.speed = joint_speed_rad_s
        self.broken = broken
        self._lock = threading.Lock()
        self._q = [[0.0] * 6, [0.0] * 6]
        self._stops = 0
        self._camera_robot = 0
        self._t0 = time.monotonic()
        self._clock_reads = 0
        if broken:
            self.name += " broken: " + broken

    def _report(self, value):  # what the `units` break gets wrong
        return math.degrees(value) if self.broken == "units" else value

    def robots(self):
        limits = [(self._report(lo), self._report(hi)) for lo, hi in LIMITS_RAD]
        return [RobotInfo("r1", limits), RobotInfo("r2", limits)]

    def move(self, robot, q_rad, should_stop):
        with self._lock:
            start = list(self._q[robot])
            stops = self._stops
        span = max(abs(b - a) for a, b in zip(start, q_rad))
        duration = span / self.speed
        t0 = time.monotonic()
        while True:
            elapsed = time.monotonic() - t0
            s = 1.0 if duration <= 0 else min(1.0, elapsed / duration)
            with self._lock:
                self._q[robot] = [a + s * (b - a) for a, b in zip(start, q_rad)]
                stopped = self._stops != stops
            if s >= 1.0:
                return MoveOutcome(MoveStatus.SETTLED, "", duration)
            if self.broken != "no-stop" and (stopped or should_stop()):
                return MoveOutcome(MoveStatus.STOPPED, "stopped after %.3f s of %.3f s"
                                   % (elapsed, duration), elapsed)
            time.sleep(0.01)

    def read_joints(self, robot):
        with self._lock:
            return [self._report(v) for v in self._q[robot]]

    def stop(self):
        with self._lock:
            self._stops += 1

    def time_s(self):
        with self._lock:
            self._clock_reads += 1
            back = self.broken == "clock" and self._clock_reads % 5 == 0
        return time.monotonic() - self._t0 - (0.25 if back else 0.0)

    def temperature_c(self, robot):
        return 21.0 + 0.5 * robot + 0.01 * (time.monotonic() - self._t0)

    def camera_robot(self):
        with self._lock:
            return self._camera_robot

    def exchange_tools(self):
        with self._lock:
            self._camera_robot = 1 - self._camera_robot
        return MoveOutcome(MoveStatus.SETTLED, "", 0.0)


class FakeCamera(CameraDriver):
    def __init__(self):
        self._frame = Frame(IMAGE_WIDTH, IMAGE_HEIGHT, fake_image())

    def size(self):
        return IMAGE_WIDTH, IMAGE_HEIGHT

    def grab(self):
        return self._frame


def _extra(parser):
    parser.add_argument("--joint-speed", type=float, default=1.0, metavar="RAD_S",
                        help="joint speed of the fake robots (default %(default)s rad/s)")
    parser.add_argument("--break", dest="broken", choices=["units", "no-stop", "clock"],
                        help="serve a deliberately broken adapter (for conformance checks)")


def make_drivers(args):
    """The fake's drivers (also for `python3 -m twinbench_cell.server --driver fake_hardware`)."""
    return (FakeRobots(getattr(args, "joint_speed", 1.0), getattr(args, "broken", None)),
            FakeCamera())


def main(argv=None):
    return serve_main(make_drivers, argv,
                      description="A fake two-robot cell with a camera, for the cell protocol.",
                      add_extra_arguments=_extra)


if __name__ == "__main__":
    sys.exit(main())
