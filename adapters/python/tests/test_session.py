"""The protocol on the fake cell: a round trip, one session at a time, the heartbeat watchdog,
targets out of limits, Stop, the camera's images, the optional methods."""
import math
import threading
import time
import unittest

import grpc

from helpers import HEARTBEAT_S, MARGIN_S, FakeCell, code_of, pb, stub, wait_for
from twinbench_cell import png
from twinbench_cell.client import RemoteCell

import fake_hardware  # noqa: E402 (helpers put the adapter folder on the path)

FAILED_PRECONDITION = grpc.StatusCode.FAILED_PRECONDITION
TOLERANCE_RAD = 1e-9  # the fake reaches its targets exactly; a settled move must read them


class SessionTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.cell = FakeCell()
        cls.channel, cls.stub = stub(cls.cell.address)

    @classmethod
    def tearDownClass(cls):
        cls.channel.close()
        cls.cell.close()

    def tearDown(self):
        self.assertIsNone(self.cell.proc.poll(), "the server died:\n" + self.cell.stderr_text())

    def remote(self, **kw):
        return RemoteCell(self.cell.address, client_name=self.id(), **kw)

    def test_round_trip_reaches_the_target(self):
        with self.remote() as cell:
            d = cell.describe()
            self.assertEqual(d.protocol_version, 1)
            self.assertEqual([r.name for r in d.robots], ["r1", "r2"])
            self.assertEqual([len(r.joints) for r in d.robots], [6, 6])
            self.assertEqual((d.image_width_px, d.image_height_px), (640, 480))
            self.assertAlmostEqual(d.heartbeat_timeout_s, HEARTBEAT_S)
            start = cell.read_encoders(1)
            self.assertEqual(len(start), 6)
            step = [0.3, -0.2, 0.1, 0.25, -0.15, 0.05]
            target = [a + b for a, b in zip(start, step)]
            t0 = time.monotonic()
            result = cell.move_to(1, target)
            took = time.monotonic() - t0
            self.assertEqual(result.status, "SETTLED", result.reason)
            # 0.3 rad at the fake's 1 rad/s
            self.assertAlmostEqual(result.duration_s, 0.3, delta=0.01)
            self.assertGreaterEqual(took, 0.3)
            reached = cell.read_encoders(1)
            for j, (got, want) in enumerate(zip(reached, target)):
                self.assertAlmostEqual(got, want, delta=TOLERANCE_RAD, msg="joint %d" % j)
            self.assertEqual(cell.move_to(1, start).status, "SETTLED")

    def test_one_session_at_a_time(self):
        first = self.remote()
        first.open()
        code, _ = code_of(self.stub.OpenSession, pb.OpenSessionRequest(client="second"))
        self.assertEqual(code, FAILED_PRECONDITION)
        first.close()
        code, answer = code_of(self.stub.OpenSession, pb.OpenSessionRequest(client="second"))
        self.assertEqual(code, grpc.StatusCode.OK)
        self.stub.CloseSession(pb.CloseSessionRequest(session_id=answer.session_id))
        # A closed session is refused like any other name.
        code, _ = code_of(self.stub.Heartbeat, pb.HeartbeatRequest(session_id=answer.session_id))
        self.assertEqual(code, FAILED_PRECONDITION)

    def test_a_clients_name_is_kept_to_200_characters(self):
        answer = self.stub.OpenSession(pb.OpenSessionRequest(client="n" * 5000))
        try:
            with self.assertRaises(grpc.RpcError) as refused:
                self.stub.OpenSession(pb.OpenSessionRequest(client="second"))
            message = refused.exception.details()
            self.assertIn("n" * 200, message)  # the holder is named ...
            self.assertNotIn("n" * 201, message)  # ... by its first 200 characters
        finally:
            self.stub.CloseSession(pb.CloseSessionRequest(session_id=answer.session_id))

    def test_heartbeats_keep_a_session_and_silence_ends_it(self):
        sid = self.stub.OpenSession(pb.OpenSessionRequest(client="silent")).session_id
        # Heartbeats for twice the timeout keep it alive...
        t0 = time.monotonic()
        while True:
            self.stub.Heartbeat(pb.HeartbeatRequest(session_id=sid))
            quiet_since = time.monotonic()
            if quiet_since - t0 > 2 * HEARTBEAT_S:
                break
            time.sleep(HEARTBEAT_S / 4)
            code, _ = code_of(self.stub.OpenSession, pb.OpenSessionRequest(client="other"))
            self.assertEqual(code, FAILED_PRECONDITION)
        # ...and silence ends it: another client gets the cell within timeout + margin (and
        # not before the timeout, less the heartbeat's way back to us).
        answer = []

        def opened():
            code, a = code_of(self.stub.OpenSession, pb.OpenSessionRequest(client="other"))
            answer.append(a)
            return code == grpc.StatusCode.OK

        self.assertIsNotNone(wait_for(opened, HEARTBEAT_S + MARGIN_S))
        self.assertGreater(time.monotonic() - quiet_since, HEARTBEAT_S - 0.05)
        # The old session stays refused, for every call.
        for call, request in ((self.stub.Heartbeat, pb.HeartbeatRequest(session_id=sid)),
                              (self.stub.ReadEncoders, pb.ReadEncodersRequest(session_id=sid)),
                              (self.stub.MoveTo, pb.MoveToRequest(session_id=sid, robot=0,
                                                                  q_target_rad=[0] * 6))):
            self.assertEqual(code_of(call, request)[0], FAILED_PRECONDITION)
        self.stub.CloseSession(pb.CloseSessionRequest(session_id=answer[-1].session_id))

    def test_calls_without_a_session_are_refused(self):
        for sid in ("", "not-a-session"):
            code, _ = code_of(self.stub.ReadEncoders, pb.ReadEncodersRequest(session_id=sid))
            self.assertEqual(code, FAILED_PRECONDITION)

    def test_target_out_of_limits_moves_nothing(self):
        with self.remote() as cell:
            before = cell.read_encoders(0)
            limits = cell.describe().robots[0].joints
            target = list(before)
            target[2] = limits[2].upper_rad + 0.01
            result = cell.move_to(0, target)
            self.assertEqual(result.status, "OUT_OF_LIMITS")
            self.assertIn("joint 2", result.reason)
            time.sleep(0.1)
            self.assertEqual(cell.read_encoders(0), before)

    def test_stop_stops_a_move_part_way(self):
        with self.remote() as cell:
            start = cell.read_encoders(0)
            target = list(start)
            target[0] = 2.0 if start[0] < 0 else -2.0  # at least 2 s away at 1 rad/s
            results = []
            mover = threading.Thread(target=lambda: results.append(cell.move_to(0, target)))
            mover.start()
            time.sleep(0.4)
            t_stop = time.monotonic()
            cell.stop()
            mover.join(5)
            self.assertFalse(mover.is_alive())
            # The fake polls should_stop every 10 ms; 0.5 s leaves room for a loaded CI machine
            # and is still a quarter of the move's remaining 1.6 s or more.
            self.assertLess(time.monotonic() - t_stop, 0.5)
            self.assertEqual(results[0].status, "STOPPED")
            q1 = cell.read_encoders(0)
            time.sleep(0.3)
            self.assertEqual(cell.read_encoders(0), q1)
            self.assertGreater(abs(q1[0] - target[0]), 1.0)
            # The session stays open, and the next move runs.
            self.assertEqual(cell.move_to(0, start).status, "SETTLED")

    def test_a_client_gone_mid_move_ends_its_session_at_once(self):
        # A 5 s heartbeat timeout, so that "at once" (within 1 s of the call's end) cannot be
        # the watchdog's doing. The move's deadline passes 0.3 s into a move of 2 s or more.
        cell = FakeCell(heartbeat_s=5.0)
        channel, s = stub(cell.address)
        try:
            sid = s.OpenSession(pb.OpenSessionRequest(client=self.id())).session_id
            start = list(s.ReadEncoders(pb.ReadEncodersRequest(session_id=sid, robot=0)).q_rad)
            target = list(start)
            target[0] = 2.0 if start[0] < 0 else -2.0
            code, _ = code_of(s.MoveTo, pb.MoveToRequest(session_id=sid, robot=0,
                                                         q_target_rad=target), timeout=0.3)
            self.assertEqual(code, grpc.StatusCode.DEADLINE_EXCEEDED)
            t_end = time.monotonic()

            def ended():
                code, _ = code_of(s.Heartbeat, pb.HeartbeatRequest(session_id=sid))
                return code == FAILED_PRECONDITION

            self.assertIsNotNone(wait_for(ended, 1.0), "the session outlived its client's move")
            self.assertLess(time.monotonic() - t_end, 1.0)
            # And a new session opens at once.
            code, _ = code_of(s.OpenSession, pb.OpenSessionRequest(client="next"))
            self.assertEqual(code, grpc.StatusCode.OK)
        finally:
            channel.close()
            cell.close()

    def test_full_image_is_the_synthetic_frame(self):
        with self.remote() as cell:
            d = cell.describe()
            width, height, rgb = cell.grab_image()
            self.assertEqual((width, height), (d.image_width_px, d.image_height_px))
            self.assertEqual(rgb, fake_hardware.fake_image())
            # The frame is what fake_pixel says, pixel by pixel at a few places (the gradient,
            # each square, the corners): no swapped channels, no flipped rows.
            for x, y in ((0, 0), (639, 0), (0, 479), (639, 479), (320, 240), (110, 90),
                         (450, 350), (510, 70), (99, 79)):
                i = 3 * (y * width + x)
                self.assertEqual(tuple(rgb[i:i + 3]), fake_hardware.fake_pixel(x, y),
                                 "pixel (%d, %d)" % (x, y))
            self.assertEqual(tuple(rgb[0:3]), (0, 0, 128))
            i = 3 * (479 * width + 639)
            self.assertEqual(tuple(rgb[i:i + 3]), (255, 255, 128))

    def test_regions_have_their_size_and_offset(self):
        frame = fake_hardware.fake_image()

        def crop(x, y, w, h):
            return b"".join(frame[3 * (r * 640 + x):3 * (r * 640 + x + w)]
                            for r in range(y, y + h))

        with self.remote() as cell:
            self.assertEqual(cell.grab_image_region(100, 80, 60, 60),
                             (100, 80, 60, 60, b"\xff" * (3 * 60 * 60)))  # the white square
            self.assertEqual(cell.grab_image_region(200, 100, 33, 17),
                             (200, 100, 33, 17, crop(200, 100, 33, 17)))
            # Clipped to the frame at each side.
            self.assertEqual(cell.grab_image_region(600, 470, 100, 50),
                             (600, 470, 40, 10, crop(600, 470, 40, 10)))
            self.assertEqual(cell.grab_image_region(-10, -5, 30, 20),
                             (0, 0, 20, 15, crop(0, 0, 20, 15)))
            # Missing the frame: an empty image at the region.
            self.assertEqual(cell.grab_image_region(640, 0, 10, 10), (640, 0, 0, 0, b""))
            self.assertEqual(cell.grab_image_region(-20, 10, 20, 10), (-20, 10, 0, 0, b""))
            for w, h in ((0, 10), (10, 0), (-5, 10)):
                with self.assertRaises(grpc.RpcError) as e:
                    cell.grab_image_region(10, 10, w, h)
                self.assertEqual(e.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)

    def test_image_answer_is_a_png_of_the_stated_size(self):
        with self.remote() as cell:
            r = self.stub.GrabImage(pb.GrabImageRequest(session_id=cell.session_id))
            self.assertEqual(r.encoding, "png")
            self.assertEqual(r.data[:8], b"\x89PNG\r\n\x1a\n")
            self.assertEqual((r.width_px, r.height_px, r.x_px, r.y_px), (640, 480, 0, 0))
            self.assertEqual(png.decode(r.data)[:2], (640, 480))

    def test_optional_methods(self):
        with self.remote() as cell:
            t1 = cell.clock_seconds()
            time.sleep(0.05)
            t2 = cell.clock_seconds()
            self.assertTrue(math.isfinite(t1))
            self.assertGreater(t2, t1)
            self.assertTrue(math.isfinite(cell.read_temperature_c(1)))
            self.assertEqual(cell.measure_tracker(0).status, "NO_TRACKER")
            first = cell.camera_robot()
            self.assertEqual(cell.exchange_tools().status, "SETTLED")
            self.assertEqual(cell.camera_robot(), 1 - first)
            self.assertEqual(cell.exchange_tools().status, "SETTLED")
            self.assertEqual(cell.mount_target("feature_board").status, "SETTLED")
            self.assertEqual(cell.mount_target("intrinsics_target").status, "INVALID_INPUT")
            r = cell.jog_tip_to_contact(1)
            self.assertEqual(r.status, "INVALID_INPUT")
            self.assertIn("handclasp", r.reason)


