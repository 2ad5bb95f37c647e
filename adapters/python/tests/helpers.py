"""Shared by the adapter's tests: the fake cell as a subprocess, stubs, throwaway certificates."""
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time

ADAPTER = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ADAPTER)
FAKE = os.path.join(ADAPTER, "fake_hardware.py")
PYTHON = sys.executable

import grpc  # noqa: E402

from twinbench_cell import stubs  # noqa: E402

pb, pb_grpc = stubs.load()

# The heartbeat timeout the tests' servers run with [s], and what they allow beyond it for the
# watchdog's period and a loaded machine.
HEARTBEAT_S = 0.6
MARGIN_S = 1.5


class FakeCell:
    """fake_hardware.py on a free loopback port (or `listen`); .address, .stderr_text()."""

    def __init__(self, *args, heartbeat_s=HEARTBEAT_S, listen="127.0.0.1:0"):
        self._err = tempfile.TemporaryFile(mode="w+")
        self.proc = subprocess.Popen(
            [PYTHON, FAKE, "--listen", listen, "--heartbeat-timeout", str(heartbeat_s)] +
            list(args), stdout=subprocess.PIPE, stderr=self._err, text=True)
        ready, _, _ = select.select([self.proc.stdout], [], [], 30)
        line = self.proc.stdout.readline() if ready else ""
        if not line.startswith("listening on "):
            self.close()
            raise RuntimeError("the fake cell did not start: %r\n%s" % (line, self.stderr_text()))
        self.port = int(line.split()[-1].rsplit(":", 1)[1])
        self.address = "127.0.0.1:%d" % self.port

    def stderr_text(self):
        if not self._err.closed:
            self._err.seek(0)
            self._stderr = self._err.read()
        return self._stderr

    def close(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc.stdout.close()
        self.stderr_text()
        self._err.close()


def stub(address):
    channel = grpc.insecure_channel(address)
    return channel, pb_grpc.CellStub(channel)


def code_of(call, *args, **kwargs):
    """The status code of a call (OK when it answers) and the answer (None on error)."""
    try:
        return grpc.StatusCode.OK, call(*args, **kwargs)
    except grpc.RpcError as e:
        return e.code(), None


def wait_for(predicate, timeout_s, period_s=0.05):
    """Polls predicate() until it is true or timeout_s passes; returns the time it took or None."""
    t0 = time.monotonic()
    while time.monotonic() - t0 <= timeout_s:
        if predicate():
            return time.monotonic() - t0
        time.sleep(period_s)
    return None


def make_certificates(folder):
    """A CA, a server certificate for localhost / 127.0.0.1 and a client certificate signed by
    it, and a second CA with a client certificate of its own (a stranger), made with the
    openssl CLI; returns {name: path}. None without openssl."""
    if shutil.which("openssl") is None:
        return None
    p = {n: os.path.join(folder, n) for n in (
        "ca.key", "ca.crt", "server.key", "server.crt", "client.key", "client.crt",
        "other_ca.key", "other_ca.crt", "stranger.key", "stranger.crt", "server.ext")}
    with open(p["server.ext"], "w") as f:
        f.write("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    ec = ["-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes"]

    def run(*cmd):
        subprocess.run(("openssl",) + cmd, check=True, capture_output=True)

    for ca in ("ca", "other_ca"):
        run("req", "-x509", *ec, "-keyout", p[ca + ".key"], "-out", p[ca + ".crt"],
            "-days", "2", "-subj", "/CN=twinbench test " + ca)
    for name, ca, ext in (("server", "ca", ["-extfile", p["server.ext"]]),
                          ("client", "ca", []), ("stranger", "other_ca", [])):
        csr = os.path.join(folder, name + ".csr")
        run("req", *ec, "-keyout", p[name + ".key"], "-out", csr, "-subj", "/CN=" + name)
        run("x509", "-req", "-in", csr, "-CA", p[ca + ".crt"], "-CAkey", p[ca + ".key"],
            "-CAcreateserial", "-out", p[name + ".crt"], "-days", "2", *ext)
    return p
