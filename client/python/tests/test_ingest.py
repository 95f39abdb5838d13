"""Client.ingest sessions against a real fremend: batches of every kind and their acknowledgements
(accepted and rejected counts with reasons), batches refused as a whole, retries recognised as
duplicates, a writer that lost its count, many batches in flight, a stream that fails, and a
message the daemon cannot parse."""

import math
import unittest

import grpc

import fremen
from fremen.ingest import IngestSession
from fremen.v1 import ingest_pb2
from fremend_process import DaemonTestCase

T = 1.7e9


class IngestTest(DaemonTestCase):
    def test_generic_states_by_id_and_by_name_are_acknowledged(self):
        self.client.create_map("doors")
        with self.client.ingest("doors", writer_id=7) as session:
            self.assertEqual(session.send(T, [1, 0, 1], ids=[1, 2, 3], groups=["hall", "hall", "lab"]), 1)
            self.assertEqual(session.send(T + 60, [0, 1], names=["front", "back"]), 2)
            acks = session.wait()
        self.assertEqual([(a.sequence, a.accepted, a.rejected, a.duplicate, a.ok) for a in acks],
                         [(1, 3, 0, False, True), (2, 2, 0, False, True)])
        self.assertEqual(self.client.stats("doors").states, 5)
        self.assertEqual(self.client.stats("doors").observations, 5)

    def test_bad_values_are_rejected_with_their_reason(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            session.send(T, [1, 1.5, math.nan, 0], names=["a", "b", "c", "d"])
            (ack,) = session.wait()
        self.assertEqual((ack.accepted, ack.rejected), (2, 2))
        self.assertEqual(ack.rejections, [fremen.Rejection(1, "value_out_of_range"),
                                          fremen.Rejection(2, "value_out_of_range")])

    def test_grid_cells_by_index_and_by_point_outside_cells_rejected(self):
        self.client.create_map("lab", size=(8, 6, 2), resolution=0.5)
        session = self.client.ingest("lab")
        session.send(T, [1, 0, 1], cells=[(0, 0, 0), (7, 5, 1), (8, 0, 0)])
        session.send(T, [1, 1, 1], points=[(0.1, 0.1), (3.9, 2.9, 0.9), (-0.1, 0)])
        acks = session.close()  # close() answers what wait() has not
        self.assertEqual([(a.accepted, a.rejected) for a in acks], [(2, 1), (2, 1)])
        self.assertEqual(acks[0].rejections, [fremen.Rejection(2, "outside_map")])
        self.assertEqual(acks[1].rejections, [fremen.Rejection(2, "outside_map")])

    def test_patches_of_floats_and_of_bytes_are_acknowledged(self):
        self.client.create_map("lab", size=(8, 6), resolution=0.5)
        with self.client.ingest("lab") as session:
            session.send_patch(T, origin=(2, 1), size=(4, 3), values=[i % 2 for i in range(12)])
            session.send_patch(T, origin=(0, 0), size=(8, 6), probabilities=bytes([255] * 48))
            acks = session.wait()
        self.assertEqual([a.accepted for a in acks], [12, 48])

    def test_compact_cells_give_the_models_of_the_same_cells_sent_by_index(self):
        # An 8×6×2 grid: linear index x + 8·(y + 6·z).
        for name in ("by_index", "compact"):
            self.client.create_map(name, size=(8, 6, 2), resolution=0.5)
        indices = [i for i in range(96) if i % 3 != 1]
        occupied = [i % 2 for i in indices]
        cells = [(i % 8, i // 8 % 6, i // 48) for i in indices]
        with self.client.ingest("by_index") as session:
            session.send(T, occupied, cells=cells)
            session.send(T + 60, [1 - v for v in occupied], cells=cells)
            session.wait()
        with self.client.ingest("compact") as session:
            session.send_compact(T, indices, occupied=occupied)
            session.send_compact(T + 60, indices, probabilities=bytes(255 * (1 - v) for v in occupied))
            acks = session.wait()
        self.assertEqual([(a.accepted, a.rejected, a.ok) for a in acks], [(64, 0, True), (64, 0, True)])
        # The same observations give the same models: the same predictions, exactly.
        times = [T + 3600 * h for h in range(5)]
        compact_p = self.client.predict("compact", times, cells=cells)
        by_index_p = self.client.predict("by_index", times, cells=cells)
        self.assertEqual(compact_p.unobserved, [])
        self.assertEqual(repr(compact_p.probabilities), repr(by_index_p.probabilities))

    def test_malformed_compact_cells_are_refused_before_sending_or_by_the_daemon_naming_the_field(self):
        self.client.create_map("lab", size=(8, 6), resolution=0.5)
        with self.client.ingest("lab") as session:
            with self.assertRaises(fremen.InvalidArgument):
                session.send_compact(T, [3, 2], occupied=[1, 1])
            with self.assertRaises(fremen.InvalidArgument):
                session.send_compact(T, [1, 2], occupied=[0.5, 1])
            session.send_compact(T, [1, 2], probabilities=b"a")
            session.send_compact(T, [47, 48, 1000], occupied=[1, 0, 1])
            bad, outside = session.wait()
        self.assertIsInstance(bad.error, fremen.InvalidArgument)
        self.assertIn("compact.probabilities has 1 bytes for 2 cells", str(bad.error))
        self.assertEqual((outside.accepted, outside.rejected), (1, 2))
        self.assertEqual(outside.rejections, [fremen.Rejection(1, "outside_map"), fremen.Rejection(2, "outside_map")])

    def test_a_batch_refused_as_a_whole_carries_its_error_and_the_stream_goes_on(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            session.send(math.nan, [1], names=["a"])
            session.send(T, [1, 0], names=["a"])
            session.send(T, [1], names=["a"])
            bad_time, bad_lengths, good = session.wait()
        self.assertIsInstance(bad_time.error, fremen.InvalidArgument)
        self.assertEqual(bad_time.error.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("time", bad_time.error.message)
        self.assertFalse(bad_time.ok)
        self.assertEqual(bad_time.accepted, 0)
        self.assertEqual(bad_lengths.error.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("values", bad_lengths.error.message)
        self.assertTrue(good.ok)
        self.assertEqual(good.accepted, 1)

    def test_a_resent_batch_is_a_duplicate_and_not_applied_again(self):
        self.client.create_map("doors")
        with self.client.ingest("doors", writer_id=42) as session:
            session.send(T, [1], names=["a"])
            session.send(T + 1, [1], names=["a"])
        with self.client.ingest("doors", writer_id=42, first_sequence=2) as resumed:
            resumed.send(T + 1, [1], names=["a"])
            resumed.send(T + 2, [0], names=["a"])
            retry, new = resumed.wait()
        self.assertTrue(retry.duplicate)
        self.assertEqual(retry.sequence, 2)
        self.assertFalse(new.duplicate)
        self.assertEqual(new.sequence, 3)
        self.assertEqual(self.client.stats("doors").observations, 3)

    def test_a_rebooted_writer_continues_after_its_last_sequence_and_loses_nothing(self):
        self.client.create_map("doors")
        self.assertEqual(self.client.last_sequence("doors", 9), 0)
        with self.client.ingest("doors", writer_id=9) as session:
            for i in range(3):
                self.assertEqual(session.send(T + i, [1], names=["a"]), i + 1)
        self.assertEqual(self.client.last_sequence("doors", 9), 3)
        # The robot rebooted and knows its id, not its count: the session asks the daemon.
        with self.client.ingest("doors", writer_id=9) as rebooted:
            self.assertEqual(rebooted.send(T + 3, [0], names=["a"]), 4)
            (ack,) = rebooted.wait()
        self.assertTrue(ack.ok)
        self.assertFalse(ack.duplicate)
        self.assertEqual(self.client.stats("doors").observations, 4)
        # Counting from 1 again with new data: refused naming where to continue, not dropped as a
        # duplicate.
        with self.client.ingest("doors", writer_id=9, first_sequence=1) as counting_again:
            counting_again.send(T + 4, [1], names=["b"])
            (refused,) = counting_again.wait()
        self.assertFalse(refused.duplicate)
        self.assertIsInstance(refused.error, fremen.AlreadyExists)
        self.assertEqual(refused.error.code, grpc.StatusCode.ALREADY_EXISTS)
        self.assertIn("writer 9 sequence 1 was already used for a different batch; continue after sequence 4",
                      refused.error.message)
        self.assertEqual(self.client.stats("doors").observations, 4)

    def test_a_message_the_daemon_cannot_parse_ends_the_session_naming_its_position(self):
        self.client.create_map("doors")

        # A link that damages the second message on its way: its bytes cut short.
        def damaging(request):
            data = request.SerializeToString()
            return data[:-2] if request.sequence == 2 else data
        channel = grpc.insecure_channel(self.daemon.address)
        self.addCleanup(channel.close)
        method = channel.stream_stream("/fremen.v1.IngestService/Ingest", request_serializer=damaging,
                                       response_deserializer=ingest_pb2.IngestResponse.FromString)
        session = IngestSession(method, "doors", [], writer_id=3, first_sequence=1, max_in_flight=8, timeout=60)
        session.send(T, [1], names=["a"])
        self.assertEqual(len(session.wait()), 1)
        session.send(T + 1, [1], names=["a"])
        session.send(T + 2, [1], names=["a"])
        with self.assertRaises(fremen.InvalidArgument) as raised:
            session.wait(timeout=30)
        self.assertEqual(raised.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("message 2 of the stream: cannot parse IngestRequest", raised.exception.message)
        self.assertEqual([b.sequence for b in session.unanswered()], [2, 3])
        self.assertEqual(self.client.stats("doors").observations, 1)

    def test_many_batches_in_flight_are_answered_in_order(self):
        self.client.create_map("lab", size=(40, 30), resolution=0.5)
        with self.client.ingest("lab", max_in_flight=4) as session:
            for i in range(200):
                session.send(T + i, [1.0] * 40, cells=[(x, i % 30) for x in range(40)])
            acks = session.wait(timeout=120)
        self.assertEqual([a.sequence for a in acks], list(range(1, 201)))
        self.assertTrue(all(a.accepted == 40 for a in acks))

    def test_explicit_sequence_numbers_are_kept(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            self.assertEqual(session.send(T, [1], names=["a"], sequence=100), 100)
            self.assertEqual(session.send(T, [1], names=["a"]), 101)
            self.assertEqual([a.sequence for a in session.wait()], [100, 101])

    def test_unknown_map_ends_the_stream_with_not_found(self):
        session = self.client.ingest("nowhere")
        # The refusal may come before the first batch is sent (the header names the map) or after.
        with self.assertRaises(fremen.NotFound) as raised:
            session.send(T, [1], names=["a"])
            session.wait(timeout=30)
        self.assertEqual(raised.exception.code, grpc.StatusCode.NOT_FOUND)
        self.assertIn("nowhere", raised.exception.message)
        with self.assertRaises(fremen.NotFound):
            session.send(T, [1], names=["a"])
        with self.assertRaises(fremen.NotFound):
            session.close()

    def test_arguments_refused_before_sending(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            with self.assertRaises(fremen.InvalidArgument) as raised:
                session.send(T, [1], names=["a"], ids=[1])
            self.assertIn("exactly one of", raised.exception.message)
            with self.assertRaises(fremen.InvalidArgument):
                session.send(T, [1], cells=[(1, 2, 3, 4)])
            with self.assertRaises(fremen.InvalidArgument):
                session.send(T, [1], cells=[(1, 2)], groups=["g"])
            with self.assertRaises(fremen.InvalidArgument):
                session.send_patch(T, (0, 0), (1, 1))
            self.assertEqual(session.wait(), [])
            self.assertEqual(session.send(T, [1], names=["a"]), 1)  # refusals used no sequence number

    def test_sending_after_close_is_refused(self):
        self.client.create_map("doors")
        session = self.client.ingest("doors")
        self.assertEqual(session.close(), [])
        with self.assertRaises(fremen.FailedPrecondition):
            session.send(T, [1], names=["a"])

    def test_an_exception_in_the_with_block_cancels_the_stream(self):
        self.client.create_map("doors")
        with self.assertRaisesRegex(RuntimeError, "robot fell over"):
            with self.client.ingest("doors") as session:
                session.send(T, [1], names=["a"])
                self.assertEqual(len(session.wait()), 1)
                raise RuntimeError("robot fell over")
        with self.assertRaises(fremen.FailedPrecondition):
            session.send(T, [1], names=["a"])
        self.assertEqual(self.client.stats("doors").observations, 1)  # what was acknowledged stays

    def test_batches_unanswered_when_the_daemon_died_are_resent_exactly_once(self):
        self.client.create_map("doors")
        session = self.client.ingest("doors", writer_id=5)
        for i in range(5):
            session.send(T + i, [1], names=["a"])
        self.assertEqual(len(session.wait()), 5)
        # A stopped daemon answers nothing: the next batches stay unanswered, until it dies.
        self.daemon.pause()
        for i in range(5, 8):
            session.send(T + i, [1], names=["a"])
        self.daemon.kill()
        with self.assertRaises(fremen.Unavailable):
            session.wait(timeout=30)
        unanswered = session.unanswered()
        self.assertEqual([b.sequence for b in unanswered], [6, 7, 8])

        self.restart_daemon()
        with self.client.ingest("doors", writer_id=5) as resumed:
            resumed.resend(unanswered)
            resumed.resend(unanswered[:1])  # applied by now: answered as a duplicate
            self.assertEqual(resumed.send(T + 8, [1], names=["a"]), 9)
            acks = resumed.wait()
        self.assertEqual([(a.sequence, a.duplicate) for a in acks],
                         [(6, False), (7, False), (8, False), (6, True), (9, False)])
        self.assertEqual(self.client.stats("doors").observations, 9)
        with self.client.ingest("doors", writer_id=6) as other_writer:
            with self.assertRaises(fremen.InvalidArgument) as raised:
                other_writer.resend(unanswered)
        self.assertIn("writer_id=5", raised.exception.message)


if __name__ == "__main__":
    unittest.main()
