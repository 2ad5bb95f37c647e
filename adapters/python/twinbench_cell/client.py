"""RemoteCell: a Python client of a cell server (adapters/python's CellServer, or the C++
`twinbench serve-cell`, which speaks the same protocol), with Pythonic methods named after the
Cell interface. Heartbeats run in a background thread while a session is open.

    with RemoteCell("127.0.0.1:50051") as cell:          # opens a session
        q = cell.read_encoders(0)
        result = cell.move_to(0, [0.1, 0, 0, 0, 0, 0])   # MoveResult("SETTLED", "", 0.1)
        width, height, rgb = cell.grab_image()

gRPC errors arrive as grpc.RpcError (e.code(): FAILED_PRECONDITION, INVALID_ARGUMENT, ...).
"""
import collections
import math
import threading

import grpc

from . import png, stubs

MoveResult = collections.namedtuple("MoveResult", "status reason duration_s")
TrackerReading = collections.namedtuple("TrackerReading", "status reason p_m time_s")


def open_channel(target, ca_cert=None, client_cert=None, client_key=None, server_name=None):
    """A channel to target (host:port): TLS when ca_cert (PEM bytes of the CA that signed the
    server's certificate) is given, with a client certificate when client_cert/client_key are;
    plaintext otherwise (loopback only, as servers allow). server_name overrides the name the
    server's certificate is checked against."""
    if ca_cert is None and client_cert is None:
        return grpc.insecure_channel(target)
    creds = grpc.ssl_channel_credentials(root_certificates=ca_cert, private_key=client_key,
                                         certificate_chain=client_cert)
    options = [("grpc.ssl_target_name_override", server_name)] if server_name else []
    return grpc.secure_channel(target, creds, options=options)


def _read(path):
    if path is None:
        return None
    with open(path, "rb") as f:
        return f.read()


