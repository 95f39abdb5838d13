"""Client.reconstruct against a real fremend: the exact past states of a lossless map (created with
lossless_sampling), slot by slot, with slots never observed reported as unobserved, by name and by
id, on numpy and FlatArray clients; and its errors (a map without lossless history, a bad time
range, no states named)."""

import unittest

import fremen
from fremend_process import DaemonTestCase

T0 = 1_700_006_400.0
SLOT = 600.0  # the map's sampling period
SLOTS = 200
GAP = range(120, 130)  # slots in which "door" was not observed


def door(k):
    """The door's state in slot k: an irregular pattern no periodic model reproduces by itself."""
    return 1 if (k * k + 3 * k) % 7 < 3 else 0


class ReconstructTest(DaemonTestCase):
    def fill(self):
        self.client.create_map("history", lossless_sampling=SLOT, lossless_origin=T0)
        with self.client.ingest("history") as session:
            for k in range(SLOTS):
                t = T0 + k * SLOT + 17  # inside slot k
                if k in GAP:
                    session.send(t, [1], names=["light"])
                else:
                    session.send(t, [door(k), 1], names=["door", "light"])
            self.assertTrue(all(ack.ok and ack.rejected == 0 for ack in session.wait()))

    def test_every_observed_slot_comes_back_exactly(self):
        self.fill()
        self.client.update("history")  # the update rebuilds the model and its outliers: still exact
        # From two slots before the origin to the end, with a state never observed.
        past = self.client.reconstruct("history", T0 - 2 * SLOT, T0 + SLOTS * SLOT,
                                       names=["door", "light", "never-seen"])
        self.assertEqual(past.first_slot_time, T0 - 2 * SLOT)
        self.assertEqual(past.slot_seconds, SLOT)
        self.assertEqual(past.slots.shape, (3, SLOTS + 2))
        self.assertEqual(str(past.slots.dtype), "uint8")
        unobserved = fremen.Reconstruction.UNOBSERVED
        want_door = [unobserved] * 2 + [unobserved if k in GAP else door(k) for k in range(SLOTS)]
        self.assertEqual(past.slots[0].tolist(), want_door)
        self.assertEqual(past.slots[1].tolist(), [unobserved] * 2 + [1] * SLOTS)
        self.assertEqual(past.slots[2].tolist(), [unobserved] * (SLOTS + 2))
        self.assertEqual(past.slot_times()[2], T0)
        self.assertEqual(len(past.slot_times()), SLOTS + 2)

    def test_a_window_by_id_without_numpy(self):
        self.fill()
        door_id = self.client.model("history", name="door").id
        flat = self.connect(use_numpy=False).reconstruct("history", T0 + 10 * SLOT + 1, T0 + 20 * SLOT, ids=[door_id])
        self.assertIsInstance(flat.slots, fremen.FlatArray)
        self.assertEqual(flat.first_slot_time, T0 + 10 * SLOT)  # the slot that holds the start
        self.assertEqual(flat.slots.tolist(), [[door(k) for k in range(10, 20)]])

    def test_errors(self):
        self.client.create_map("plain")
        self.client.create_map("history", lossless_sampling=SLOT, lossless_origin=T0)
        with self.assertRaises(fremen.FailedPrecondition) as raised:
            self.client.reconstruct("plain", T0, T0 + SLOT, names=["door"])
        self.assertIn("lossless", raised.exception.message)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.reconstruct("history", T0, T0, names=["door"])
        self.assertIn("start_time must be < end_time", raised.exception.message)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.reconstruct("history", T0, T0 + SLOT)
        self.assertIn("exactly one of", raised.exception.message)
        with self.assertRaises(fremen.NotFound):
            self.client.reconstruct("nowhere", T0, T0 + SLOT, names=["door"])


if __name__ == "__main__":
    unittest.main()
