#!/usr/bin/python3
"""Runs the Python adapter's tests (stdlib unittest); exit 77 (skipped) when grpc, protobuf,
protoc or grpc_python_plugin are missing for this interpreter (Debian: python3-grpcio
python3-protobuf protobuf-compiler protobuf-compiler-grpc). ctest: test python_adapter."""
import os
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))



def skip(why):
    print("skipped: %s" % why)
    sys.exit(77)


try:
    import grpc  # noqa: F401
    import google.protobuf  # noqa: F401
except ImportError as e:
    skip(e)
from twinbench_cell import stubs  # noqa: E402
try:
    stubs.generate()
except stubs.StubError as e:
    skip(e)

suite = unittest.defaultTestLoader.discover(HERE, pattern="test_*.py", top_level_dir=HERE)
result = unittest.TextTestRunner(verbosity=2).run(suite)
sys.exit(0 if result.wasSuccessful() else 1)
