"""Client.predict / region / model / stats / top / anomalies / update against a real fremend, on maps
filled through Client.ingest: a door open in office hours and a grid whose left half is occupied in
office hours. Regions are checked against Predict of the same cells, StateModel.probability against
Predict at the same order, and every call has an error case."""

import unittest

import grpc

import fremen
from fremend_process import DaemonTestCase

T0 = 1_700_006_400.0  # a Monday 00:00 UTC
HOUR = 3600.0
WEEKS = 2
HOURS_A_WEEK = 7 * 24
DAYS = WEEKS * 7
NX, NY = 16, 12
NOON = T0 + DAYS * 86400 + 12 * HOUR  # a day after the observations, at noon
NIGHT = NOON + 12 * HOUR


def office_hours(t):
    return 1.0 if 8 <= (t - T0) % 86400 / HOUR < 18 else 0.0


class QueriesTest(DaemonTestCase):
    # The first update publishes P at order 0 (no order has been scored yet); the second scores
    # the second week against the first P at every order and selects one (docs/model.md,
    # "Order selection").
    def fill_doors(self):
        self.client.create_map("doors")
        for week in range(WEEKS):
            with self.client.ingest("doors", first_sequence=week * HOURS_A_WEEK + 1, writer_id=1) as session:
                for h in range(week * HOURS_A_WEEK, (week + 1) * HOURS_A_WEEK):
                    t = T0 + h * HOUR
                    session.send(t, [office_hours(t), 1.0], names=["door", "always"], groups=["hall", "hall"])
                self.assertTrue(all(a.ok for a in session.wait()))
            self.client.update("doors")

    def fill_grid(self, name="lab", nz=None):
        size = (NX, NY) if nz is None else (NX, NY, nz)
        planes = 1 if nz is None else nz
        self.client.create_map(name, size=size, resolution=0.25)
        for week in range(WEEKS):
            with self.client.ingest(name) as session:
                for h in range(week * HOURS_A_WEEK, (week + 1) * HOURS_A_WEEK):
                    t = T0 + h * HOUR
                    # Every row but the last: the left half follows office hours, the right is free.
                    row = [office_hours(t) if x < NX // 2 else 0.0 for x in range(NX)]
                    session.send_patch(t, (0, 0, 0), (NX, NY - 1, planes), values=row * (NY - 1) * planes)
            self.client.update(name)

    # --- predict ---

    def test_predict_follows_the_observations(self):
        self.fill_doors()
        prediction = self.client.predict("doors", [NOON, NIGHT], names=["door", "always", "never-seen"])
        p = prediction.probabilities
        self.assertEqual(p.shape, (2, 3))
        self.assertGreater(p[0, 0], 0.7)  # the door at noon
        self.assertLess(p[1, 0], 0.3)  # and at midnight
        self.assertEqual(p[0, 1], 1.0)
        self.assertEqual(p[0, 2], 0.5)
        self.assertEqual(prediction.unobserved, [2])
        self.assertIsNone(prediction.states)

    def test_predict_by_id_equals_by_name(self):
        self.fill_doors()
        door = self.client.model("doors", name="door")
        by_name = self.client.predict("doors", NOON, names=["door"])
        by_id = self.client.predict("doors", NOON, ids=[door.id])
        self.assertEqual(by_id.probabilities.tolist(), by_name.probabilities.tolist())

    def test_predict_states_at_a_confidence(self):
        self.fill_doors()
        both = self.client.predict("doors", [NOON, NIGHT], names=["door"], confidence=0.6)
        self.assertEqual(both.states.tolist(), [[True], [False]])
        only = self.client.predict("doors", [NOON, NIGHT], names=["door"], confidence=0.6, states_only=True)
        self.assertIsNone(only.probabilities)
        self.assertEqual(only.states.tolist(), [[True], [False]])

    def test_predict_by_point_equals_by_cell(self):
        self.fill_grid()
        cells = [(1, 1), (12, 3), (5, NY - 1)]
        points = [(x * 0.25 + 0.1, y * 0.25 + 0.1) for x, y in cells]
        by_cell = self.client.predict("lab", [NOON, NIGHT], cells=cells)
        by_point = self.client.predict("lab", [NOON, NIGHT], points=points)
        self.assertEqual(by_cell.probabilities.tolist(), by_point.probabilities.tolist())
        self.assertEqual(by_cell.unobserved, [2])

    def test_predict_errors(self):
        self.fill_doors()
        with self.assertRaises(fremen.NotFound):
            self.client.predict("nowhere", NOON, names=["door"])
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.predict("doors", NOON, names=["door"], confidence=2)
        self.assertIn("confidence", raised.exception.message)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.predict("doors", NOON, names=["door"], order=99)
        self.assertIn("options.order", raised.exception.message)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.predict("doors", NOON)
        self.assertIn("exactly one of", raised.exception.message)

    def test_persistence_on_a_map_without_it_is_failed_precondition(self):
        self.client.create_map("plain", persistence=False)
        with self.assertRaises(fremen.FailedPrecondition) as raised:
            self.client.predict("plain", NOON, names=["a"], persistence=True)
        self.assertEqual(raised.exception.code, grpc.StatusCode.FAILED_PRECONDITION)
        self.assertIn("persistence", raised.exception.message)

    # --- region ---

    def test_region_agrees_with_predict_of_its_cells(self):
        self.fill_grid()
        lo, hi = (2, 1), (14, NY)
        region = self.client.region("lab", lo, hi, NOON)
        self.assertEqual(region.shape, (hi[1] - lo[1], hi[0] - lo[0]))
        self.assertEqual(str(region.dtype), "float32")
        cells = [(x, y) for y in range(lo[1], hi[1]) for x in range(lo[0], hi[0])]
        predicted = self.client.predict("lab", NOON, cells=cells).probabilities[0]
        self.assertEqual(region.ravel().tolist(), predicted.tolist())
        self.assertGreater(region[0, 0], 0.7)  # the left half at noon
        self.assertLess(region[0, -1], 0.3)  # the right half
        self.assertEqual(region[-1, 0], 0.5)  # the last row was never observed

    def test_region_outputs(self):
        self.fill_grid()
        p = self.client.region("lab", (0, 0), (NX, NY), NOON)
        as_bytes = self.client.region("lab", (0, 0), (NX, NY), NOON, output="uint8")
        self.assertEqual(str(as_bytes.dtype), "uint8")
        self.assertEqual(as_bytes.tolist(), [[round(255 * v) for v in row] for row in p.tolist()])
        states = self.client.region("lab", (0, 0), (NX, NY), NOON, output="states", confidence=0.6)
        self.assertEqual(states.tolist(), [[int(v >= 0.6) for v in row] for row in p.tolist()])
        entropy = self.client.region("lab", (0, 0), (NX, NY), NOON, output="entropy")
        self.assertAlmostEqual(float(entropy[NY - 1, 0]), 1.0, places=5)  # p = 0.5: one bit

    def test_region_in_small_chunks_equals_one_chunk(self):
        self.fill_grid()
        whole = self.client.region("lab", (0, 0), (NX, NY), NOON)
        chunked = self.client.region("lab", (0, 0), (NX, NY), NOON, chunk_cells=7)
        self.assertEqual(chunked.tolist(), whole.tolist())

    def test_region_series_frames_equal_region_at_each_time(self):
        self.fill_grid()
        times = [NOON + h * HOUR for h in range(0, 24, 4)]
        for output in ("float", "uint8", "entropy", "states"):
            frames = self.client.region_series("lab", (1, 0), (NX, NY), times, output=output, confidence=0.6,
                                               chunk_cells=9)
            self.assertEqual(len(frames), len(times))
            for t, frame in zip(times, frames):
                region = self.client.region("lab", (1, 0), (NX, NY), t, output=output, confidence=0.6)
                self.assertEqual(frame.shape, region.shape)
                self.assertEqual(frame.tolist(), region.tolist())
        # The left half varies, the right half and the last row do not.
        frames = self.client.region_series("lab", (0, 0), (NX, NY), [NOON, NIGHT])
        self.assertGreater(frames[0][0, 0], 0.7)
        self.assertLess(frames[1][0, 0], 0.3)
        self.assertEqual(frames[1][NY - 1, 0], 0.5)
        with self.assertRaises(fremen.Error) as raised:
            self.client.region_series("lab", (0, 0), (NX, NY), [])
        self.assertEqual(raised.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("times", raised.exception.message)

    def test_region_of_a_3d_grid_is_shaped_z_y_x(self):
        self.fill_grid("cube", nz=3)
        region = self.client.region("cube", (0, 0, 1), (NX, NY, 3), NOON)
        self.assertEqual(region.shape, (2, NY, NX))
        predicted = self.client.predict("cube", NOON, cells=[(3, 4, 2), (12, 4, 1)]).probabilities[0]
        self.assertEqual([region[1, 4, 3], region[0, 4, 12]], predicted.tolist())

    def test_region_without_numpy_is_a_flat_array(self):
        self.fill_grid()
        flat_client = self.connect(use_numpy=False)
        flat = flat_client.region("lab", (2, 1), (14, NY), NOON)
        self.assertIsInstance(flat, fremen.FlatArray)
        self.assertEqual(flat.shape, (NY - 1, 12))
        self.assertEqual(len(flat.values), (NY - 1) * 12)
        self.assertEqual(flat.tolist(), self.client.region("lab", (2, 1), (14, NY), NOON).tolist())
        prediction = flat_client.predict("lab", [NOON, NIGHT], cells=[(0, 0), (15, 0)])
        self.assertIsInstance(prediction.probabilities, fremen.FlatArray)
        self.assertEqual(prediction.probabilities.shape, (2, 2))

    def test_region_errors(self):
        self.fill_grid()
        with self.assertRaises(fremen.OutOfRange) as raised:
            self.client.region("lab", (0, 0), (NX + 1, NY), NOON)
        self.assertEqual(raised.exception.code, grpc.StatusCode.OUT_OF_RANGE)
        with self.assertRaises(fremen.NotFound):
            self.client.region("nowhere", (0, 0), (1, 1), NOON)
        with self.assertRaises(fremen.InvalidArgument):
            self.client.region("lab", (0, 0), (1, 1, 1), NOON)
        with self.assertRaises(fremen.InvalidArgument):
            self.client.region("lab", (0, 0), (1, 1), NOON, output="png")

    # --- model ---

    def test_model_is_a_friendly_object_that_predicts_like_the_daemon(self):
        self.fill_doors()
        door = self.client.model("doors", name="door", include_spectrum=True)
        self.assertEqual((door.name, door.group), ("door", "hall"))
        self.assertEqual(door.observations, DAYS * 24)
        self.assertEqual((door.first_time, door.last_time), (T0, T0 + (DAYS * 24 - 1) * HOUR))
        self.assertAlmostEqual(door.mean, 10 / 24, places=5)
        self.assertEqual(len(door.spectrum), 24)
        self.assertGreater(len(door.published), 0)
        self.assertEqual(door.published[0].period_seconds, 86400)  # the strongest rhythm: a day
        self.assertEqual(door.persistence.last_value, 0.0)
        self.assertIsNone(door.cell)
        for order in (0, 1, 2, door.selected_order):
            for t in (NOON, NIGHT, NOON + 5 * HOUR):
                daemon = float(self.client.predict("doors", t, names=["door"], order=order).probabilities[0, 0])
                self.assertAlmostEqual(door.probability(t, order), daemon, places=4, msg=f"order {order} at {t}")

    def test_model_of_a_cell_its_message_and_never_observed(self):
        self.fill_grid()
        cell = self.client.model("lab", cell=(3, 2))
        self.assertEqual(cell.cell, (3, 2, 0))
        self.assertEqual(cell.observations, DAYS * 24)
        by_point = self.client.model("lab", point=(3 * 0.25 + 0.1, 2 * 0.25 + 0.1))
        self.assertEqual(by_point.id, cell.id)
        self.assertEqual(cell.proto.observations, DAYS * 24)
        self.assertIsNone(self.client.model("lab", cell=(3, NY - 1)))

    def test_model_errors(self):
        self.fill_doors()
        with self.assertRaises(fremen.NotFound):
            self.client.model("nowhere", name="door")
        with self.assertRaises(fremen.InvalidArgument):
            self.client.model("doors", name="door", id=3)
        with self.assertRaises(fremen.FailedPrecondition) as raised:
            self.client.model("doors", cell=(1, 1))  # a generic map has no cells
        self.assertIn("state.cell", raised.exception.message)

    # --- stats, top, anomalies, update ---

    def test_stats_count_states_and_observations(self):
        self.fill_doors()
        stats = self.client.stats("doors")
        self.assertIsInstance(stats, fremen.MapStats)
        self.assertIsInstance(stats.last_update, fremen.MapUpdate)  # fill_doors updates after each week
        self.assertEqual(stats.states, 2)
        self.assertEqual(stats.dynamic_states, 1)
        self.assertEqual(stats.observations, 2 * DAYS * 24)
        self.assertGreater(stats.disk_bytes, 0)
        with self.assertRaises(fremen.NotFound):
            self.client.stats("nowhere")

    def test_top_ranks_a_group(self):
        self.fill_doors()
        at_night = self.client.top("doors", "hall", NIGHT, n=2)
        self.assertEqual([s.name for s in at_night], ["always", "door"])
        self.assertEqual(at_night[0].probability, 1.0)
        self.assertEqual(len(self.client.top("doors", "hall", NIGHT, n=1)), 1)
        with self.assertRaises(fremen.NotFound):
            self.client.top("doors", "no-such-group", NIGHT)

    def test_list_states_by_name(self):
        self.fill_doors()
        states = list(self.client.list_states("doors", page_size=1))  # one state a page: the pages join
        self.assertEqual([s.name for s in states], sorted(s.name for s in states))
        self.assertEqual({s.name for s in states}, {"always", "door"})
        self.assertTrue(all(s.group == "hall" for s in states))
        self.assertIsInstance(states[0], fremen.NamedState)
        with self.assertRaises(fremen.NotFound):
            list(self.client.list_states("doors", group="no-such-group"))

    def test_anomalies_flag_the_unexpected(self):
        self.fill_doors()
        check = self.client.anomalies("doors", [1.0, 0.0, 1.0], [NIGHT, NOON, NOON], 0.7,
                                      names=["door", "door", "always"])
        self.assertEqual(check.anomalous, [True, True, False])
        self.assertEqual(len(check.probabilities), 3)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.anomalies("doors", [1.0], NOON, 0.2, names=["door"])
        self.assertIn("confidence", raised.exception.message)

    def test_update_returns_the_finished_operation(self):
        self.client.create_map("doors")
        operation = self.client.update("doors")
        self.assertTrue(operation.done)
        self.assertEqual(operation.map_name, "doors")
        self.assertEqual(operation.stage, "done")
        started = self.client.update("doors", wait=False)
        self.assertTrue(started.name.startswith("operations/"))
        with self.assertRaises(fremen.NotFound):
            self.client.update("nowhere")


if __name__ == "__main__":
    unittest.main()
