"""fremen.FleetClient against three real fremend processes on loopback, each asked directly: the
merged map list names every map with the daemon that holds it (a map on two daemons on both),
server_status() per daemon and summed; after kill -9 of one daemon its address and Unavailable come
back beside the others' answers. The daemons want tokens; the fleet's one token reaches each.
fremen.Placement against the owners a real nginx chose (client/lib/placement_test.cc pins them too)."""

import os
import tempfile
import unittest

import fremen
from fremend_process import FremendProcess

TOKENS = ["--tokens", "read:fleet-reader write:fleet-writer"]
# What nginx 1.22.1's `hash $http_x_fremen_map consistent` chose over these three servers.
NGINX_SERVERS = ["127.0.0.1:50051", "127.0.0.1:50061", "127.0.0.1:50071"]
NGINX_OWNERS = {
    "m1": "127.0.0.1:50071", "m2": "127.0.0.1:50071", "m3": "127.0.0.1:50061", "m4": "127.0.0.1:50061",
    "m5": "127.0.0.1:50071", "m6": "127.0.0.1:50051", "m7": "127.0.0.1:50061", "m8": "127.0.0.1:50071",
    "m9": "127.0.0.1:50061", "m10": "127.0.0.1:50061", "m11": "127.0.0.1:50071", "m12": "127.0.0.1:50061",
    "office": "127.0.0.1:50051", "lab": "127.0.0.1:50051", "warehouse-7": "127.0.0.1:50051",
    "hospital.wing-b": "127.0.0.1:50071", "a": "127.0.0.1:50071",
}


class PlacementTest(unittest.TestCase):
    def test_owners_are_the_ones_nginx_chose(self):
        placement = fremen.Placement(NGINX_SERVERS)
        for map_name, owner in NGINX_OWNERS.items():
            self.assertEqual(placement.owner(map_name), owner, map_name)
        # The order of the servers does not matter.
        shuffled = fremen.Placement(list(reversed(NGINX_SERVERS)))
        for map_name, owner in NGINX_OWNERS.items():
            self.assertEqual(shuffled.owner(map_name), owner, map_name)

    def test_bad_fleets(self):
        for bad in ([], ["a:1", "a:1"], [""]):
            with self.assertRaises(fremen.InvalidArgument, msg=bad):
                fremen.Placement(bad)


