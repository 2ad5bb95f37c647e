"""CellServer: the whole twinbench.cell.v1.Cell service over a RobotDriver and an optional
CameraDriver (drivers.py). The protocol is enforced here, in one place, so that every adapter
gets it right:

- Authentication first (token interceptor, when a token is set), then the session, then the
  request's fields: a call naming no live session is FAILED_PRECONDITION even when its fields
  are malformed too.
- One session at a time: OpenSession while one is alive is FAILED_PRECONDITION. Every call but
  Describe and OpenSession must name the live session.
- A watchdog ends a session silent for longer than the heartbeat timeout: any call naming it
  counts (Heartbeat included), and a call still in flight (a long MoveTo) keeps it alive while
  its client is connected. Ending calls driver.stop(), makes a move in flight return STOPPED,
  and every later call naming the old session is FAILED_PRECONDITION.
- A motion call that ends early (the client disconnected or was killed, or its deadline
  passed) stops its motion and ends its session at once.
- Malformed requests are INVALID_ARGUMENT (robot index the cell lacks, wrong vector length,
  NaN or infinity, a region of zero or negative width or height, a BracketTarget that is
  UNSPECIFIED or a number the proto does not name); targets outside the joint limits are
  MOVE_STATUS_OUT_OF_LIMITS and the driver is not called. A driver that
  raises or answers nonsense gives INTERNAL; the server never goes down on a request.
- The camera methods (GrabImage, CameraRobot, ExchangeTools) are UNIMPLEMENTED without a
  camera; the optional extras (clock, temperature, tracker, handclasp, mount target) answer as
  calib/cell/cell.h's defaults do (has_clock false, has_sensor false, TRACKER_STATUS_NO_TRACKER,
  MOVE_STATUS_INVALID_INPUT with a reason).

Security (start() / serve_main()): plaintext only on loopback; beyond loopback TLS plus client
certificates (--client-ca) or a bearer token (--token-file), else the server refuses to start
(exit 2).
"""
import argparse
import contextlib
import functools
import hmac
import ipaddress
import logging
import math
import os
import secrets
import signal
import sys
import threading
import time
from concurrent import futures

import grpc

from . import png, stubs
from .drivers import BracketTarget, CameraDriver, Frame, MoveOutcome, MoveStatus, RobotDriver

log = logging.getLogger("twinbench_cell.server")

PROTOCOL_VERSION = 1
SERVER_NAME = "twinbench_cell (Python) 1.0"


class ConfigError(Exception):
    """A server configuration that must not start (exit 2)."""


class _Refusal(Exception):
    def __init__(self, code, message):
        super().__init__(message)
        self.code = code
        self.message = message


def _rpc(method):
    """Turns refusals into their gRPC status and any other exception into INTERNAL (logged)."""
    @functools.wraps(method)
    def wrapper(self, request, context):
        try:
            return method(self, request, context)
        except _Refusal as r:
            code, message = r.code, r.message
        except Exception as e:  # the adapter's fault; the server stays up
            log.exception("%s failed", method.__name__)
            code, message = grpc.StatusCode.INTERNAL, "adapter error in %s: %s" % (
                method.__name__, e)
        context.abort(code, message)
    return wrapper


def _invalid(message):
    return _Refusal(grpc.StatusCode.INVALID_ARGUMENT, message)


class _Session:
    def __init__(self, session_id, client):
        self.id = session_id
        self.client = client
        self.last_seen = time.monotonic()
        self.calls = set()    # contexts of calls in flight
        self.ended = False
        self.stop_count = 0   # Stop calls so far: a move started before one is stopped


