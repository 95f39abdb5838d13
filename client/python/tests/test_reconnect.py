"""Reconnection after UNAVAILABLE against a real fremend that the test restarts on the same data
directory and port: an ingest session that keeps sending through the restart resumes by itself and
every batch is answered once and applied exactly once (observation counts); unary reads retry until
the daemon is back; and the bounds: a daemon that stays away ends in fremen.Unavailable (the
unanswered batches kept for a manual resend), as do calls that are not retried. StuckStreamTest
injects the one fault a real daemon cannot cause: a stream whose call ended while gRPC's response
iterator waits for ever; the session abandons it and resumes (or fails, without resume)."""

import threading
import time
import unittest

import grpc

import fremen
from fremen import ingest
from fremend_process import DaemonTestCase

T = 1.7e9
NAMES = ["a", "b"]  # two observations a batch
AFTER_RESTART = 100  # batches sent after the daemon is back


class ReconnectTest(DaemonTestCase):
    def restart_in_background(self, how):
        """Stops the daemon (SIGTERM, or SIGKILL: batches durable but never answered) and starts
        another on the same data directory and port, in a thread the test joins."""
        def restart():
            if how == "kill":
                self.daemon.kill()
            else:
                self.assertEqual(self.daemon.stop(), 0, self.daemon.log())
            time.sleep(0.3)  # a while with no daemon at all: connections refused
            self.restart_daemon(same_port=True)
        thread = threading.Thread(target=restart)
        thread.start()
        return thread

    def ingest_through_a_restart(self, how):
        self.client.create_map("doors")
        session = self.client.ingest("doors", writer_id=77, max_in_flight=16)
        sent = 0
        for _ in range(200):  # before the restart
            session.send(T + sent, [sent % 2, 1], names=NAMES)
            sent += 1
        restarter = self.restart_in_background(how)
        while restarter.is_alive():  # through it: send() blocks while 16 batches are unanswered
            session.send(T + sent, [sent % 2, 1], names=NAMES)
            sent += 1
        restarter.join()
        for _ in range(AFTER_RESTART):
            session.send(T + sent, [sent % 2, 1], names=NAMES)
            sent += 1
        acks = session.close(timeout=120)

        self.assertGreaterEqual(session.reconnects, 1)
        self.assertEqual([a.sequence for a in acks], list(range(1, sent + 1)))  # each answered once
        self.assertTrue(all(a.ok for a in acks))
        applied = [a for a in acks if not a.duplicate]
        self.assertTrue(all(a.accepted == 2 for a in applied))
        self.assertTrue(all(a.accepted == 0 for a in acks if a.duplicate))
        # Exactly once: every batch applied once, whether answered before or after the restart.
        stats = self.client.stats("doors")
        self.assertEqual(stats.observations, 2 * sent)
        self.assertEqual(self.client.model("doors", name="a").observations, sent)
        return acks

    def test_an_ingest_session_resumes_through_a_graceful_restart(self):
        self.ingest_through_a_restart("stop")

    def test_an_ingest_session_resumes_through_a_crash(self):
        self.ingest_through_a_restart("kill")

    def test_reads_retry_until_the_daemon_is_back(self):
        self.client.create_map("doors")
        self.assertEqual(self.daemon.stop(), 0)
        restarter = threading.Thread(target=lambda: (time.sleep(1.0), self.restart_daemon(same_port=True)))
        restarter.start()
        try:
            started = time.monotonic()
            self.assertEqual(self.client.get_map("doors").name, "doors")  # retried while the daemon is away
            self.assertGreater(time.monotonic() - started, 0.5)
            self.assertEqual(self.client.stats("doors").observations, 0)
        finally:
            restarter.join()

    def test_calls_not_retried_and_bounds_end_in_unavailable(self):
        self.client.create_map("doors")
        patient = self.connect(reconnect=fremen.Backoff(initial=1.0, maximum=1.0, max_attempts=100))
        brief = self.connect(reconnect=fremen.Backoff(initial=0.1, multiplier=2, jitter=0, max_attempts=3))
        no_retries = self.connect(reconnect=None)
        self.assertEqual(self.daemon.stop(), 0)
        started = time.monotonic()
        with self.assertRaises(fremen.Unavailable):
            patient.create_map("other")  # not idempotent: one try only
        with self.assertRaises(fremen.Unavailable):
            patient.delete_map("doors")
        with self.assertRaises(fremen.Unavailable):
            no_retries.stats("doors")
        # Retried, they would go on for 30 s (`patient` pauses up to 1 s each, max_elapsed 30 s).
        self.assertLess(time.monotonic() - started, 5.0)
        started = time.monotonic()
        with self.assertRaises(fremen.Unavailable):
            brief.stats("doors")
        self.assertGreaterEqual(time.monotonic() - started, 0.3)  # two pauses: 0.1 + 0.2 s
        self.restart_daemon()

    def test_an_ingest_session_gives_up_when_the_daemon_stays_away(self):
        self.client.create_map("doors")
        brief = self.connect(reconnect=fremen.Backoff(initial=0.05, max_attempts=3))
        session = brief.ingest("doors", writer_id=5)
        for i in range(5):
            session.send(T + i, [1], names=["a"])
        self.assertEqual(len(session.wait()), 5)
        self.daemon.pause()  # answers nothing from now on
        for i in range(5, 8):
            session.send(T + i, [1], names=["a"])
        self.daemon.kill()
        with self.assertRaises(fremen.Unavailable):
            session.wait(timeout=30)
        self.assertEqual(session.reconnects, 0)  # no new stream while the daemon is away
        self.assertEqual([b.sequence for b in session.unanswered()], [6, 7, 8])
        with self.assertRaises(fremen.Unavailable):
            session.close()

        self.restart_daemon()  # then the manual form: a new session resends them
        with self.client.ingest("doors", writer_id=5) as resumed:
            resumed.resend(session.unanswered())
            self.assertEqual([a.sequence for a in resumed.wait()], [6, 7, 8])
        self.assertEqual(self.client.stats("doors").observations, 8)

    def test_a_session_without_resume_fails_at_once(self):
        self.client.create_map("doors")
        session = self.client.ingest("doors", resume=False)
        session.send(T, [1], names=["a"])
        self.assertEqual(len(session.wait()), 1)
        self.assertEqual(self.daemon.stop(), 0)
        with self.assertRaises(fremen.Unavailable):
            session.send(T + 1, [1], names=["a"])
            session.wait(timeout=30)
        self.assertEqual(session.reconnects, 0)
        self.restart_daemon()


