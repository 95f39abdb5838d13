"""fremen.FleetClient: the maps and the status of every daemon of a fleet, each asked directly —
through the proxy, a call that names no map (ListMaps, GetServerStatus) reaches whichever one
daemon the proxy picks (docs/fleet.md, "Fleet-wide views"). The C++ client's FleetClient
(client/lib/fleet_client.h) answers the same.

    fleet = fremen.FleetClient("all:fremend:50051", token="...")
    maps = fleet.list_maps()
    for m in maps.maps:
        print(m.map.name, m.daemon, "DUPLICATE" if m.duplicate else "")
    for d in maps.errors:
        print(d.address, d.error)

Addresses are "host:port" strings, a comma-separated string of them, or both in a list; an item
all:HOST:PORT stands for every address HOST resolves to (a Kubernetes headless Service's name
resolves to all its pods). The daemons are asked at once, a thread each. A daemon that does not
answer does not hide the others: its address and fremen.Error come back beside their answers.
Nothing is deduplicated: a map that two daemons hold (a move in progress, a restored copy) is listed
once per daemon and named in `duplicates`.

Thread-safety: as fremen.Client's.
"""

import collections
import concurrent.futures
import dataclasses
import socket
from typing import Callable, Literal, Optional, Sequence, TypeVar, Union

import grpc

from fremen import errors
from fremen.client import Client, connect
from fremen.maps import MapInfo
from fremen.placement import Placement
from fremen.retry import Backoff
from fremen.status import ServerStatus

EVERY_ADDRESS_PREFIX = "all:"
_T = TypeVar("_T")


def resolve_every(host_port: str) -> list[str]:
    """Every address HOST of "HOST:PORT" resolves to, as "IP:PORT" ("[IPv6]:PORT"), sorted.
    InvalidArgument when it is not HOST:PORT, Unavailable when HOST does not resolve."""
    host, colon, port = host_port.rpartition(":")
    if not colon or not host:
        raise errors.InvalidArgument(f"{EVERY_ADDRESS_PREFIX}{host_port}: expected all:HOST:PORT")
    try:
        found = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as error:
        raise errors.Unavailable(grpc.StatusCode.UNAVAILABLE, f"cannot resolve {host}: {error}") from None
    addresses = set()
    for family, _, _, _, sockaddr in found:
        if family == socket.AF_INET:
            addresses.add(f"{sockaddr[0]}:{port}")
        elif family == socket.AF_INET6:
            addresses.add(f"[{sockaddr[0]}]:{port}")
    return sorted(addresses)


def expand_addresses(addresses: Union[str, Sequence[str]]) -> list[str]:
    """The daemons' addresses: comma-separated items split, all:HOST:PORT resolved in place.
    InvalidArgument when none is named or one twice."""
    items = [addresses] if isinstance(addresses, str) else list(addresses)
    expanded: list[str] = []
    for item in items:
        for address in (a.strip() for a in item.split(",")):
            if not address:
                continue
            resolved = (resolve_every(address[len(EVERY_ADDRESS_PREFIX):])
                        if address.startswith(EVERY_ADDRESS_PREFIX) else [address])
            for one in resolved:
                if one in expanded:
                    raise errors.InvalidArgument(f"daemon {one} is named twice")
                expanded.append(one)
    if not expanded:
        raise errors.InvalidArgument("no daemon named")
    return expanded


@dataclasses.dataclass(frozen=True)
class DaemonError:
    """A daemon that did not answer a fleet-wide call."""
    address: str
    error: errors.Error


@dataclasses.dataclass(frozen=True)
class FleetMap:
    map: MapInfo
    daemon: str  # the address of the daemon that listed it
    duplicate: bool  # another daemon listed a map of the same name too


@dataclasses.dataclass(frozen=True)
class FleetMaps:
    maps: list[FleetMap]  # every daemon's maps, in name order, then in the fleet's daemon order
    duplicates: list[str]  # names listed by more than one daemon, in name order
    errors: list[DaemonError]  # the daemons that did not answer, in the fleet's order


@dataclasses.dataclass(frozen=True)
class DaemonStatus:
    address: str
    status: Optional[ServerStatus]  # None when the daemon did not answer
    error: Optional[errors.Error]  # why not


@dataclasses.dataclass(frozen=True)
class FleetSummary:
    """The answers of the daemons that answered, added up."""
    daemons: int  # in the fleet
    answered: int
    map_count: int
    state_count: int
    dynamic_state_count: int
    running_operations: int
    failed_maps: int  # maps not served or whose writes stopped, over the fleet
    min_data_dir_free_bytes: int  # the daemon that fills first; 0 when none answered
    versions: list[str]  # distinct, sorted: more than one during a rolling upgrade
    recovering: list[str]  # addresses of the daemons still opening their maps