class CellServer:
    """The Cell service (add it to a grpc.server, or use start())."""

    def __init__(self, robot: RobotDriver, camera: CameraDriver = None,
                 heartbeat_timeout_s: float = 2.0, name: str = None):
        if not (heartbeat_timeout_s > 0 and math.isfinite(heartbeat_timeout_s)):
            raise ConfigError("the heartbeat timeout must be a positive number of seconds")
        self.pb, self.pb_grpc = stubs.load()
        self.robot = robot
        self.camera = camera
        self.heartbeat_timeout_s = float(heartbeat_timeout_s)
        self.name = name or getattr(robot, "name", "cell")
        self.robots = list(robot.robots())
        self._check_robots()
        self.image_size = tuple(camera.size()) if camera is not None else (0, 0)
        self._lock = threading.Lock()
        self._session = None
        self._motion_lock = threading.Lock()  # one motion (move, exchange, jog, mount) at a time
        self._halt = threading.Event()
        self._watchdog = threading.Thread(target=self._watch, name="cell-watchdog", daemon=True)
        self._watchdog.start()
        self._server = None

    def _check_robots(self):
        if not 1 <= len(self.robots) <= 2:
            raise ConfigError("a cell has one or two robots, the driver describes %d"
                              % len(self.robots))
        for r in self.robots:
            if not 1 <= len(r.limits_rad) <= 12:
                raise ConfigError("robot %s has %d joints (1 to 12)" % (r.name, len(r.limits_rad)))
            for lo, hi in r.limits_rad:
                if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                    raise ConfigError("robot %s: bad joint limits (%r, %r)" % (r.name, lo, hi))

    # --- sessions and the watchdog -------------------------------------------------------------

    @contextlib.contextmanager
    def _call(self, session_id, context):
        """The live session named by session_id for the length of one call, or
        FAILED_PRECONDITION. The call keeps the session alive while it is in flight."""
        with self._lock:
            s = self._session
            if s is None:
                raise _Refusal(grpc.StatusCode.FAILED_PRECONDITION, "no session is open")
            if not hmac.compare_digest(session_id.encode("utf-8", "replace"), s.id.encode()):
                raise _Refusal(grpc.StatusCode.FAILED_PRECONDITION,
                               "not the cell's session (ended, or the cell is held by another)")
            s.last_seen = time.monotonic()
            s.calls.add(context)

        def done():
            with self._lock:
                if context in s.calls:
                    s.calls.discard(context)
                    s.last_seen = time.monotonic()

        if not context.add_callback(done):  # already terminated (cancelled before we got here)
            done()
        try:
            yield s
        finally:
            done()

    def _end(self, s, why, stop_driver):
        with self._lock:
            if s.ended:
                return
            s.ended = True
            if self._session is s:
                self._session = None
        log.info("session of %r ended: %s", s.client, why)
        if stop_driver:
            try:
                self.robot.stop()
            except Exception:
                log.exception("driver.stop() failed")

    def _watch(self):
        period = min(0.05, self.heartbeat_timeout_s / 10)
        while not self._halt.wait(period):
            with self._lock:
                s = self._session
                silent = (s is not None and
                          not any(c.is_active() for c in s.calls) and
                          time.monotonic() - s.last_seen > self.heartbeat_timeout_s)
            if silent:
                self._end(s, "silent for more than %g s" % self.heartbeat_timeout_s, True)

    def _motion(self, should_stop):
        """Waits for the motion lock unless should_stop() turns true first; True: acquired."""
        while not self._motion_lock.acquire(timeout=0.02):
            if should_stop():
                return False
        return True

    # --- checks and conversions ---------------------------------------------------------------

    def _robot_index(self, index, field="robot"):
        if index >= len(self.robots):
            raise _invalid("%s %d: this cell has robot%s 0%s" % (
                field, index, "s" if len(self.robots) > 1 else "",
                "..%d" % (len(self.robots) - 1) if len(self.robots) > 1 else ""))
        return index

    @staticmethod
    def _finite_vector(values, n, field):
        if len(values) != n:
            raise _invalid("%s has %d values, the robot has %d joints" % (field, len(values), n))
        for i, v in enumerate(values):
            if not math.isfinite(v):
                raise _invalid("%s[%d] is not finite (%r)" % (field, i, v))
        return [float(v) for v in values]

    def _move_result(self, outcome):
        if not isinstance(outcome, MoveOutcome):
            raise TypeError("the driver answered %r, not a MoveOutcome" % (outcome,))
        status = MoveStatus(int(outcome.status))  # ValueError (INTERNAL) for a bad status
        return self.pb.MoveResult(status=int(status), reason=str(outcome.reason or ""),
                                  duration_s=float(outcome.duration_s))

    def _need_camera(self):
        if self.camera is None:
            raise _Refusal(grpc.StatusCode.UNIMPLEMENTED, "this cell has no camera")

    @staticmethod
    def _as_frame(image):
        if isinstance(image, Frame):
            return image
        if hasattr(image, "shape") and hasattr(image, "tobytes"):  # a numpy array
            if len(image.shape) != 3 or image.shape[2] != 3 or str(image.dtype) != "uint8":
                raise ValueError("the camera gave an array of shape %s, %s; not (h, w, 3) uint8"
                                 % (image.shape, image.dtype))
            return Frame(int(image.shape[1]), int(image.shape[0]), image.tobytes())
        width, height, rgb = image
        return Frame(int(width), int(height), bytes(rgb))

    # --- the service: session ---------------------------------------------------------------

    @_rpc
    def Describe(self, request, context):
        r = self.pb.DescribeResponse(
            protocol_version=PROTOCOL_VERSION, cell_name=self.name,
            has_camera=self.camera is not None,
            image_width_px=self.image_size[0], image_height_px=self.image_size[1],
            has_tracker=bool(self.robot.has_tracker), has_handclasp=bool(self.robot.has_handclasp),
            has_clock=bool(self.robot.has_clock), heartbeat_timeout_s=self.heartbeat_timeout_s,
            server=SERVER_NAME)
        for info in self.robots:
            rd = r.robots.add(name=info.name)
            for lo, hi in info.limits_rad:
                rd.joints.add(lower_rad=lo, upper_rad=hi)
        return r

    @_rpc
    def OpenSession(self, request, context):
        with self._lock:
            if self._session is not None:
                raise _Refusal(grpc.StatusCode.FAILED_PRECONDITION,
                               "the cell is held by another session (of %r)" % self._session.client)
            # The client's name as the C++ server keeps it: at most 200 characters.
            s = _Session(secrets.token_hex(16), request.client[:200])
            self._session = s
        log.info("session opened by %r (peer %s)", s.client, context.peer())
        return self.pb.OpenSessionResponse(session_id=s.id,
                                           heartbeat_timeout_s=self.heartbeat_timeout_s)

    @_rpc
    def Heartbeat(self, request, context):
        with self._call(request.session_id, context):
            return self.pb.HeartbeatResponse()

    @_rpc
    def CloseSession(self, request, context):
        with self._call(request.session_id, context) as s:
            # The robots hold where they stand: a motion still in flight is stopped.
            self._end(s, "closed by the client", self._motion_lock.locked())
            return self.pb.CloseSessionResponse()

    @_rpc
    def Stop(self, request, context):
        with self._call(request.session_id, context) as s:
            with self._lock:
                s.stop_count += 1
            self.robot.stop()
            return self.pb.StopResponse()

    # --- motion -------------------------------------------------------------------------------

    def _run_motion(self, s, context, action):
        """Runs action(should_stop) -> MoveOutcome under the motion lock. should_stop turns true
        when the session ends, on Stop, or when this call's client is gone."""
        stops = s.stop_count

        def should_stop():
            return s.ended or s.stop_count != stops or not context.is_active()

        acquired = self._motion(should_stop)
        try:
            if not acquired:
                return self.pb.MoveResult(status=MoveStatus.STOPPED,
                                          reason="stopped before the motion started")
            return self._move_result(action(should_stop))
        finally:
            # A client gone during its motion call (disconnected, killed, or past its deadline)
            # ends its session at once, as the C++ server does, and before the motion lock is
            # released: no motion call of that session may start after it.
            if not context.is_active():
                self._end(s, "its client went away during a motion call", True)
            if acquired:
                self._motion_lock.release()

    @_rpc
    def MoveTo(self, request, context):
        with self._call(request.session_id, context) as s:
            robot = self._robot_index(request.robot)
            limits = self.robots[robot].limits_rad
            q = self._finite_vector(request.q_target_rad, len(limits), "q_target_rad")
            outside = ["joint %d: %.6g rad outside [%.6g, %.6g]" % (j, v, lo, hi)
                       for j, (v, (lo, hi)) in enumerate(zip(q, limits)) if not lo <= v <= hi]
            if outside:
                return self.pb.MoveResult(status=MoveStatus.OUT_OF_LIMITS,
                                          reason="; ".join(outside))
            return self._run_motion(s, context,
                                    lambda should_stop: self.robot.move(robot, q, should_stop))

    @_rpc
    def ReadEncoders(self, request, context):
        with self._call(request.session_id, context):
            robot = self._robot_index(request.robot)
            q = [float(v) for v in self.robot.read_joints(robot)]
            n = len(self.robots[robot].limits_rad)
            if len(q) != n:
                raise ValueError("the driver read %d joints of robot %d, not %d"
                                 % (len(q), robot, n))
            return self.pb.ReadEncodersResponse(q_rad=q)

    @_rpc
    def ExchangeTools(self, request, context):
        with self._call(request.session_id, context) as s:
            self._need_camera()
            return self._run_motion(s, context, lambda _: self.robot.exchange_tools())

    @_rpc
    def CameraRobot(self, request, context):
        with self._call(request.session_id, context):
            self._need_camera()
            robot = int(self.robot.camera_robot())
            if not 0 <= robot < len(self.robots):
                raise ValueError("the driver names camera robot %d" % robot)
            return self.pb.CameraRobotResponse(robot=robot)

    @_rpc
    def JogTipToContact(self, request, context):
        with self._call(request.session_id, context) as s:
            robot = self._robot_index(request.jogged_robot, "jogged_robot")
            return self._run_motion(s, context, lambda _: self.robot.jog_tip_to_contact(robot))

    @_rpc
    def MountTarget(self, request, context):
        with self._call(request.session_id, context) as s:
            # UNSPECIFIED and numbers the proto does not name are malformed.
            try:
                target = BracketTarget(request.target)
            except ValueError:
                raise _invalid("target %d is not a bracket target (1: feature board, 2: "
                               "intrinsics target)" % request.target) from None
            return self._run_motion(s, context, lambda _: self.robot.mount_target(target))

    # --- camera -------------------------------------------------------------------------------

    @_rpc
    def GrabImage(self, request, context):
        with self._call(request.session_id, context):
            self._need_camera()
            fw, fh = self.image_size
            if not request.HasField("region"):
                frame = self._as_frame(self.camera.grab())
                if (frame.width, frame.height) != (fw, fh):
                    raise ValueError("the camera gave %dx%d, it describes %dx%d"
                                     % (frame.width, frame.height, fw, fh))
                x0, y0 = 0, 0
            else:
                reg = request.region
                if reg.width_px <= 0 or reg.height_px <= 0:
                    raise _invalid("the region is %d x %d px; width and height must be > 0"
                                   % (reg.width_px, reg.height_px))
                # Clipped to the frame (Python integers: no overflow at int32's ends).
                x0, y0 = max(reg.x_px, 0), max(reg.y_px, 0)
                x1, y1 = min(reg.x_px + reg.width_px, fw), min(reg.y_px + reg.height_px, fh)
                if x1 <= x0 or y1 <= y0:  # misses the frame: an empty image at the region
                    return self.pb.GrabImageResponse(encoding="png", x_px=reg.x_px,
                                                     y_px=reg.y_px)
                frame = self._grab_region(x0, y0, x1 - x0, y1 - y0)
            data = png.encode(frame.width, frame.height, frame.rgb)
            return self.pb.GrabImageResponse(encoding="png", data=data, width_px=frame.width,
                                             height_px=frame.height, x_px=x0, y_px=y0)

    def _grab_region(self, x, y, w, h):
        got = self.camera.grab_region(x, y, w, h)
        if got is not None:
            frame = self._as_frame(got)
            if (frame.width, frame.height) != (w, h):
                raise ValueError("the camera's region is %dx%d, not %dx%d"
                                 % (frame.width, frame.height, w, h))
            return frame
        full = self._as_frame(self.camera.grab())
        if (full.width, full.height) != self.image_size:
            raise ValueError("the camera gave %dx%d, it describes %dx%d"
                             % ((full.width, full.height) + self.image_size))
        stride = 3 * full.width
        rows = [full.rgb[r * stride + 3 * x:r * stride + 3 * (x + w)] for r in range(y, y + h)]
        return Frame(w, h, b"".join(rows))

    # --- clock, temperature, tracker ------------------------------------------------------------

    @_rpc
    def ReadClock(self, request, context):
        with self._call(request.session_id, context):
            t = float(self.robot.time_s())
            finite = math.isfinite(t)
            return self.pb.ReadClockResponse(has_clock=finite, time_s=t if finite else 0.0)

    @_rpc
    def ReadTemperature(self, request, context):
        with self._call(request.session_id, context):
            robot = self._robot_index(request.robot)
            c = float(self.robot.temperature_c(robot))
            finite = math.isfinite(c)
            return self.pb.ReadTemperatureResponse(has_sensor=finite,
                                                   temperature_deg_c=c if finite else 0.0)

    @_rpc
    def MeasureTracker(self, request, context):
        with self._call(request.session_id, context):
            robot = self._robot_index(request.robot)
            m = self.robot.measure_tracker(robot)
            x, y, z = (float(v) for v in m.p_m)
            return self.pb.MeasureTrackerResponse(
                status=int(m.status), reason=str(m.reason or ""), x_m=x, y_m=y, z_m=z,
                time_s=float(m.time_s))

    # --- running it ---------------------------------------------------------------------------

    def start(self, listen, tls_cert=None, tls_key=None, client_ca=None, token=None,
              max_workers=16):
        """Listens on `listen` (host:port, port 0 picks one) and returns the bound address.
        ConfigError for a configuration that must not start (see check_security)."""
        check_security(listen, tls_cert is not None, client_ca is not None, token is not None)
        interceptors = [TokenInterceptor(token)] if token is not None else []
        server = grpc.server(futures.ThreadPoolExecutor(max_workers=max_workers,
                                                        thread_name_prefix="cell-rpc"),
                             interceptors=interceptors)
        self.pb_grpc.add_CellServicer_to_server(self, server)
        try:
            if tls_cert is not None:
                creds = grpc.ssl_server_credentials([(tls_key, tls_cert)],
                                                    root_certificates=client_ca,
                                                    require_client_auth=client_ca is not None)
                port = server.add_secure_port(listen, creds)
            else:
                port = server.add_insecure_port(listen)
        except RuntimeError as e:
            raise OSError("cannot listen on %s: %s" % (listen, e)) from None
        if not port and not listen.startswith("unix:"):
            raise OSError("cannot listen on %s" % listen)
        server.start()
        self._server = server
        host = listen.rsplit(":", 1)[0] if not listen.startswith("unix:") else listen
        return listen if listen.startswith("unix:") else "%s:%d" % (host, port)

    def shutdown(self, grace=0.5):
        """Stops serving; a session still open is ended and the robots stopped."""
        with self._lock:
            s = self._session
        if s is not None:
            self._end(s, "the server shuts down", True)
        self._halt.set()
        if self._server is not None:
            self._server.stop(grace).wait()

    def wait(self):
        if self._server is not None:
            self._server.wait_for_termination()