class FleetClientTest(unittest.TestCase):
    def setUp(self):
        self._dir = tempfile.TemporaryDirectory(prefix="fremen_fleet.")
        self.addCleanup(self._dir.cleanup)
        self.daemons = []
        for i in range(3):
            daemon = FremendProcess.start(os.path.join(self._dir.name, f"daemon-{i}"), TOKENS)
            self.addCleanup(daemon.kill)
            self.daemons.append(daemon)
        self.addresses = [d.address for d in self.daemons]

    def fleet(self, addresses=None, token="fleet-writer"):
        # Few retries, so that a killed daemon answers Unavailable soon.
        fleet = fremen.FleetClient(addresses or self.addresses, token=token,
                                   reconnect=fremen.Backoff(max_attempts=2))
        self.addCleanup(fleet.close)
        return fleet

    def create_on(self, daemon, *names):
        with fremen.connect(self.addresses[daemon], token="fleet-writer") as client:
            for name in names:
                client.create_map(name)

    @staticmethod
    def rows(maps):
        return [(m.map.name, m.daemon, m.duplicate) for m in maps.maps]

    def test_every_map_of_every_daemon_with_its_daemon(self):
        self.create_on(0, "lab", "office")
        self.create_on(1, "garage")
        self.create_on(2, "atrium", "office")  # a second copy, as during a move
        a, b, c = self.addresses
        fleet = self.fleet(f"{a}, {b},{c}")  # one comma-separated string, as --address
        self.assertEqual(fleet.addresses, self.addresses)
        maps = fleet.list_maps()
        self.assertEqual(self.rows(maps), [("atrium", c, False), ("garage", b, False), ("lab", a, False),
                                           ("office", a, True), ("office", c, True)])
        self.assertEqual(maps.duplicates, ["office"])
        self.assertEqual(maps.errors, [])
        self.assertIsInstance(maps.maps[0].map, fremen.MapInfo)
        self.assertEqual(maps.maps[0].map.kind, "generic")

    def test_status_of_each_daemon_and_their_sum(self):
        self.create_on(0, "a", "b")
        self.create_on(2, "c")
        status = self.fleet().server_status()
        self.assertEqual([d.address for d in status.daemons], self.addresses)
        self.assertEqual([d.status.map_count for d in status.daemons], [2, 0, 1])
        self.assertTrue(all(d.error is None and d.status.tokens_required for d in status.daemons))
        summary = status.summary
        self.assertEqual((summary.daemons, summary.answered, summary.map_count, summary.failed_maps), (3, 3, 3, 0))
        self.assertEqual(summary.versions, [fremen.__version__])
        self.assertGreater(summary.min_data_dir_free_bytes, 0)
        self.assertEqual(summary.recovering, [])

    def test_a_daemon_that_does_not_answer_is_reported_and_the_others_answer(self):
        self.create_on(0, "lab")
        self.create_on(1, "garage")
        self.create_on(2, "atrium")
        fleet = self.fleet()
        self.daemons[1].kill()
        maps = fleet.list_maps()
        self.assertEqual(self.rows(maps), [("atrium", self.addresses[2], False), ("lab", self.addresses[0], False)])
        self.assertEqual([e.address for e in maps.errors], [self.addresses[1]])
        self.assertIsInstance(maps.errors[0].error, fremen.Unavailable)
        status = fleet.server_status()
        self.assertIsNone(status.daemons[1].status)
        self.assertIsInstance(status.daemons[1].error, fremen.Unavailable)
        self.assertEqual((status.summary.answered, status.summary.map_count), (2, 2))

    def test_the_token_goes_to_every_daemon(self):
        self.create_on(1, "garage")
        self.assertEqual(self.rows(self.fleet(token="fleet-reader").list_maps()),
                         [("garage", self.addresses[1], False)])
        refused = self.fleet(token=None).list_maps()
        self.assertEqual(refused.maps, [])
        self.assertEqual([e.address for e in refused.errors], self.addresses)
        self.assertTrue(all(isinstance(e.error, fremen.Unauthenticated) for e in refused.errors))

    def test_client_for_is_the_owner_by_placement(self):
        fleet = self.fleet()
        placement = fremen.Placement(self.addresses)
        names = [f"building-{i}" for i in range(12)]
        for name in names:
            fleet.client_for(name).create_map(name)
        maps = fleet.list_maps()
        self.assertEqual(sorted(m.map.name for m in maps.maps), sorted(names))
        for m in maps.maps:
            self.assertEqual(m.daemon, placement.owner(m.map.name), m.map.name)

    def test_all_host_port_and_bad_addresses(self):
        self.create_on(0, "lab")
        fleet = self.fleet([f"all:{self.addresses[0]}"])
        self.assertEqual(fleet.addresses, [self.addresses[0]])
        self.assertEqual(self.rows(fleet.list_maps()), [("lab", self.addresses[0], False)])
        with self.assertRaises(fremen.FailedPrecondition):
            fleet.client_for("lab")
        with self.assertRaises(fremen.Unavailable) as unresolved:
            fremen.FleetClient("all:no-such-daemon.invalid:50051")
        self.assertIn("cannot resolve no-such-daemon.invalid", unresolved.exception.message)
        for bad in ("", [], [self.addresses[0], self.addresses[0]], "all:no-port"):
            with self.assertRaises(fremen.InvalidArgument, msg=bad):
                fremen.FleetClient(bad)


if __name__ == "__main__":
    unittest.main()
