"""IngestSession.send_history against a real fremend: a door's log as one batch gives the
predictions of the same log sent one scan per time, bit for bit; a many-states history; bad
histories refused naming the field while the stream goes on."""

import math
import unittest

from fremend_process import DaemonTestCase

T = 1.7e9


def door_log(n):
    """n minutes of a door open by day (08:00-18:00)."""
    times = [T + 60.0 * i for i in range(n)]
    return times, [1.0 if 8 <= (t % 86400) / 3600 < 18 else 0.0 for t in times]


def _flat(array):
    """The values of a numpy array or of nested lists, in order."""
    if hasattr(array, "ravel"):
        return list(array.ravel())
    return [p for row in array for p in row]


class HistoryTest(DaemonTestCase):
    def test_a_history_predicts_as_one_scan_per_time(self):
        self.client.create_map("by_history")
        self.client.create_map("by_scans")
        times, values = door_log(3 * 1440)
        with self.client.ingest("by_history") as session:
            session.send_history(times, values, names=["door"])
            (ack,) = session.wait()
        self.assertEqual((ack.accepted, ack.rejected, ack.ok), (3 * 1440, 0, True))
        with self.client.ingest("by_scans") as session:
            for t, v in zip(times, values):
                session.send(t, [v], names=["door"])
            session.wait()
        for name in ("by_history", "by_scans"):
            self.client.update(name)
        query_times = [T + 3600.0 * h + 7 for h in range(0, 100, 3)]
        # At order 2 (the first update selects on no evidence yet), so that P is periodic.
        by_history = self.client.predict("by_history", query_times, names=["door"], order=2).probabilities
        by_scans = self.client.predict("by_scans", query_times, names=["door"], order=2).probabilities
        self.assertEqual([float(p) for p in _flat(by_history)], [float(p) for p in _flat(by_scans)])
        self.assertGreater(len(set(float(p) for p in _flat(by_history))), 1, "P was not published")
        self.assertEqual(self.client.stats("by_history").observations, 3 * 1440)

    def test_many_states_by_id_each_with_its_time(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            session.send_history([T, T, T + 60], [1, 0, 1], ids=[1, 2, 1], groups=["hall", "lab", "hall"])
            (ack,) = session.wait()
        self.assertEqual(ack.accepted, 3)
        self.assertEqual(self.client.stats("doors").states, 2)

    def test_bad_histories_are_refused_naming_the_field(self):
        self.client.create_map("doors")
        with self.client.ingest("doors") as session:
            session.send_history([T, math.nan], [1, 0], ids=[1])
            session.send_history([T], [1, 0], ids=[1])
            session.send_history([T, T + 1], [1, 0], ids=[1])
            nan_time, short, good = session.wait()
        self.assertIn("history.times[1]", str(nan_time.error))
        self.assertIn("history.times has 1 times for 2 values", str(short.error))
        self.assertTrue(good.ok)


if __name__ == "__main__":
    unittest.main()
