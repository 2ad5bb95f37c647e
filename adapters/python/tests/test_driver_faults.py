"""CellServer in-process over drivers that fail: every fault is INTERNAL for that call, and
the server keeps answering (a cell without a camera: its methods are UNIMPLEMENTED)."""
import unittest

import grpc

from helpers import code_of, pb, stub
from twinbench_cell.drivers import MoveOutcome, RobotDriver, RobotInfo
from twinbench_cell.server import CellServer, ConfigError


class FaultyRobot(RobotDriver):
    def robots(self):
        return [RobotInfo("only", [(-1.0, 1.0)] * 3)]

    def move(self, robot, q_rad, should_stop):
        if q_rad[0] > 0.5:
            raise RuntimeError("the controller is unplugged")
        return MoveOutcome(status=42)  # not a status

    def read_joints(self, robot):
        return [0.0, 0.0]  # one joint short

    def stop(self):
        pass

    def time_s(self):
        raise OSError("no clock today")


class DriverFaultTest(unittest.TestCase):
    def setUp(self):
        self.cell = CellServer(FaultyRobot(), None, heartbeat_timeout_s=5)
        self.address = self.cell.start("127.0.0.1:0")
        self.channel, self.stub = stub(self.address)
        self.sid = self.stub.OpenSession(pb.OpenSessionRequest(client="t")).session_id

    def tearDown(self):
        self.channel.close()
        self.cell.shutdown()

    def test_faults_are_internal_and_the_server_stays_up(self):
        s, sid = self.stub, self.sid
        internal = grpc.StatusCode.INTERNAL
        faults = ((s.MoveTo, pb.MoveToRequest(session_id=sid, q_target_rad=[0.9, 0, 0])),
                  (s.MoveTo, pb.MoveToRequest(session_id=sid, q_target_rad=[0.1, 0, 0])),
                  (s.ReadEncoders, pb.ReadEncodersRequest(session_id=sid)),
                  (s.ReadClock, pb.ReadClockRequest(session_id=sid)))
        with self.assertLogs("twinbench_cell.server", "ERROR") as logged:  # each one logged
            for call, req in faults:
                self.assertEqual(code_of(call, req)[0], internal, str(req))
        self.assertEqual(len(logged.records), len(faults))
        # The checks before the driver still answer, and the session lives.
        self.assertEqual(code_of(s.MoveTo, pb.MoveToRequest(session_id=sid, robot=1,
                                                            q_target_rad=[0, 0, 0]))[0],
                         grpc.StatusCode.INVALID_ARGUMENT)
        self.assertEqual(s.MoveTo(pb.MoveToRequest(session_id=sid, q_target_rad=[1.5, 0, 0]))
                         .status, pb.MOVE_STATUS_OUT_OF_LIMITS)
        s.Heartbeat(pb.HeartbeatRequest(session_id=sid))
        d = s.Describe(pb.DescribeRequest())
        self.assertEqual((len(d.robots), d.has_camera, d.image_width_px), (1, False, 0))

    def test_without_a_camera_its_methods_are_unimplemented(self):
        s, sid = self.stub, self.sid
        for call, req in ((s.GrabImage, pb.GrabImageRequest(session_id=sid)),
                          (s.CameraRobot, pb.CameraRobotRequest(session_id=sid)),
                          (s.ExchangeTools, pb.ExchangeToolsRequest(session_id=sid))):
            self.assertEqual(code_of(call, req)[0], grpc.StatusCode.UNIMPLEMENTED)
        # The defaults of the optional methods answer as calib/cell/cell.h's do.
        self.assertFalse(s.ReadTemperature(pb.ReadTemperatureRequest(session_id=sid)).has_sensor)
        self.assertEqual(s.MeasureTracker(pb.MeasureTrackerRequest(session_id=sid)).status,
                         pb.TRACKER_STATUS_NO_TRACKER)
        self.assertEqual(s.JogTipToContact(pb.JogTipToContactRequest(session_id=sid)).status,
                         pb.MOVE_STATUS_INVALID_INPUT)

    def test_a_driver_with_bad_limits_does_not_start(self):
        class NoLimits(FaultyRobot):
            def robots(self):
                return [RobotInfo("r", [(1.0, -1.0)])]
        with self.assertRaises(ConfigError):
            CellServer(NoLimits())


if __name__ == "__main__":
    unittest.main()
