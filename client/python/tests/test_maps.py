"""Client.create_map / get_map / list_maps / delete_map against a real fremend (a fremen.MapInfo
whose fields are named as create_map's parameters), and their errors raised as fremen.Error
subclasses carrying the gRPC code and the daemon's message."""

import unittest

import grpc

import fremen
from fremend_process import DaemonTestCase


class MapsTest(DaemonTestCase):
    def test_create_grid_2d_fills_in_the_defaults(self):
        made = self.client.create_map("lab", size=(40, 30), resolution=0.5, origin=(-1, 2))
        self.assertIsInstance(made, fremen.MapInfo)
        self.assertEqual(made.name, "lab")
        self.assertEqual(made.kind, "grid")
        self.assertEqual(made.size, (40, 30, 1))
        self.assertEqual(made.resolution, 0.5)
        self.assertEqual(made.origin, (-1, 2, 0))
        self.assertEqual(made.longest_period, 604800)
        self.assertEqual(made.period_count, 24)
        self.assertEqual(made.periods, [])
        self.assertEqual(made.max_order, 5)
        self.assertTrue(made.persistence)
        self.assertEqual(made.criterion, "threshold")
        self.assertEqual(made.error_half_life, 7 * 86400)
        self.assertEqual(made.order_selection, "margin")
        self.assertEqual(made.order_margin, 0.001)
        self.assertEqual(made.order_temperature, 0.01)
        self.assertGreater(made.create_time, 1.7e9)
        self.assertEqual(made.proto.grid.size.x, 40)  # the message it came from

    def test_create_grid_3d_and_generic_keep_every_setting(self):
        grid = self.client.create_map("cube", size=(10, 20, 4), resolution=0.25, longest_period=86400,
                                      period_count=6, floor_periods=True, max_order=3, persistence=False,
                                      error_half_life=3600, criterion="threshold", order_selection="margin",
                                      order_margin=0.003, lossless_sampling=60,
                                      lossless_origin=1.7e9, shards=3)
        self.assertEqual(grid.size, (10, 20, 4))
        self.assertEqual(grid.longest_period, 86400)
        self.assertEqual(grid.period_count, 6)
        self.assertTrue(grid.floor_periods)
        self.assertEqual(grid.max_order, 3)
        self.assertFalse(grid.persistence)
        self.assertEqual(grid.error_half_life, 3600)
        self.assertEqual(grid.criterion, "threshold")
        self.assertEqual(grid.order_selection, "margin")
        self.assertEqual(grid.order_margin, 0.003)
        paper = self.client.create_map("paper", order_selection="paper", order_temperature=0.5)
        self.assertEqual((paper.order_selection, paper.order_temperature), ("paper", 0.5))
        self.assertEqual(grid.lossless_sampling, 60)
        self.assertEqual(grid.lossless_origin, 1.7e9)
        self.assertEqual(grid.shards, 3)

        doors = self.client.create_map("doors", periods=[86400, 43200, 3600])
        self.assertEqual(doors.kind, "generic")
        self.assertEqual((doors.size, doors.resolution, doors.origin), (None, None, None))
        self.assertEqual(doors.periods, [86400, 43200, 3600])

    def test_get_map_answers_what_create_map_made(self):
        made = self.client.create_map("lab", size=(8, 8), resolution=0.1)
        self.assertEqual(self.client.get_map("lab"), made)

    def test_list_maps_walks_every_page_in_name_order(self):
        names = ["e", "a", "d", "b", "c"]
        for name in names:
            self.client.create_map(name)
        self.assertEqual([m.name for m in self.client.list_maps(page_size=2)], sorted(names))
        self.assertEqual([m.name for m in self.client.list_maps()], sorted(names))

    def test_list_maps_on_an_empty_daemon(self):
        self.assertEqual(list(self.client.list_maps()), [])

    def test_delete_map_removes_it(self):
        self.client.create_map("doors")
        self.client.delete_map("doors")
        self.assertEqual(list(self.client.list_maps()), [])
        with self.assertRaises(fremen.NotFound):
            self.client.get_map("doors")

    # --- errors ---

    def test_unknown_map_is_not_found_with_the_code_and_message(self):
        for call in (lambda: self.client.get_map("nowhere"), lambda: self.client.delete_map("nowhere")):
            with self.assertRaises(fremen.Error) as raised:
                call()
            self.assertIsInstance(raised.exception, fremen.NotFound)
            self.assertEqual(raised.exception.code, grpc.StatusCode.NOT_FOUND)
            self.assertIn("nowhere", raised.exception.message)

    def test_bad_setting_is_invalid_argument_naming_the_field(self):
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.create_map("lab", size=(8, 8), resolution=0)
        self.assertEqual(raised.exception.code, grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("map.grid.resolution", raised.exception.message)
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.create_map("bad name!")
        self.assertIn("name", raised.exception.message)

    def test_taken_name_is_already_exists(self):
        self.client.create_map("doors")
        with self.assertRaises(fremen.AlreadyExists) as raised:
            self.client.create_map("doors")
        self.assertEqual(raised.exception.code, grpc.StatusCode.ALREADY_EXISTS)

    def test_arguments_refused_before_calling_are_invalid_argument(self):
        with self.assertRaises(fremen.InvalidArgument) as raised:
            self.client.create_map("lab", size=(8, 8))
        self.assertIn("resolution", raised.exception.message)
        with self.assertRaises(ValueError):  # InvalidArgument is also a ValueError
            self.client.create_map("lab", kind="cube")
        with self.assertRaises(fremen.InvalidArgument):
            self.client.create_map("lab", criterion="best")
        with self.assertRaises(fremen.InvalidArgument):
            self.client.create_map("lab", order_selection="best")
        with self.assertRaises(fremen.InvalidArgument) as raised:  # refused by the daemon
            self.client.create_map("lab", order_temperature=0)
        self.assertIn("map.order_temperature", raised.exception.message)

    def test_a_daemon_that_is_gone_is_unavailable(self):
        self.stop_daemon()
        client = fremen.connect(self.daemon.address, timeout=5)
        self.addCleanup(client.close)
        with self.assertRaises(fremen.Unavailable) as raised:
            client.get_map("lab")
        self.assertEqual(raised.exception.code, grpc.StatusCode.UNAVAILABLE)


if __name__ == "__main__":
    unittest.main()