class PngTest(unittest.TestCase):
    """The client's decoder reads every PNG filter type (a C++ server's encoder, OpenCV's,
    chooses filters per row), checked on rows filtered here by the PNG rules."""

    def test_all_filter_types_decode(self):
        import random
        import struct
        import zlib
        rng = random.Random(5)
        w, h = 7, 10
        rgb = bytes(rng.randrange(256) for _ in range(3 * w * h))
        stride = 3 * w
        raw = bytearray()
        for y in range(h):
            ftype = y % 5
            row = rgb[y * stride:(y + 1) * stride]
            up = rgb[(y - 1) * stride:y * stride] if y else bytes(stride)
            raw.append(ftype)
            for i in range(stride):
                a = row[i - 3] if i >= 3 else 0
                b = up[i]
                c = up[i - 3] if i >= 3 else 0
                p = a + b - c
                paeth = a if abs(p - a) <= abs(p - b) and abs(p - a) <= abs(p - c) else (
                    b if abs(p - b) <= abs(p - c) else c)
                pred = (0, a, b, (a + b) // 2, paeth)[ftype]
                raw.append((row[i] - pred) & 0xFF)

        def chunk(kind, data):
            return struct.pack(">I", len(data)) + kind + data + struct.pack(
                ">I", zlib.crc32(kind + data))

        data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(bytes(raw))) + chunk(b"IEND", b""))
        self.assertEqual(png.decode(data), (w, h, rgb))
        self.assertEqual(png.decode(png.encode(w, h, rgb)), (w, h, rgb))
        broken = bytearray(data)
        broken[40] ^= 1  # inside IDAT: its CRC no longer matches
        with self.assertRaises(png.PngError):
            png.decode(bytes(broken))


if __name__ == "__main__":
    unittest.main()
