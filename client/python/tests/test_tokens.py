"""Bearer tokens and TLS through fremen.connect(token=..., tls=...) against a real fremend: a read
token may query but not write (PermissionDenied), no token is Unauthenticated, a write token may do
everything, and a TLS daemon is reached with its certificate as the root."""

import unittest

import grpc

import fremen
from fremend_process import DaemonTestCase

T = 1.7e9


class TokensTest(DaemonTestCase):
    tokens = ("read:reader-token", "write:writer-token")
    token = "writer-token"

    def test_a_write_token_may_write_and_read(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            session.send(T, [1], names=["a"])
            (ack,) = session.wait()
        self.assertEqual(ack.accepted, 1)
        self.assertEqual(self.client.predict("doors", T, names=["a"]).probabilities[0, 0], 1.0)

    def test_a_read_token_may_read_but_not_write(self):
        self.client.create_map("doors")
        reader = self.connect(token="reader-token")
        self.assertEqual([m.name for m in reader.list_maps()], ["doors"])
        self.assertEqual(reader.predict("doors", T, names=["a"]).unobserved, [0])
        with self.assertRaises(fremen.PermissionDenied) as raised:
            reader.create_map("lab")
        self.assertEqual(raised.exception.code, grpc.StatusCode.PERMISSION_DENIED)
        self.assertIn("needs a write token", raised.exception.message)
        session = reader.ingest("doors")
        # The daemon refuses the stream as it opens: the refusal may beat the first batch.
        with self.assertRaises(fremen.PermissionDenied):
            session.send(T, [1], names=["a"])
            session.close()

    def test_no_token_or_an_unknown_one_is_unauthenticated(self):
        for token in (None, "guess"):
            client = self.connect(token=token)
            with self.assertRaises(fremen.Unauthenticated) as raised:
                list(client.list_maps())
            self.assertEqual(raised.exception.code, grpc.StatusCode.UNAUTHENTICATED)


class TlsTest(DaemonTestCase):
    tls = True

    def test_tls_with_the_daemons_certificate(self):
        self.client.create_map("doors")
        self.assertEqual([m.name for m in self.client.list_maps()], ["doors"])
        plaintext = self.connect(timeout=5)
        with self.assertRaises(fremen.Unavailable):
            plaintext.get_map("doors")


if __name__ == "__main__":
    unittest.main()
