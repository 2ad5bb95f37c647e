"""1,000 generated malformed or out-of-range requests (seeded): each gets the status the
protocol gives it, the server stays up, nothing moves."""
import random
import unittest

import grpc

from helpers import FakeCell, code_of, pb, stub

OK = grpc.StatusCode.OK
INVALID = grpc.StatusCode.INVALID_ARGUMENT
NO_SESSION = grpc.StatusCode.FAILED_PRECONDITION
N_REQUESTS = 1000
N_ROBOTS, N_JOINTS, WIDTH, HEIGHT = 2, 6, 640, 480
INT32_MAX, UINT32_MAX = 2 ** 31 - 1, 2 ** 32 - 1


def bad_robot(rng):
    return rng.choice([N_ROBOTS, N_ROBOTS + 1, 17, 2 ** 31, UINT32_MAX])


def wrong_session(rng, sid):
    return rng.choice(["", "x", sid[:-1] + ("1" if sid[-1] != "1" else "2"), sid.upper(),
                       sid + "0", "\u00e9\u00df" * 8, "%032x" % rng.getrandbits(128), " " + sid])


def request(rng, sid, limits):
    """(method name, request, expected code, check of the answer or None), one defect each."""
    if rng.random() < 0.2:  # a wrong session: checked before anything else in the request
        s = wrong_session(rng, sid)
        name, req = rng.choice([
            ("Heartbeat", pb.HeartbeatRequest(session_id=s)),
            ("CloseSession", pb.CloseSessionRequest(session_id=s)),
            ("Stop", pb.StopRequest(session_id=s)),
            ("MoveTo", pb.MoveToRequest(session_id=s, robot=rng.randrange(3),
                                        q_target_rad=[0.0] * rng.randrange(8))),
            ("ReadEncoders", pb.ReadEncodersRequest(session_id=s, robot=rng.randrange(3))),
            ("GrabImage", pb.GrabImageRequest(session_id=s)),
            ("ExchangeTools", pb.ExchangeToolsRequest(session_id=s)),
            ("CameraRobot", pb.CameraRobotRequest(session_id=s)),
            ("ReadClock", pb.ReadClockRequest(session_id=s)),
            ("MountTarget", pb.MountTargetRequest(session_id=s, target=rng.randrange(4)))])
        return name, req, NO_SESSION, None
    kind = rng.choice(["move", "move", "move", "robot", "region", "target", "jog"])
    if kind == "move":
        defect = rng.choice(["robot", "length", "nonfinite", "limits"])
        q = [rng.uniform(-0.5, 0.5) for _ in range(N_JOINTS)]
        robot = rng.randrange(N_ROBOTS)
        expected, check = INVALID, None
        if defect == "robot":
            robot = bad_robot(rng)
        elif defect == "length":
            q = [rng.uniform(-0.5, 0.5) for _ in range(rng.choice([0, 1, 5, 7, 12, 100]))]
        elif defect == "nonfinite":
            q[rng.randrange(N_JOINTS)] = rng.choice([float("nan"), float("inf"), float("-inf")])
        else:
            j = rng.randrange(N_JOINTS)
            lo, hi = limits[j]
            beyond = rng.choice([1e-6, 0.01, 1.0, 1e300])
            q[j] = hi + beyond if rng.random() < 0.5 else lo - beyond
            expected = OK

            def check(answer):
                return answer.status == pb.MOVE_STATUS_OUT_OF_LIMITS
        return "MoveTo", pb.MoveToRequest(session_id=sid, robot=robot, q_target_rad=q), \
            expected, check
    if kind == "robot":
        name, req = rng.choice([("ReadEncoders", pb.ReadEncodersRequest),
                                ("ReadTemperature", pb.ReadTemperatureRequest),
                                ("MeasureTracker", pb.MeasureTrackerRequest)])
        return name, req(session_id=sid, robot=bad_robot(rng)), INVALID, None
    if kind == "jog":
        return "JogTipToContact", pb.JogTipToContactRequest(
            session_id=sid, jogged_robot=bad_robot(rng)), INVALID, None
    if kind == "target":  # UNSPECIFIED or a number the proto does not name
        target = rng.choice([0, 3, 4, 100, INT32_MAX, -1, -2 ** 31])
        return "MountTarget", pb.MountTargetRequest(session_id=sid, target=target), INVALID, None
    # kind == "region"
    big = [INT32_MAX, 2 ** 30, 10 ** 6]
    if rng.random() < 0.5:  # empty or negative: malformed
        w, h = rng.choice([(0, 10), (10, 0), (0, 0), (-1, 5), (5, -7), (-2 ** 31, 1)])
        region = pb.PixelRegion(x_px=rng.randrange(-100, 700), y_px=rng.randrange(-100, 500),
                                width_px=w, height_px=h)
        return "GrabImage", pb.GrabImageRequest(session_id=sid, region=region), INVALID, None
    # well formed but missing the frame (some at int32's ends): an empty image
    x, y, w, h = rng.choice([
        (WIDTH, 0, 10, 10), (0, HEIGHT, 10, 10), (rng.choice(big), 5, rng.choice(big), 3),
        (-rng.choice(big), 0, rng.randrange(1, 50), 10), (3, -2 ** 31, 4, rng.choice(big[1:])),
        (-2 ** 31, -2 ** 31, INT32_MAX, INT32_MAX)])
    region = pb.PixelRegion(x_px=x, y_px=y, width_px=w, height_px=h)

    def empty(answer):
        return answer.data == b"" and answer.width_px == 0 and answer.height_px == 0
    return "GrabImage", pb.GrabImageRequest(session_id=sid, region=region), OK, empty