class TokenInterceptor(grpc.ServerInterceptor):
    """Requires metadata `authorization: Bearer <token>` on every call (compared in constant
    time), else UNAUTHENTICATED."""

    def __init__(self, token):
        self._expected = b"Bearer " + token.encode("ascii")

        def deny(request, context):
            context.abort(grpc.StatusCode.UNAUTHENTICATED,
                          "missing or wrong bearer token (metadata authorization)")
        self._deny = grpc.unary_unary_rpc_method_handler(deny)

    def intercept_service(self, continuation, handler_call_details):
        got = b""
        for key, value in handler_call_details.invocation_metadata or ():
            if key == "authorization":
                got = value.encode("utf-8", "replace") if isinstance(value, str) else value
                break
        if hmac.compare_digest(got, self._expected):
            return continuation(handler_call_details)
        return self._deny


def is_loopback(listen):
    """True for 127.0.0.0/8, ::1, localhost, and unix sockets in the file system (guarded by
    their file permissions). An abstract unix socket has no permissions: any local user can
    connect, so it is not loopback here."""
    if listen.startswith("unix-abstract:"):
        return False
    if listen.startswith("unix:"):
        return True
    host = listen.rsplit(":", 1)[0] if ":" in listen else listen
    if host.startswith("ipv4:") or host.startswith("ipv6:"):
        host = host[5:]
    host = host.strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def check_security(listen, tls, client_ca, token):
    """ConfigError unless: loopback (plaintext allowed), or TLS with client certificates or a
    token. Client certificates need TLS."""
    if client_ca and not tls:
        raise ConfigError("--client-ca needs TLS (--tls-cert and --tls-key)")
    if not is_loopback(listen) and not (tls and (client_ca or token)):
        raise ConfigError(
            "refusing to listen on %s beyond loopback without TLS and client authentication: "
            "give --tls-cert and --tls-key, and --client-ca or --token-file (plaintext only on "
            "127.0.0.1, ::1 or localhost)" % listen)


