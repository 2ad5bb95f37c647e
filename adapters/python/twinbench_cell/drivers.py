"""The two interfaces a hardware integrator fills in: RobotDriver (the robots, and the cell's
optional extras) and CameraDriver (the hand camera). The server (server.py) does everything of
the protocol around them: sessions, the heartbeat watchdog, checking every request, refusing
targets outside the limits, PNG encoding. A driver only talks to the hardware.

Units: joint angles in rad (motor side, as the controller reports them), time in s,
temperature in deg C, lengths in m, images in px. Calls may come from several threads at
once (a ReadEncoders while a move runs, stop() from the watchdog): drivers must be thread-safe
for that; moves themselves are never concurrent (the server runs one at a time).
"""
import abc
import enum
import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Sequence, Tuple


class MoveStatus(enum.IntEnum):
    """twinbench.cell.v1.MoveStatus (same numbers)."""
    SETTLED = 1         # reached the targets and came to rest
    COLLISION = 2       # stopped: something was hit (reason names it)
    NOT_SETTLED = 3     # still moving after the cell's time limit
    OUT_OF_LIMITS = 4   # the targets are outside the joint limits; nothing moved
    INVALID_INPUT = 5   # the cell refused the request; nothing moved
    STOPPED = 6         # stopped by Stop or by the end of the session


class TrackerStatus(enum.IntEnum):
    """twinbench.cell.v1.TrackerStatus (same numbers)."""
    OK = 1
    NO_TRACKER = 2
    OUT_OF_RANGE = 3
    OCCLUDED = 4


class BracketTarget(enum.IntEnum):
    """twinbench.cell.v1.BracketTarget (same numbers)."""
    FEATURE_BOARD = 1
    INTRINSICS_TARGET = 2


@dataclass
class MoveOutcome:
    status: MoveStatus = MoveStatus.SETTLED
    reason: str = ""          # what went wrong, empty when settled
    duration_s: float = 0.0   # motion time of the move


@dataclass
class TrackerOutcome:
    status: TrackerStatus = TrackerStatus.NO_TRACKER
    reason: str = ""
    p_m: Tuple[float, float, float] = (0.0, 0.0, 0.0)  # the reflector in the tracker's frame
    time_s: float = 0.0                                # when it was measured (the cell's clock)


@dataclass
class RobotInfo:
    name: str
    limits_rad: List[Tuple[float, float]] = field(default_factory=list)  # (lower, upper) per joint


@dataclass
class Frame:
    """One camera frame: rgb holds R, G, B bytes per pixel, rows from the top."""
    width: int
    height: int
    rgb: bytes


class RobotDriver(abc.ABC):
    """The robots of a cell (one or two) and the cell's optional extras."""

    #: The cell's name for Describe (free text).
    name = "cell"
    #: Set True where time_s() reads a clock.
    has_clock = False
    #: Set True where measure_tracker() is implemented.
    has_tracker = False
    #: Set True where jog_tip_to_contact() is implemented.
    has_handclasp = False

    @abc.abstractmethod
    def robots(self) -> Sequence[RobotInfo]:
        """The robots, index 0 first (at most two), with their joint limits [rad]. Read once
        when the server starts."""

    @abc.abstractmethod
    def move(self, robot: int, q_rad: Sequence[float],
             should_stop: Callable[[], bool]) -> MoveOutcome:
        """Moves robot `robot` to the joint targets [rad] and blocks until it has settled. The
        targets are checked already (right length, finite, inside the limits). Must poll
        should_stop() while moving (every few tens of ms) and, once it is true, stop the robot
        and return MoveStatus.STOPPED."""

    @abc.abstractmethod
    def read_joints(self, robot: int) -> Sequence[float]:
        """The joint encoders of robot `robot` now [rad], one per joint."""

    @abc.abstractmethod
    def stop(self) -> None:
        """Stops all motion now (the watchdog calls it when a session goes silent)."""

    # --- optional: the defaults refuse as calib/cell/cell.h's defaults do -------------------

    def time_s(self) -> float:
        """The cell's clock [s] from an origin of its choosing; NaN: no clock."""
        return math.nan

    def temperature_c(self, robot: int) -> float:
        """Robot `robot`'s structure temperature [deg C]; NaN: no sensor."""
        return math.nan

    def measure_tracker(self, robot: int) -> TrackerOutcome:
        return TrackerOutcome(TrackerStatus.NO_TRACKER,
                              "this cell has no laser tracker (robot %d)" % robot)

    def camera_robot(self) -> int:
        """The robot carrying the hand camera now (asked only where the cell has a camera)."""
        return 0

    def exchange_tools(self) -> MoveOutcome:
        return MoveOutcome(MoveStatus.INVALID_INPUT,
                           "this cell cannot exchange the camera and the board")

    def jog_tip_to_contact(self, jogged_robot: int) -> MoveOutcome:
        return MoveOutcome(MoveStatus.INVALID_INPUT,
                           "this cell has no handclasp (robot %d cannot be jogged onto the "
                           "other tip)" % jogged_robot)

    def mount_target(self, target: BracketTarget) -> MoveOutcome:
        if target != BracketTarget.FEATURE_BOARD:
            return MoveOutcome(MoveStatus.INVALID_INPUT,
                               "this cell has no intrinsics target (only the feature board)")
        return MoveOutcome()


class CameraDriver(abc.ABC):
    """The hand camera: 8-bit RGB frames of a fixed size."""

    @abc.abstractmethod
    def size(self) -> Tuple[int, int]:
        """(width, height) of a frame [px]."""

    @abc.abstractmethod
    def grab(self):
        """One frame now: a Frame, a (width, height, rgb bytes) tuple, or a numpy uint8 array
        of shape (height, width, 3) in RGB order."""

    def grab_region(self, x: int, y: int, width: int, height: int) -> Optional[object]:
        """The region (already clipped to the frame, never empty) of the next frame, in any
        form grab() returns; None (the default): the server grabs a whole frame and crops it.
        A camera that reads out a region faster overrides this."""
        return None