@dataclasses.dataclass(frozen=True)
class FleetStatus:
    daemons: list[DaemonStatus]  # in the fleet's order
    summary: FleetSummary


class FleetClient:
    """A fremen.Client per daemon of `addresses`, all with the same token, TLS, timeout, numpy
    choice and reconnect backoff (see fremen.connect). Usable as a context manager."""

    def __init__(self, addresses: Union[str, Sequence[str]], token: Optional[str] = None,
                 tls: Union[None, bool, str] = None, timeout: Optional[float] = 30.0,
                 use_numpy: Optional[bool] = None, reconnect: Optional[Backoff] = Backoff()) -> None:
        items = [addresses] if isinstance(addresses, str) else list(addresses)
        self._resolved = any(a.strip().startswith(EVERY_ADDRESS_PREFIX) for item in items for a in item.split(","))
        self.addresses = expand_addresses(items)
        self.clients = {a: connect(a, token=token, tls=tls, timeout=timeout, use_numpy=use_numpy,
                                   reconnect=reconnect) for a in self.addresses}
        self._placement = None if self._resolved else Placement(self.addresses)

    def close(self) -> None:
        for client in self.clients.values():
            client.close()

    def __enter__(self) -> "FleetClient":
        return self

    def __exit__(self, *exc_info: object) -> Literal[False]:
        self.close()
        return False

    def _ask_each(self, ask: Callable[[Client], _T]) -> list[Union[_T, errors.Error]]:
        """ask(client) of every daemon at once; each answer or its fremen.Error, in order."""
        def one(address: str) -> Union[_T, errors.Error]:
            try:
                return ask(self.clients[address])
            except errors.Error as error:
                return error
        with concurrent.futures.ThreadPoolExecutor(max_workers=len(self.addresses)) as pool:
            return list(pool.map(one, self.addresses))

    def list_maps(self) -> FleetMaps:
        """Every map of every daemon, each with the daemon that listed it."""
        answers = self._ask_each(lambda client: list(client.list_maps()))
        rows: list[tuple[str, int, MapInfo]] = []
        failed: list[DaemonError] = []
        for index, (address, answer) in enumerate(zip(self.addresses, answers)):
            if isinstance(answer, errors.Error):
                failed.append(DaemonError(address, answer))
                continue
            rows.extend((info.name, index, info) for info in answer)
        rows.sort(key=lambda row: (row[0], row[1]))
        held = collections.Counter(name for name, _, _ in rows)
        maps = [FleetMap(info, self.addresses[index], held[name] > 1) for name, index, info in rows]
        return FleetMaps(maps, sorted(name for name, count in held.items() if count > 1), failed)

    def server_status(self) -> FleetStatus:
        """Each daemon's ServerStatus (or the error it answered), and their sum."""
        answers = self._ask_each(lambda client: client.server_status())
        daemons = [DaemonStatus(address, None, answer) if isinstance(answer, errors.Error)
                   else DaemonStatus(address, answer, None) for address, answer in zip(self.addresses, answers)]
        up = [d.status for d in daemons if d.status is not None]
        summary = FleetSummary(
            daemons=len(daemons),
            answered=len(up),
            map_count=sum(s.map_count for s in up),
            state_count=sum(s.state_count for s in up),
            dynamic_state_count=sum(s.dynamic_state_count for s in up),
            running_operations=sum(s.running_operations for s in up),
            failed_maps=sum(len(s.failed_maps) for s in up),
            min_data_dir_free_bytes=min((s.data_dir_free_bytes for s in up), default=0),
            versions=sorted({s.version for s in up}),
            recovering=[d.address for d in daemons if d.status is not None and d.status.store_state == "recovering"],
        )
        return FleetStatus(daemons, summary)

    def client_for(self, map_name: str) -> Client:
        """The Client of the daemon that owns `map_name` by the proxy's consistent hash (for a caller
        that bypasses the proxy). The ring hashes the proxy's server strings, so the addresses must
        be written as the proxy's configuration writes them: FailedPrecondition for a fleet named
        by all:HOST:PORT."""
        if self._placement is None:
            raise errors.FailedPrecondition(
                grpc.StatusCode.FAILED_PRECONDITION,
                "the fleet was named by all:HOST:PORT; placement hashes the proxy's server strings, so name "
                "the daemons one by one, as the proxy does")
        return self.clients[self._placement.owner(map_name)]
