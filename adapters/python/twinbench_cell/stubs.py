"""The Python stubs of proto/twinbench/cell/v1/cell.proto, generated at use time (never committed).

load() runs protoc with the gRPC Python plugin into a cache folder keyed by the proto's content
(a changed proto regenerates) and imports the two modules from there.

Where things are found (environment variables override the defaults):
- TWINBENCH_PROTO_DIR: the proto root holding twinbench/cell/v1/cell.proto
  (default: the repository's proto/, two folders above this package).
- TWINBENCH_PY_GEN: the cache folder (default: adapters/python/build/gen when writable, else
  $XDG_CACHE_HOME/twinbench/py-gen, else a folder in the system's temporary directory).
- TWINBENCH_PROTOC, TWINBENCH_GRPC_PYTHON_PLUGIN: the programs (default: protoc on PATH and
  /usr/bin/grpc_python_plugin, or grpc_python_plugin on PATH).
"""
import hashlib
import importlib
import os
import shutil
import subprocess
import sys
import tempfile
import threading

PROTO_REL = os.path.join("twinbench", "cell", "v1", "cell.proto")
_ADAPTER_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_lock = threading.Lock()
_loaded = None


class StubError(RuntimeError):
    """The stubs cannot be generated (no proto, no protoc or plugin, protoc failed)."""


def proto_dir():
    d = os.environ.get("TWINBENCH_PROTO_DIR") or os.path.join(
        os.path.dirname(os.path.dirname(_ADAPTER_DIR)), "proto")
    if not os.path.isfile(os.path.join(d, PROTO_REL)):
        raise StubError("no %s under %s (set TWINBENCH_PROTO_DIR to the proto root)"
                        % (PROTO_REL, d))
    return d


def _writable_dir(path):
    try:
        os.makedirs(path, exist_ok=True)
        return os.access(path, os.W_OK)
    except OSError:
        return False


def cache_root():
    env = os.environ.get("TWINBENCH_PY_GEN")
    if env:
        os.makedirs(env, exist_ok=True)
        return env
    candidates = [os.path.join(_ADAPTER_DIR, "build", "gen")]
    xdg = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    candidates.append(os.path.join(xdg, "twinbench", "py-gen"))
    candidates.append(os.path.join(tempfile.gettempdir(), "twinbench-py-gen-%d" % os.getuid()))
    for c in candidates:
        if _writable_dir(c):
            return c
    raise StubError("no writable cache folder for the generated stubs (set TWINBENCH_PY_GEN)")


def tools():
    """(protoc, grpc_python_plugin) paths, or StubError naming what is missing."""
    protoc = os.environ.get("TWINBENCH_PROTOC") or shutil.which("protoc")
    plugin = os.environ.get("TWINBENCH_GRPC_PYTHON_PLUGIN")
    if not plugin:
        plugin = "/usr/bin/grpc_python_plugin"
        if not os.access(plugin, os.X_OK):
            plugin = shutil.which("grpc_python_plugin")
    if not protoc or not os.access(protoc, os.X_OK):
        raise StubError("protoc not found (%s; Debian: apt-get install protobuf-compiler)"
                        % (protoc or "not on PATH"))
    if not plugin or not os.access(plugin, os.X_OK):
        raise StubError("grpc_python_plugin not found (%s; Debian: apt-get install "
                        "protobuf-compiler-grpc)" % (plugin or "not on PATH"))
    return protoc, plugin


def generate(out_dir=None):
    """Generates the stubs (if not there yet) and returns the folder to put on sys.path."""
    src = proto_dir()
    with open(os.path.join(src, PROTO_REL), "rb") as f:
        digest = hashlib.sha256(f.read()).hexdigest()[:16]
    root = out_dir or cache_root()
    os.makedirs(root, exist_ok=True)
    target = os.path.join(root, digest)
    if os.path.isfile(os.path.join(target, "twinbench", "cell", "v1", "cell_pb2_grpc.py")):
        return target
    protoc, plugin = tools()
    # Generated into a private folder and renamed into place: processes started together
    # (a test's servers and clients) never import half-written files.
    tmp = tempfile.mkdtemp(prefix=".gen-", dir=root)
    cmd = [protoc, "--python_out=" + tmp, "--grpc_out=" + tmp,
           "--plugin=protoc-gen-grpc=" + plugin, "-I", src, os.path.join(src, PROTO_REL)]
    try:
        run = subprocess.run(cmd, capture_output=True, text=True)
        failure = run.stderr if run.returncode != 0 else None
    except OSError as e:
        failure = str(e)
    if failure is not None:
        shutil.rmtree(tmp, ignore_errors=True)
        raise StubError("protoc failed (%s):\n%s" % (" ".join(cmd), failure))
    try:
        os.rename(tmp, target)
    except OSError:  # another process was faster: its copy is the same
        shutil.rmtree(tmp, ignore_errors=True)
    return target


def load():
    """(cell_pb2, cell_pb2_grpc), generated and imported once per process."""
    global _loaded
    with _lock:
        if _loaded is None:
            path = generate()
            if path not in sys.path:
                sys.path.insert(0, path)
            pb2 = importlib.import_module("twinbench.cell.v1.cell_pb2")
            pb2_grpc = importlib.import_module("twinbench.cell.v1.cell_pb2_grpc")
            _loaded = (pb2, pb2_grpc)
        return _loaded


if __name__ == "__main__":
    print(generate(sys.argv[1] if len(sys.argv) > 1 else None))
