"""Small conformance checks of a cell server, each a list of the problems it found (empty: the
server passes). The tests run them on the fake cell and on its deliberately broken variants,
which they must catch. Each check opens and closes its own session."""
import math
import os
import signal
import subprocess
import tempfile
import time

import grpc

from helpers import ADAPTER, MARGIN_S, PYTHON, code_of, pb, stub, wait_for

TWO_PI = 2 * math.pi


def check_units(address):
    """Joint limits and readings in radians: limits within a few turns, and a move of 0.2 rad
    reads back as 0.2 rad."""
    problems = []
    channel, s = stub(address)
    try:
        d = s.Describe(pb.DescribeRequest())
        for r in d.robots:
            for j, lim in enumerate(r.joints):
                if max(abs(lim.lower_rad), abs(lim.upper_rad)) > 2 * TWO_PI:
                    problems.append("robot %s joint %d: limits [%g, %g] are not radians"
                                    % (r.name, j, lim.lower_rad, lim.upper_rad))
        sid = s.OpenSession(pb.OpenSessionRequest(client="check_units")).session_id
        q = list(s.ReadEncoders(pb.ReadEncodersRequest(session_id=sid, robot=0)).q_rad)
        target = [0.0] * len(q)
        target[0] = 0.2
        result = s.MoveTo(pb.MoveToRequest(session_id=sid, robot=0, q_target_rad=target))
        if result.status != pb.MOVE_STATUS_SETTLED:
            problems.append("the move to 0.2 rad did not settle: %s" % result.reason)
        read = s.ReadEncoders(pb.ReadEncodersRequest(session_id=sid, robot=0)).q_rad[0]
        # 1 mrad: far above an encoder's noise, far below what degrees read as radians show
        # (0.2 rad reads 11.46 in degrees), as cell-check's own units check.
        if abs(read - 0.2) > 1e-3:
            problems.append("moved to 0.2 rad, reads %g" % read)
        s.CloseSession(pb.CloseSessionRequest(session_id=sid))
    finally:
        channel.close()
    return problems


def check_clock(address, reads=40):
    """The clock never runs backwards."""
    problems = []
    channel, s = stub(address)
    try:
        sid = s.OpenSession(pb.OpenSessionRequest(client="check_clock")).session_id
        last = -math.inf
        for i in range(reads):
            r = s.ReadClock(pb.ReadClockRequest(session_id=sid))
            if r.has_clock and r.time_s < last:
                problems.append("read %d: the clock went back from %.6f to %.6f s"
                                % (i, last, r.time_s))
            last = r.time_s
            time.sleep(0.002)
        s.CloseSession(pb.CloseSessionRequest(session_id=sid))
    finally:
        channel.close()
    return problems


# A client that opens a session, reports it and moves robot 0's joint 0 to the other side:
# killed (SIGKILL) part-way by check_stop_on_disconnect.
_MOVER = r"""
import sys
sys.path.insert(0, sys.argv[2])
from twinbench_cell.client import RemoteCell
cell = RemoteCell(sys.argv[1], client_name="mover")
sid = cell.open()
q = cell.read_encoders(0)
target = list(q)
target[0] = -2.5 if q[0] > 0 else 2.5
print("moving", sid, target[0], flush=True)
cell.move_to(0, target)
print("the move ended", flush=True)
"""


def check_stop_on_disconnect(address, heartbeat_s, kill_after_s=0.7):
    """A client killed during a long move: within the heartbeat timeout + MARGIN_S (from the
    kill) a new session opens, the old session is refused, and the robot is still (two reads
    0.3 s apart are equal) and short of the target."""
    problems = []
    err = tempfile.TemporaryFile(mode="w+")
    mover = subprocess.Popen([PYTHON, "-c", _MOVER, address, ADAPTER], stdout=subprocess.PIPE,
                             stderr=err, text=True)
    channel, s = stub(address)
    try:
        words = mover.stdout.readline().split()
        if not words or words[0] != "moving":
            mover.wait()
            err.seek(0)
            return ["the moving client did not start:\n" + err.read()]
        old_sid, target = words[1], float(words[2])
        time.sleep(kill_after_s)
        os.kill(mover.pid, signal.SIGKILL)
        mover.wait()
        sid = []

        def opened():
            code, answer = code_of(s.OpenSession, pb.OpenSessionRequest(client="after-kill"))
            if code == grpc.StatusCode.OK:
                sid.append(answer.session_id)
            return bool(sid)

        if wait_for(opened, heartbeat_s + MARGIN_S) is None:
            return ["no new session within %.1f s of the client's death"
                    % (heartbeat_s + MARGIN_S)]
        code, _ = code_of(s.Heartbeat, pb.HeartbeatRequest(session_id=old_sid))
        if code != grpc.StatusCode.FAILED_PRECONDITION:
            problems.append("the dead client's session is answered with %s" % code)
        read = lambda: list(s.ReadEncoders(pb.ReadEncodersRequest(  # noqa: E731
            session_id=sid[0], robot=0)).q_rad)
        q1 = read()
        time.sleep(0.3)
        q2 = read()
        if q1 != q2:
            problems.append("still moving after the session ended: joint 0 %.4f -> %.4f rad"
                            % (q1[0], q2[0]))
        time.sleep(0.3)
        # Stopped 0.7 s into a move of 2 s or more at 1 rad/s, it is over 1 rad short of the
        # target; within 1 mrad of it, the move ran to its end.
        if abs(read()[0] - target) < 1e-3:
            problems.append("the move reached its target %.3f rad: it was not stopped" % target)
        # Back to the start, for the next check on this server.
        back = read()
        back[0] = 0.0
        s.MoveTo(pb.MoveToRequest(session_id=sid[0], robot=0, q_target_rad=back))
        s.CloseSession(pb.CloseSessionRequest(session_id=sid[0]))
    finally:
        if mover.poll() is None:
            mover.kill()
            mover.wait()
        mover.stdout.close()
        err.close()
        channel.close()
    return problems