class StuckCall:
    """Fault injection: an Ingest call that ended with UNAVAILABLE while its response iterator waits
    for ever, as python3-grpcio 1.51's sometimes does for a call that fails at once."""

    def __iter__(self):
        return self

    def __next__(self):
        threading.Event().wait()

    def add_done_callback(self, callback):
        callback(self)

    def code(self):
        return grpc.StatusCode.UNAVAILABLE

    def details(self):
        return "failed to connect to all addresses"

    def cancel(self):
        return False


class FirstStreamStuck:
    """The client's IngestService stub, whose first stream is a StuckCall."""

    def __init__(self, stub):
        self.stub = stub
        self.streams = 0

    def Ingest(self, requests, metadata=None, timeout=None):  # noqa: N802 (the stub's name)
        self.streams += 1
        if self.streams == 1:
            return StuckCall()
        return self.stub.Ingest(requests, metadata=metadata, timeout=timeout)

    def __getattr__(self, name):  # the stub's other methods (LastSequence), unchanged
        return getattr(self.stub, name)


class StuckStreamTest(DaemonTestCase):
    def setUp(self):
        super().setUp()
        grace, ingest.STUCK_GRACE = ingest.STUCK_GRACE, 0.2
        self.addCleanup(setattr, ingest, "STUCK_GRACE", grace)
        self.client.create_map("doors")
        self.client._ingest = FirstStreamStuck(self.client._ingest)

    def test_a_stuck_stream_is_abandoned_and_its_batches_resent(self):
        session = self.client.ingest("doors", writer_id=3)
        for i in range(3):
            session.send(T + i, [1], names=["a"])
        acks = session.wait(timeout=30)
        self.assertEqual([(a.sequence, a.accepted, a.duplicate) for a in acks],
                         [(1, 1, False), (2, 1, False), (3, 1, False)])
        self.assertEqual(session.reconnects, 1)
        self.assertEqual(self.client.stats("doors").observations, 3)
        session.close()

    def test_without_resume_a_stuck_stream_fails_with_its_status(self):
        session = self.client.ingest("doors", resume=False)
        session.send(T, [1], names=["a"])
        with self.assertRaises(fremen.Unavailable) as raised:
            session.wait(timeout=30)
        self.assertIn("failed to connect", raised.exception.message)
        self.assertEqual(len(session.unanswered()), 1)


if __name__ == "__main__":
    unittest.main()
