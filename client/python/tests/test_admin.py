"""The admin calls against a real fremend: backup_map and restore_map (the copy holds the
original's observations), get_operation / list_operations (every page, newest first) /
cancel_operation of update jobs, server_status; each with its errors, and the token roles."""

import os
import unittest

import grpc

import fremen
from fremend_process import DaemonTestCase

T = 1.7e9
BIG_NX, BIG_NY = 1024, 512  # 524,288 dynamic cells: an update that takes a while


class AdminTest(DaemonTestCase):
    def fill(self, name, batches=20):
        self.client.create_map(name)
        with self.client.ingest(name) as session:
            for i in range(batches):
                session.send(T + 60 * i, [i % 2, 1, 0], names=["a", "b", "c"])
        return 3 * batches

    def make_dynamic_grid(self, name):
        """Every cell changes once, so that the update job has every cell to publish."""
        self.client.create_map(name, size=(BIG_NX, BIG_NY), resolution=0.1)
        with self.client.ingest(name) as session:
            for i, byte in enumerate((0, 255)):
                session.send_patch(T + 60 * i, (0, 0), (BIG_NX, BIG_NY),
                                   probabilities=bytes([byte]) * (BIG_NX * BIG_NY))
            self.assertEqual([a.accepted for a in session.wait(timeout=120)], [BIG_NX * BIG_NY] * 2)

    # --- backup, restore ---

    def test_backup_then_restore_under_a_new_name(self):
        observations = self.fill("lab")
        backup = self.client.backup_map("lab", "nightly/lab")
        self.assertIsInstance(backup, fremen.Backup)
        self.assertTrue(backup.path.endswith(os.path.join("nightly", "lab")), backup.path)
        self.assertTrue(os.path.exists(os.path.join(backup.path, "map.info")))
        self.assertGreater(backup.bytes, 0)
        restored = self.client.restore_map("nightly/lab", "lab-copy")
        self.assertEqual(restored.name, "lab-copy")
        self.assertIsInstance(restored, fremen.MapInfo)
        self.assertEqual(restored.kind, "generic")
        self.assertEqual([m.name for m in self.client.list_maps()], ["lab", "lab-copy"])
        self.assertEqual(self.client.stats("lab-copy").observations, observations)
        self.assertEqual(self.client.model("lab-copy", name="a").observations, 20)

    def test_backup_and_restore_errors(self):
        self.fill("lab")
        for bad in ("/tmp/x", "../x", ""):
            with self.assertRaises(fremen.InvalidArgument, msg=bad) as raised:
                self.client.backup_map("lab", bad)
            self.assertIn("directory", raised.exception.message)
        with self.assertRaises(fremen.NotFound):
            self.client.backup_map("nowhere", "x")
        self.client.backup_map("lab", "b")
        with self.assertRaises(fremen.AlreadyExists):
            self.client.backup_map("lab", "b")
        with self.assertRaises(fremen.AlreadyExists):
            self.client.restore_map("b")  # as "lab", which exists
        with self.assertRaises(fremen.NotFound):
            self.client.restore_map("nothing-here", "other")
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.restore_map("/etc", "other")
        self.assertIn("directory", raised.exception.message)

    # --- operations ---

    def test_operations_listed_newest_first_on_every_page(self):
        self.client.create_map("a")
        self.client.create_map("b")
        operations = [self.client.update(m) for m in ("a", "b", "a")]
        self.assertIsInstance(operations[0], fremen.Operation)
        names = [op.name for op in operations]
        self.assertEqual([op.name for op in self.client.list_operations()], names[::-1])
        self.assertEqual([op.name for op in self.client.list_operations("a", page_size=1)], [names[2], names[0]])
        self.assertEqual(list(self.client.list_operations(running_only=True)), [])
        again = self.client.get_operation(names[1])
        self.assertEqual((again.name, again.map_name, again.done, again.trigger), (names[1], "b", True, "RunUpdate"))
        self.assertEqual(again.stage, "done")
        self.assertIsNone(again.error)
        self.assertGreaterEqual(again.end_time, again.create_time)
        self.assertEqual(self.client.get_operation(names[1], "b").name, names[1])

    def test_operation_errors(self):
        self.client.create_map("a")
        done = self.client.update("a")
        with self.assertRaises(fremen.NotFound):
            self.client.get_operation(done.name, "other-map")
        with self.assertRaises(fremen.NotFound):
            self.client.get_operation("operations/update-a-99")
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.get_operation("update-a-1")
        self.assertIn("name", raised.exception.message)
        with self.assertRaises(fremen.NotFound):
            self.client.cancel_operation("operations/update-a-99")
        with self.assertRaises(fremen.InvalidArgument) as raised:
            list(self.client.list_operations(page_size=-1))
        self.assertIn("page_size", raised.exception.message)

    def test_cancel_a_queued_update_and_an_ended_one(self):
        self.make_dynamic_grid("big")
        self.client.create_map("small")
        big = self.client.update("big", wait=False)
        small = self.client.update("small", wait=False)  # updates run one at a time: behind big
        self.assertEqual(small.stage, "queued")
        self.assertEqual([op.name for op in self.client.list_operations(running_only=True)], [small.name, big.name])
        cancelled = self.client.cancel_operation(small.name)
        self.assertTrue(cancelled.done)
        self.assertTrue(cancelled.cancel_requested)
        self.assertEqual(cancelled.error.code, grpc.StatusCode.CANCELLED)
        self.assertIsInstance(cancelled.error, fremen.Error)
        self.assertIsNone(cancelled.update)
        self.assertEqual(self.client.get_operation(small.name).error.code, grpc.StatusCode.CANCELLED)

        finished = self.client.update("big")  # RunUpdate answers the running job: waits for it
        self.assertEqual(finished.name, big.name)
        self.assertEqual(finished.update.states_published, BIG_NX * BIG_NY)
        unchanged = self.client.cancel_operation(big.name)
        self.assertIsNone(unchanged.error)
        self.assertFalse(unchanged.cancel_requested)

    # --- status ---

    def test_server_status(self):
        self.fill("lab")
        done = self.client.update("lab")
        status = self.client.server_status()
        self.assertIsInstance(status, fremen.ServerStatus)
        self.assertEqual(status.version, fremen.__version__)
        self.assertEqual(status.map_count, 1)
        self.assertEqual(status.state_count, 3)
        self.assertEqual(status.dynamic_state_count, 1)
        self.assertEqual(status.running_operations, 0)
        self.assertEqual(status.store_state, "open")
        self.assertFalse(status.tls)
        self.assertFalse(status.tokens_required)
        self.assertGreater(status.uptime_seconds, 0)
        self.assertGreater(status.data_dir_free_bytes, 0)
        self.assertEqual({m: op.name for m, op in status.last_updates.items()}, {"lab": done.name})
        self.assertEqual(list(status.map_updates), ["lab"])
        self.assertEqual(status.map_updates["lab"].states_updated, 1)
        self.assertEqual(status.failed_maps, {})
        self.assertIsNone(status.next_scrub_time)  # scrubbing is off by default
        self.assertGreater(status.start_time, 1.7e9)


class AdminTokensTest(DaemonTestCase):
    tokens = ("read:reader-token", "write:writer-token")
    token = "writer-token"

    def test_status_needs_a_token_and_backups_a_write_token(self):
        self.client.create_map("lab")
        self.assertTrue(self.client.server_status().tokens_required)
        with self.assertRaises(fremen.Unauthenticated):
            self.connect().server_status()
        reader = self.connect(token="reader-token")
        self.assertEqual(reader.server_status().map_count, 1)
        self.assertEqual(list(reader.list_operations()), [])
        with self.assertRaises(fremen.PermissionDenied):
            reader.backup_map("lab", "b")
        with self.assertRaises(fremen.PermissionDenied):
            reader.cancel_operation("operations/update-lab-1")


if __name__ == "__main__":
    unittest.main()
