"""The daemon's status (server_status()) and a backup's result (backup_map()), as the admin calls
return them."""

import dataclasses
from typing import Optional

from fremen import proto_values
from fremen.maps import MapUpdate
from fremen.operations import Operation
from fremen.v1 import admin_pb2


@dataclasses.dataclass(frozen=True)
class Backup:
    path: str  # the copy's directory as the daemon sees it
    bytes: int
    duration_seconds: float
    proto: admin_pb2.BackupMapResponse = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, message: admin_pb2.BackupMapResponse) -> "Backup":
        return cls(message.path, message.bytes, message.duration_seconds, message)


@dataclasses.dataclass(frozen=True)
class CheckProblem:
    """One thing found wrong in a map's files."""
    file: str  # relative to the map's directory, e.g. "shard-2/data.mdb"
    location: str  # where in it; may be empty
    description: str


@dataclasses.dataclass(frozen=True)
class MapScrub:
    """What the latest background scrub (setting scrub_interval) of a map found."""
    finish_time: Optional[float]  # seconds since the epoch
    duration_seconds: float
    clean: bool
    problem_count: int  # every problem found; the first few are in `problems`
    problems: list[CheckProblem]
    records: int  # shard records read and checked


@dataclasses.dataclass(frozen=True)
class ServerStatus:
    """The daemon as it is now. The dictionaries are keyed by map name."""
    version: str  # fremend's version, e.g. "0.1.0"
    start_time: Optional[float]  # seconds since the epoch
    uptime_seconds: float
    store_state: str  # "recovering" (opening the maps; map calls answer UNAVAILABLE) or "open"
    map_count: int
    state_count: int  # over every map
    dynamic_state_count: int
    running_operations: int
    update_schedule: str  # cron, as configured (empty: never)
    update_time_zone: str
    next_update_time: Optional[float]  # None when there is no schedule
    tls: bool
    tokens_required: bool
    data_dir_free_bytes: int
    last_updates: dict[str, Operation]  # each map's latest finished update the daemon still keeps
    map_updates: dict[str, MapUpdate]  # each map's last update as its store keeps it, across restarts
    failed_maps: dict[str, str]  # maps not served or whose writes stopped: the storage error
    unknown_directories: list[str]  # under the data directory's maps/, named by no catalog record
    next_scrub_time: Optional[float]  # None when scrubbing is off
    map_scrubs: dict[str, MapScrub]  # maps not yet scrubbed are absent
    proto: admin_pb2.GetServerStatusResponse = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, message: admin_pb2.GetServerStatusResponse) -> "ServerStatus":
        def scrub(s: admin_pb2.MapScrub) -> MapScrub:
            problems = [CheckProblem(p.file, p.location, p.description) for p in s.problems]
            return MapScrub(proto_values.seconds(s.finish_time), s.duration_seconds, s.clean, s.problem_count,
                            problems, s.records)
        return cls(
            version=message.version,
            start_time=proto_values.seconds(message.start_time),
            uptime_seconds=message.uptime_seconds,
            store_state=proto_values.word(admin_pb2.StoreState, message.store_state, "STORE_STATE_"),
            map_count=message.map_count,
            state_count=message.state_count,
            dynamic_state_count=message.dynamic_state_count,
            running_operations=message.running_operations,
            update_schedule=message.update_schedule,
            update_time_zone=message.update_time_zone,
            next_update_time=proto_values.seconds(message.next_update_time),
            tls=message.tls,
            tokens_required=message.tokens_required,
            data_dir_free_bytes=message.data_dir_free_bytes,
            last_updates={op.map: Operation.from_proto(op) for op in message.last_updates},
            map_updates={u.map: MapUpdate.from_proto(u.update) for u in message.map_updates},
            failed_maps={f.map: f.error for f in message.failed_maps},
            unknown_directories=list(message.unknown_directories),
            next_scrub_time=proto_values.seconds(message.next_scrub_time),
            map_scrubs={s.map: scrub(s) for s in message.map_scrubs},
            proto=message,
        )
