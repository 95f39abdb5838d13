"""What the client answers about a map: MapInfo (its settings, as create_map, get_map, list_maps and
restore_map return them), MapStats (stats()) and MapUpdate (what its last update job did).

MapInfo's fields are named as create_map's parameters, so that a map's settings read as they were
given. Like every result class of the package, each carries the message it came from as `proto`
(not compared, not shown), for a field a newer daemon sends that this class does not know yet.
"""

import dataclasses
from typing import Optional

from fremen import proto_values
from fremen.v1 import maps_pb2, query_pb2


@dataclasses.dataclass(frozen=True)
class MapInfo:
    """A map's settings with every default filled in by the daemon."""
    name: str
    kind: str  # "grid" or "generic"
    size: Optional[tuple[int, int, int]]  # grid maps: cells (nx, ny, nz), nz = 1 in 2-D; None in generic ones
    resolution: Optional[float]  # grid maps: metres per cell
    origin: Optional[tuple[float, float, float]]  # grid maps: metres, the corner of cell (0, 0, 0)
    longest_period: Optional[float]  # seconds; None when `periods` lists them
    period_count: Optional[int]
    floor_periods: bool
    periods: list[float]  # explicit periods, seconds (empty: longest_period and period_count)
    max_order: Optional[int]
    persistence: Optional[bool]
    error_half_life: Optional[float]  # seconds
    criterion: str  # "threshold" or "squared"
    order_selection: str  # "weighted", "margin" or "paper"
    order_margin: Optional[float]  # the margin rule's margin
    order_temperature: Optional[float]  # the weighted rule's temperature
    lossless_sampling: float  # seconds; 0 = no lossless history
    lossless_origin: float
    shards: int
    create_time: Optional[float]  # seconds since the epoch
    proto: maps_pb2.Map = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, message: maps_pb2.Map) -> "MapInfo":
        grid = message.grid if message.HasField("grid") else None
        periods = message.periods
        return cls(
            name=message.name,
            kind=proto_values.word(maps_pb2.MapKind, message.kind, "MAP_KIND_"),
            size=proto_values.triple(grid.size) if grid is not None else None,
            resolution=grid.resolution if grid is not None else None,
            origin=proto_values.triple(grid.origin) if grid is not None else None,
            longest_period=periods.longest_seconds if periods.HasField("longest_seconds") else None,
            period_count=periods.count if periods.HasField("count") else None,
            floor_periods=periods.floor_periods,
            periods=list(periods.explicit_seconds),
            max_order=message.max_order if message.HasField("max_order") else None,
            persistence=message.persistence if message.HasField("persistence") else None,
            error_half_life=(message.error_half_life_seconds if message.HasField("error_half_life_seconds")
                             else None),
            # UNSPECIFIED is the daemon's default, SQUARED (the daemon always answers with the value).
            criterion=("squared" if message.criterion == maps_pb2.ERROR_CRITERION_UNSPECIFIED
                       else proto_values.word(maps_pb2.ErrorCriterion, message.criterion, "ERROR_CRITERION_")),
            order_selection=("weighted" if message.order_selection == maps_pb2.ORDER_SELECTION_UNSPECIFIED
                             else proto_values.word(maps_pb2.OrderSelection, message.order_selection,
                                                    "ORDER_SELECTION_")),
            order_margin=message.order_margin if message.HasField("order_margin") else None,
            order_temperature=message.order_temperature if message.HasField("order_temperature") else None,
            lossless_sampling=message.lossless_sampling_seconds,
            lossless_origin=message.lossless_origin,
            shards=message.shards,
            create_time=proto_values.seconds(message.create_time),
            proto=message,
        )


@dataclasses.dataclass(frozen=True)
class MapUpdate:
    """What an update job did to a map."""
    start_time: Optional[float]  # seconds since the epoch
    duration_seconds: float
    states_updated: int  # states observed since their last update, whose P was republished
    prediction_error_before: float  # mean decayed ε_p at the selected orders, before and after
    prediction_error_after: float
    order_histogram: list[int]  # dynamic states by selected order 0..L after the update
    proto: query_pb2.MapUpdate = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, message: query_pb2.MapUpdate) -> "MapUpdate":
        return cls(proto_values.seconds(message.start_time), message.duration_seconds, message.states_updated,
                   message.prediction_error_before, message.prediction_error_after,
                   list(message.order_histogram), message)


@dataclasses.dataclass(frozen=True)
class MapStats:
    """A map's statistics (docs/model.md explains the errors)."""
    states: int
    dynamic_states: int  # states that changed at least once (and so hold a spectrum)
    observations: int
    disk_bytes: int
    memory_bytes: int
    log_bytes: int
    order_histogram: list[int]  # dynamic states by selected order 0..L
    mean_prediction_error: float  # mean ε_p over dynamic states with evidence
    compression_ratio: float  # raw observations (one bit each) over the bytes holding the models
    lossless_estimation_error: float  # lossless maps (0 otherwise)
    lossless_prediction_error: float
    last_update: Optional[MapUpdate]  # None before the first update
    proto: query_pb2.MapStats = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, message: query_pb2.MapStats) -> "MapStats":
        return cls(
            states=message.states,
            dynamic_states=message.dynamic_states,
            observations=message.observations,
            disk_bytes=message.disk_bytes,
            memory_bytes=message.memory_bytes,
            log_bytes=message.log_bytes,
            order_histogram=list(message.order_histogram),
            mean_prediction_error=message.mean_prediction_error,
            compression_ratio=message.compression_ratio,
            lossless_estimation_error=message.lossless_estimation_error,
            lossless_prediction_error=message.lossless_prediction_error,
            last_update=MapUpdate.from_proto(message.last_update) if message.HasField("last_update") else None,
            proto=message,
        )