class RemoteCell:
    """One client of a cell. Paths or PEM bytes for the TLS files; token: the bearer token
    (sent as metadata `authorization: Bearer <token>` on every call; over TLS only, but for
    loopback). timeout_s: the deadline of every call but MoveTo and the operator steps, whose
    deadline is motion_timeout_s (they wait for the motion)."""

    def __init__(self, target, ca_cert=None, client_cert=None, client_key=None, token=None,
                 server_name=None, client_name="twinbench_cell.client", timeout_s=10.0,
                 open_session=True, motion_timeout_s=300.0):
        as_bytes = lambda v: _read(v) if isinstance(v, str) else v  # noqa: E731
        self.pb, pb_grpc = stubs.load()
        self.channel = open_channel(target, as_bytes(ca_cert), as_bytes(client_cert),
                                    as_bytes(client_key), server_name)
        self.stub = pb_grpc.CellStub(self.channel)
        host = target.rsplit(":", 1)[0].strip("[]")
        if token and ca_cert is None and host not in ("127.0.0.1", "::1", "localhost") \
                and not host.startswith("127."):
            raise ValueError("a bearer token is sent only over TLS beyond loopback: give ca_cert")
        self.metadata = [("authorization", "Bearer " + token)] if token else []
        self.client_name = client_name
        self.timeout_s = timeout_s
        self.motion_timeout_s = motion_timeout_s
        self.session_id = None
        self.session_lost = None  # the error that ended the heartbeats, if one did
        self._open_session = open_session
        self._beat_stop = threading.Event()
        self._beat = None

    # --- plumbing -----------------------------------------------------------------------------

    def _call(self, name, request, timeout=True):
        return getattr(self.stub, name)(request, metadata=self.metadata,
                                        timeout=self.timeout_s if timeout else self.motion_timeout_s)

    def _sid(self):
        if self.session_id is None:
            raise RuntimeError("no session: call open() first")
        return self.session_id

    def _move_result(self, r):
        return MoveResult(self.pb.MoveStatus.Name(r.status).replace("MOVE_STATUS_", ""),
                          r.reason, r.duration_s)

    def __enter__(self):
        if self._open_session:
            self.open()
        return self

    def __exit__(self, *exc):
        self.close()

    # --- session ------------------------------------------------------------------------------

    def describe(self):
        """The DescribeResponse message (robots, limits, camera size, heartbeat timeout...)."""
        return self._call("Describe", self.pb.DescribeRequest())

    def open(self, heartbeat_interval_s=None):
        """Opens a session and starts heartbeats (default: a third of the server's timeout)."""
        r = self._call("OpenSession", self.pb.OpenSessionRequest(client=self.client_name))
        self.session_id = r.session_id
        interval = heartbeat_interval_s or r.heartbeat_timeout_s / 3
        self._beat_stop.clear()
        self._beat = threading.Thread(target=self._heartbeats, args=(r.session_id, interval),
                                      daemon=True, name="cell-heartbeat")
        self._beat.start()
        return r.session_id

    def _heartbeats(self, session_id, interval):
        while not self._beat_stop.wait(interval):
            try:
                self.stub.Heartbeat(self.pb.HeartbeatRequest(session_id=session_id),
                                    metadata=self.metadata, timeout=max(interval, 1.0))
            except grpc.RpcError as e:
                if e.code() == grpc.StatusCode.FAILED_PRECONDITION:  # the session is gone
                    self.session_lost = e
                    return
                # a transient failure: the next beat may get through before the timeout

    def close(self):
        """Closes the session (if open) and the channel."""
        self._beat_stop.set()
        if self._beat is not None:
            self._beat.join()
            self._beat = None
        if self.session_id is not None:
            try:
                self._call("CloseSession", self.pb.CloseSessionRequest(session_id=self.session_id))
            except grpc.RpcError:
                pass  # ended already (timed out): nothing to close
            self.session_id = None
        self.channel.close()

    def stop(self):
        self._call("Stop", self.pb.StopRequest(session_id=self._sid()))

    # --- the Cell interface -------------------------------------------------------------------

    def move_to(self, robot, q_target_rad):
        """Moves robot `robot` to the joint targets [rad]; blocks until it settles."""
        r = self._call("MoveTo", self.pb.MoveToRequest(
            session_id=self._sid(), robot=robot, q_target_rad=list(q_target_rad)), timeout=False)
        return self._move_result(r)

    def read_encoders(self, robot):
        """The joint encoders of robot `robot` [rad]."""
        return list(self._call("ReadEncoders", self.pb.ReadEncodersRequest(
            session_id=self._sid(), robot=robot)).q_rad)

    def _grab(self, region):
        r = self._call("GrabImage", self.pb.GrabImageRequest(session_id=self._sid(),
                                                             region=region))
        if not r.data:
            return r, 0, 0, b""
        if r.encoding != "png":
            raise ValueError("the server sent an image encoded as %r" % r.encoding)
        width, height, rgb = png.decode(r.data)
        if (width, height) != (r.width_px, r.height_px):
            raise ValueError("the PNG is %dx%d, the answer says %dx%d"
                             % (width, height, r.width_px, r.height_px))
        return r, width, height, rgb

    def grab_image(self):
        """One frame: (width, height, rgb bytes: R, G, B per pixel, rows from the top)."""
        _, width, height, rgb = self._grab(None)
        return width, height, rgb

    def grab_image_region(self, x, y, width, height):
        """The region of the next frame clipped to it: (x, y, width, height, rgb), x, y its
        frame position; width = height = 0 and rgb empty when the region misses the frame."""
        r, w, h, rgb = self._grab(self.pb.PixelRegion(x_px=x, y_px=y, width_px=width,
                                                      height_px=height))
        return r.x_px, r.y_px, w, h, rgb

    def exchange_tools(self):
        return self._move_result(self._call("ExchangeTools", self.pb.ExchangeToolsRequest(
            session_id=self._sid()), timeout=False))

    def camera_robot(self):
        return self._call("CameraRobot", self.pb.CameraRobotRequest(
            session_id=self._sid())).robot

    def jog_tip_to_contact(self, jogged_robot):
        return self._move_result(self._call("JogTipToContact", self.pb.JogTipToContactRequest(
            session_id=self._sid(), jogged_robot=jogged_robot), timeout=False))

    def mount_target(self, target):
        """target: "feature_board" or "intrinsics_target" (or the enum's number)."""
        if isinstance(target, str):
            target = self.pb.BracketTarget.Value("BRACKET_TARGET_" + target.upper())
        return self._move_result(self._call("MountTarget", self.pb.MountTargetRequest(
            session_id=self._sid(), target=target), timeout=False))

    def clock_seconds(self):
        """The cell's clock [s]; NaN where it keeps none (as Cell::ClockSeconds)."""
        r = self._call("ReadClock", self.pb.ReadClockRequest(session_id=self._sid()))
        return r.time_s if r.has_clock else math.nan

    def read_temperature_c(self, robot):
        """Robot `robot`'s temperature [deg C]; NaN without a sensor."""
        r = self._call("ReadTemperature", self.pb.ReadTemperatureRequest(
            session_id=self._sid(), robot=robot))
        return r.temperature_deg_c if r.has_sensor else math.nan

    def measure_tracker(self, robot):
        r = self._call("MeasureTracker", self.pb.MeasureTrackerRequest(
            session_id=self._sid(), robot=robot))
        return TrackerReading(self.pb.TrackerStatus.Name(r.status).replace("TRACKER_STATUS_", ""),
                              r.reason, (r.x_m, r.y_m, r.z_m), r.time_s)