def read_token(path):
    with open(path, "r", encoding="ascii", errors="strict") as f:
        token = f.read().strip()
    if not token or any(not (0x21 <= ord(c) <= 0x7E) for c in token):
        raise ConfigError("the token file %s must hold one token of printable ASCII characters "
                          "without spaces" % path)
    return token


def add_arguments(parser):
    """The standard server options (serve_main parses them)."""
    parser.add_argument("--listen", default="127.0.0.1:50051",
                        help="host:port to listen on (port 0: any free port; default %(default)s)")
    parser.add_argument("--tls-cert", help="server certificate chain (PEM): serve TLS")
    parser.add_argument("--tls-key", help="server private key (PEM)")
    parser.add_argument("--client-ca", help="CA certificates (PEM): require and verify client "
                        "certificates signed by them")
    parser.add_argument("--token-file", help="file holding a token: require metadata "
                        "'authorization: Bearer <token>'")
    parser.add_argument("--heartbeat-timeout", type=float, default=2.0, metavar="S",
                        help="end a session silent for longer than this (default %(default)s s)")


def _read_bytes(path, what):
    try:
        with open(path, "rb") as f:
            return f.read()
    except OSError as e:
        raise ConfigError("cannot read the %s %s: %s" % (what, path, e.strerror)) from None