class FuzzTest(unittest.TestCase):
    def test_malformed_requests_get_their_status(self):
        cell = FakeCell(heartbeat_s=5.0)
        channel, cell_stub = stub(cell.address)
        try:
            sid = cell_stub.OpenSession(pb.OpenSessionRequest(client="fuzz")).session_id
            d = cell_stub.Describe(pb.DescribeRequest())
            limits = [(j.lower_rad, j.upper_rad) for j in d.robots[0].joints]
            before = [list(cell_stub.ReadEncoders(pb.ReadEncodersRequest(
                session_id=sid, robot=r)).q_rad) for r in range(N_ROBOTS)]
            rng = random.Random(40)
            wrong = []
            codes = {}
            for i in range(N_REQUESTS):
                name, req, expected, check = request(rng, sid, limits)
                code, answer = code_of(getattr(cell_stub, name), req, timeout=10)
                codes[code] = codes.get(code, 0) + 1
                if code != expected or (check is not None and not check(answer)):
                    wrong.append("#%d %s(%s): %s, expected %s" % (
                        i, name, str(req).replace("\n", " ")[:200], code, expected))
            self.assertFalse(wrong, "%d of %d answers wrong, the first:\n%s"
                             % (len(wrong), N_REQUESTS, "\n".join(wrong[:10])))
            # All three kinds of answer came (the generator is not degenerate).
            self.assertGreater(codes.get(INVALID, 0), 300)
            self.assertGreater(codes.get(NO_SESSION, 0), 100)
            self.assertGreater(codes.get(OK, 0), 100)
            # The server still answers, the session still lives, nothing moved.
            self.assertEqual(len(cell_stub.Describe(pb.DescribeRequest()).robots), N_ROBOTS)
            cell_stub.Heartbeat(pb.HeartbeatRequest(session_id=sid))
            after = [list(cell_stub.ReadEncoders(pb.ReadEncodersRequest(
                session_id=sid, robot=r)).q_rad) for r in range(N_ROBOTS)]
            self.assertEqual(after, before)
            cell_stub.CloseSession(pb.CloseSessionRequest(session_id=sid))
            self.assertIsNone(cell.proc.poll())
        finally:
            channel.close()
            cell.close()
        self.assertNotIn("Traceback", cell.stderr_text())


if __name__ == "__main__":
    unittest.main()
