"""TLS with client certificates, the bearer token, and the refusal to serve beyond loopback
without both TLS and client authentication (throwaway certificates from the openssl CLI)."""
import os
import subprocess
import tempfile
import unittest

import grpc

from helpers import FAKE, PYTHON, FakeCell, make_certificates
from twinbench_cell.client import RemoteCell

UNAUTHENTICATED = grpc.StatusCode.UNAUTHENTICATED
TOKEN = "s3cr3t-token-of-the-test-0123456789"


class SecurityTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.certs = make_certificates(cls.tmp.name)
        if cls.certs is None:
            raise unittest.SkipTest("no openssl")
        cls.token_file = os.path.join(cls.tmp.name, "token")
        with open(cls.token_file, "w") as f:
            f.write(TOKEN + "\n")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def tls(self):
        return ["--tls-cert", self.certs["server.crt"], "--tls-key", self.certs["server.key"]]

    def describe(self, address, **kw):
        """The cell's name, or the status code of the refusal."""
        cell = RemoteCell(address, open_session=False, timeout_s=5, **kw)
        try:
            return cell.describe().cell_name
        except grpc.RpcError as e:
            return e.code()
        finally:
            cell.close()

    def test_client_certificates_are_required_with_client_ca(self):
        cell = FakeCell(*self.tls(), "--client-ca", self.certs["ca.crt"])
        try:
            ca = self.certs["ca.crt"]
            # No client certificate, or one from a CA the server does not trust: no handshake.
            self.assertEqual(self.describe(cell.address, ca_cert=ca), grpc.StatusCode.UNAVAILABLE)
            self.assertEqual(self.describe(cell.address, ca_cert=ca,
                                           client_cert=self.certs["stranger.crt"],
                                           client_key=self.certs["stranger.key"]),
                             grpc.StatusCode.UNAVAILABLE)
            # Plaintext to a TLS server: no answer either.
            self.assertEqual(self.describe(cell.address), grpc.StatusCode.UNAVAILABLE)
            with RemoteCell(cell.address, ca_cert=ca, client_cert=self.certs["client.crt"],
                            client_key=self.certs["client.key"]) as remote:
                self.assertIn("fake", remote.describe().cell_name)
                self.assertEqual(len(remote.read_encoders(0)), 6)
        finally:
            cell.close()

    def test_the_token_is_required_with_token_file(self):
        cell = FakeCell(*self.tls(), "--token-file", self.token_file)
        try:
            ca = self.certs["ca.crt"]
            self.assertEqual(self.describe(cell.address, ca_cert=ca), UNAUTHENTICATED)
            wrong = TOKEN[:-1] + ("x" if TOKEN[-1] != "x" else "y")  # same length, one off
            for token in (wrong, TOKEN[:-1], TOKEN + "9", "Bearer " + TOKEN):
                self.assertEqual(self.describe(cell.address, ca_cert=ca, token=token),
                                 UNAUTHENTICATED, token)
            with self.assertRaises(grpc.RpcError) as e:
                RemoteCell(cell.address, ca_cert=ca, token=wrong).open()
            self.assertEqual(e.exception.code(), UNAUTHENTICATED)
            with RemoteCell(cell.address, ca_cert=ca, token=TOKEN) as remote:
                self.assertEqual(len(remote.read_encoders(1)), 6)
        finally:
            cell.close()

    def run_server(self, *args):
        return subprocess.run([PYTHON, FAKE, *args], capture_output=True, text=True, timeout=30)

    def test_refuses_to_serve_beyond_loopback_without_tls_and_client_auth(self):
        for args in ([],                                             # plaintext
                     self.tls(),                                     # TLS, anyone may call
                     ["--token-file", self.token_file]):             # a token in plaintext
            run = self.run_server("--listen", "0.0.0.0:0", *args)
            self.assertEqual(run.returncode, 2, args)
            self.assertIn("refusing to listen on 0.0.0.0:0", run.stderr)
            self.assertEqual(run.stdout, "")
        # An abstract unix socket has no file permissions: any local user reaches it.
        run = self.run_server("--listen", "unix-abstract:twinbench-test-%d" % os.getpid())
        self.assertEqual(run.returncode, 2)
        self.assertIn("refusing to listen on unix-abstract:", run.stderr)
        # Client certificates need TLS, on loopback too; half a key pair is refused.
        run = self.run_server("--listen", "127.0.0.1:0", "--client-ca", self.certs["ca.crt"])
        self.assertEqual(run.returncode, 2)
        run = self.run_server("--listen", "127.0.0.1:0", "--tls-cert", self.certs["server.crt"])
        self.assertEqual(run.returncode, 2)

    def test_serves_beyond_loopback_with_tls_and_a_token(self):
        cell = FakeCell(*self.tls(), "--token-file", self.token_file, listen="0.0.0.0:0")
        try:
            self.assertIn("fake", self.describe(cell.address, ca_cert=self.certs["ca.crt"],
                                                token=TOKEN))
        finally:
            cell.close()


if __name__ == "__main__":
    unittest.main()
