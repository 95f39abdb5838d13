"""The real fremend for the package's tests, as tests/fremend_fixture.h runs it for the C++ ones.

FremendProcess.start() runs $FREMEND_BINARY with --listen 127.0.0.1:0 (any free port; or a given
address, to restart a daemon where its clients expect it) --data-dir <dir> (plus the test's
arguments), its output to a log file beside the data directory, learns the port from the
line "fremend listening on HOST:PORT, ..." and returns once grpc.health.v1.Health says SERVING.
stop() sends SIGTERM and returns the exit code. DaemonTestCase starts one daemon on a fresh
temporary directory per test and stops it after the test, expecting exit code 0; with tokens
and/or TLS (a self-signed certificate made with openssl) when the test class asks for them.
"""

import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
import unittest

import grpc

import fremen

START_TIMEOUT = 60.0
STOP_TIMEOUT = 60.0
POLL_INTERVAL = 0.02
_LISTENING = re.compile(r"fremend listening on ([^,\s]+),")
# grpc.health.v1.HealthCheckResponse{status: SERVING}, serialized: field 1 (varint) = 1. The
# health protos are not part of Debian's python3-grpcio, and this is all the harness needs.
_SERVING = b"\x08\x01"


def fremend_binary():
    binary = os.environ.get("FREMEND_BINARY")
    if not binary:
        raise unittest.SkipTest("FREMEND_BINARY is not set (ctest sets it to the built fremend)")
    return binary


class FremendProcess:
    def __init__(self, process, log_path):
        self.process = process
        self.log_path = log_path
        self.address = None

    @classmethod
    def start(cls, data_dir, args=(), tls_root=None, listen="127.0.0.1:0"):
        """tls_root: the PEM file of the daemon's certificate when it serves TLS."""
        log_path = f"{data_dir}.fremend-{time.monotonic_ns()}.log"
        with open(log_path, "wb") as log:
            process = subprocess.Popen(
                [fremend_binary(), "--listen", listen, "--http-listen", "127.0.0.1:0",
                 "--data-dir", data_dir, *args],
                stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        daemon = cls(process, log_path)
        try:
            daemon._await_serving(tls_root)
        except Exception:
            daemon.kill()
            raise
        return daemon

    def log(self):
        with open(self.log_path, "r", errors="replace") as log:
            return log.read()

    def _await_serving(self, tls_root):
        deadline = time.monotonic() + START_TIMEOUT
        while self.address is None:
            match = _LISTENING.search(self.log())
            if match:
                self.address = match.group(1)
            elif self.process.poll() is not None:
                raise RuntimeError(f"fremend exited with code {self.process.returncode}:\n{self.log()}")
            elif time.monotonic() > deadline:
                raise RuntimeError(f"fremend did not say where it listens:\n{self.log()}")
            else:
                time.sleep(POLL_INTERVAL)
        if tls_root:
            with open(tls_root, "rb") as pem:
                channel = grpc.secure_channel(self.address, grpc.ssl_channel_credentials(pem.read()))
        else:
            channel = grpc.insecure_channel(self.address)
        with channel:
            check = channel.unary_unary("/grpc.health.v1.Health/Check")
            while True:
                try:
                    if check(b"", timeout=5) == _SERVING:
                        return
                except grpc.RpcError:
                    pass
                if time.monotonic() > deadline:
                    raise RuntimeError(f"fremend at {self.address} never became SERVING:\n{self.log()}")
                time.sleep(POLL_INTERVAL)

    def stop(self):
        """SIGTERM, then waits; the exit code (negative: killed by a signal)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(STOP_TIMEOUT)
            except subprocess.TimeoutExpired:
                self.kill()
        return self.process.returncode

    def pause(self):
        """SIGSTOP, then waits until every thread of the daemon has stopped: the signal only marks
        the process, and a thread running on another core goes on until it is interrupted (long
        enough to read and log a batch sent just after kill() returned)."""
        os.kill(self.process.pid, signal.SIGSTOP)
        deadline = time.monotonic() + STOP_TIMEOUT
        task_dir = "/proc/%d/task" % self.process.pid
        while True:
            states = []
            for task in os.listdir(task_dir):
                try:
                    with open(os.path.join(task_dir, task, "stat")) as stat:
                        # The state follows the command name in parentheses, which may hold spaces.
                        states.append(stat.read().rsplit(")", 1)[1].split()[0])
                except FileNotFoundError:  # a thread that has just exited
                    pass
            if states and all(state in ("T", "t") for state in states):
                return
            if time.monotonic() > deadline:
                raise AssertionError("fremend's threads did not all stop: states %s" % states)
            time.sleep(POLL_INTERVAL)

    def kill(self):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


class DaemonTestCase(unittest.TestCase):
    """A fresh daemon per test (self.daemon, self.client), stopped after it with exit code 0."""

    # Bearer tokens the daemon accepts, as "ROLE:TOKEN" lines (ROLE read or write); none = no
    # authentication. self.client sends `token`.
    tokens = ()
    token = None
    # Serve TLS with a fresh self-signed certificate for 127.0.0.1 (self.certificate), which
    # self.client trusts.
    tls = False

    def setUp(self):
        self._dir = tempfile.TemporaryDirectory(prefix="fremen_python.")
        self.addCleanup(self._dir.cleanup)
        args = []
        if self.tokens:
            args += ["--tokens-file", self.write("tokens", "\n".join(self.tokens) + "\n")]
        self.certificate = None
        if self.tls:
            self.certificate = self.make_certificate()
            args += ["--tls-cert-file", self.certificate, "--tls-key-file", self.path("key.pem")]
        self._daemon_args = args
        self.daemon = FremendProcess.start(self.path("data"), args, tls_root=self.certificate)
        self.addCleanup(self.stop_daemon)
        self.client = self.connect(token=self.token, tls=self.certificate)

    def restart_daemon(self, same_port=False):
        """A new daemon on the same data directory (after the old one stopped or was killed). On a
        new port, and self.client a new client of it; or with `same_port`, where the old one
        listened, so that the clients connected to the old one reach it."""
        listen = self.daemon.address if same_port else "127.0.0.1:0"
        self.daemon = FremendProcess.start(self.path("data"), self._daemon_args, tls_root=self.certificate,
                                           listen=listen)
        if not same_port:
            self.client = self.connect(token=self.token, tls=self.certificate)

    def write(self, name, text):
        with open(self.path(name), "w") as out:
            out.write(text)
        return self.path(name)

    def make_certificate(self):
        if shutil.which("openssl") is None:
            self.skipTest("no openssl to make a test certificate")
        made = subprocess.run(
            ["openssl", "req", "-x509", "-newkey", "ec", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-nodes",
             "-days", "1", "-subj", "/CN=localhost", "-addext", "subjectAltName=IP:127.0.0.1,DNS:localhost",
             "-keyout", self.path("key.pem"), "-out", self.path("cert.pem")],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
        if made.returncode != 0:
            self.skipTest("openssl cannot make a test certificate")
        return self.path("cert.pem")

    def path(self, name):
        """A path in the test's temporary directory."""
        return os.path.join(self._dir.name, name)

    def connect(self, **kwargs):
        client = fremen.connect(self.daemon.address, **kwargs)
        self.addCleanup(client.close)
        return client

    def stop_daemon(self):
        if self.daemon.process.poll() is None:
            code = self.daemon.stop()
            self.assertEqual(code, 0, self.daemon.log())
