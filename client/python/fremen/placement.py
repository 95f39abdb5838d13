"""Which daemon of a fleet owns a map: nginx's `hash $http_x_fremen_map consistent` (ketama) over the
proxy's server strings, as client/lib/placement.h computes it for the C++ client and fremenctl (the
construction is spelled out there and in docs/fleet.md, "Placement").

Each server string "HOST:PORT" (split at its last ':' when digits follow; "unix:PATH" is PATH) gets
160 points crc32(HOST "\\0" PORT PREV), PREV the previous point as 4 little-endian bytes (0 first);
a map's owner is the server of the first point ≥ crc32(map name), wrapping round.

Thread-safety: immutable after construction.
"""

import bisect
import struct
import zlib
from typing import Sequence

from fremen import errors

POINTS_PER_DAEMON = 160


def _host_port(server: str) -> tuple[bytes, bytes]:
    if server[:5].lower() == "unix:":
        return server[5:].encode(), b""
    host, colon, port = server.rpartition(":")
    if colon and port.isdigit():
        return host.encode(), port.encode()
    return server.encode(), b""


class Placement:
    """The ring of `daemons` (nginx server strings, exactly as the proxy writes them)."""

    def __init__(self, daemons: Sequence[str]) -> None:
        if not daemons:
            raise errors.InvalidArgument("a fleet needs at least one daemon")
        if any(not d for d in daemons):
            raise errors.InvalidArgument("a daemon's name is empty")
        if len(set(daemons)) != len(daemons):
            raise errors.InvalidArgument("a daemon is listed twice")
        self.daemons = list(daemons)
        points: list[tuple[int, int]] = []
        for index, daemon in enumerate(self.daemons):
            host, port = _host_port(daemon)
            base = zlib.crc32(port, zlib.crc32(b"\0", zlib.crc32(host)))
            previous = 0
            for _ in range(POINTS_PER_DAEMON):
                previous = zlib.crc32(struct.pack("<I", previous), base)
                points.append((previous, index))
        points.sort()
        self._hashes = [h for h, _ in points]
        self._owners = [d for _, d in points]

    def owner_index(self, map_name: str) -> int:
        """The index into `daemons` of the daemon that holds `map_name` (not empty)."""
        at = bisect.bisect_left(self._hashes, zlib.crc32(map_name.encode()))
        return self._owners[at % len(self._owners)]

    def owner(self, map_name: str) -> str:
        return self.daemons[self.owner_index(map_name)]