def serve_main(make_drivers, argv=None, description=None, add_extra_arguments=None):
    """A server program: parses the standard options (and the extras), makes the drivers with
    make_drivers(args) -> (RobotDriver, CameraDriver or None), serves until SIGINT/SIGTERM.
    Prints `listening on HOST:PORT` on stdout once listening. Exit 2: a configuration that must
    not start."""
    parser = argparse.ArgumentParser(description=description)
    add_arguments(parser)
    if add_extra_arguments:
        add_extra_arguments(parser)
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, stream=sys.stderr,
                        format="%(asctime)s %(name)s: %(message)s")
    try:
        if (args.tls_cert is None) != (args.tls_key is None):
            raise ConfigError("--tls-cert and --tls-key go together")
        tls_cert = _read_bytes(args.tls_cert, "certificate") if args.tls_cert else None
        tls_key = _read_bytes(args.tls_key, "key") if args.tls_key else None
        client_ca = _read_bytes(args.client_ca, "client CA") if args.client_ca else None
        token = read_token(args.token_file) if args.token_file else None
        check_security(args.listen, tls_cert is not None, client_ca is not None,
                       token is not None)
        robot, camera = make_drivers(args)
        cell = CellServer(robot, camera, heartbeat_timeout_s=args.heartbeat_timeout)
        address = cell.start(args.listen, tls_cert, tls_key, client_ca, token)
    except (ConfigError, OSError) as e:
        print("error: %s" % e, file=sys.stderr)
        return 2 if isinstance(e, ConfigError) else 1
    print("listening on %s" % address, flush=True)
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: done.set())
    done.wait()
    cell.shutdown()
    return 0


def _load_factory(spec):
    import importlib
    module, _, name = spec.partition(":")
    return getattr(importlib.import_module(module), name or "make_drivers")


if __name__ == "__main__":
    # python3 -m twinbench_cell.server --driver MODULE[:FACTORY] [options]: FACTORY(args) gives
    # (RobotDriver, CameraDriver or None); default name make_drivers.
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--driver", required=True)
    known, rest = pre.parse_known_args()
    sys.path.insert(0, os.getcwd())
    sys.exit(serve_main(_load_factory(known.driver), rest,
                        description="A twinbench cell server over a Python driver."))
