"""fremen.connect() and the Client: every call of the fremen.v1 API a map user needs, with Python
arguments in and Python (or numpy) values out (the admin calls come from fremen.admin). Each call
names its map in the request's `map` field and in the x-fremen-map header (so that a proxy can route
on it), sends the bearer token when one was given, and turns a failed call into a fremen.Error
subclass. Calls that may be repeated without harm (reads, RunUpdate, CancelOperation) are tried
again after UNAVAILABLE with the connect()'s backoff; the others (create, delete, backup, restore)
raise Unavailable at once, since the first try may have taken effect.

Thread-safety: a Client may be shared by threads (gRPC channels and stubs are thread-safe); an
IngestSession belongs to one thread.
"""

import dataclasses
import math
import secrets
from typing import Any, Iterator, Literal, Optional, Sequence, Union

import grpc

from fremen import arrays, errors, refs
from fremen.admin import AdminCalls
from fremen.arrays import Array
from fremen.ingest import IngestSession
from fremen.maps import MapInfo, MapStats
from fremen.model import StateModel
from fremen.refs import Cells, Ids, Names, Points
from fremen.retry import Backoff, retrying
from fremen.v1 import (admin_pb2_grpc, common_pb2, ingest_pb2, ingest_pb2_grpc, maps_pb2, maps_pb2_grpc, query_pb2,
                       query_pb2_grpc)

DEFAULT_ADDRESS = "127.0.0.1:50051"
# Seconds, one number or many.
Times = Union[float, Sequence[float]]


def connect(address: str = DEFAULT_ADDRESS, token: Optional[str] = None, tls: Union[None, bool, str] = None,
            timeout: Optional[float] = 30.0, use_numpy: Optional[bool] = None,
            reconnect: Optional[Backoff] = Backoff()) -> "Client":
    """A Client of the fremend at `address` ("host:port").

    token: a bearer token, sent as "authorization: Bearer <token>" (needed when the daemon has
    tokens: a read token for queries, a write token for the rest).
    tls: None/False for plaintext, True for TLS with the system's root certificates, or the path of
    a PEM file of root certificates to trust (e.g. the daemon's self-signed certificate).
    timeout: seconds each unary call may take (None = no limit); ingest streams have their own.
    use_numpy: None = numpy arrays when numpy is importable, False = FlatArray always.
    reconnect: the fremen.Backoff after UNAVAILABLE (bounded, jittered, exponential) for the calls
    that may be repeated and for ingest sessions, which resume their stream; None = no retries.
    """
    if reconnect is not None and not isinstance(reconnect, Backoff):
        raise errors.InvalidArgument(f"reconnect must be a fremen.Backoff or None, got {reconnect!r}")
    options = reconnect.channel_options() if reconnect is not None else []
    if tls is None or tls is False:
        channel = grpc.insecure_channel(address, options=options)
    else:
        root_certificates = None
        if tls is not True:
            with open(tls, "rb") as pem:
                root_certificates = pem.read()
        channel = grpc.secure_channel(address, grpc.ssl_channel_credentials(root_certificates), options=options)
    return Client(channel, token=token, timeout=timeout, use_numpy=use_numpy, reconnect=reconnect)


@dataclasses.dataclass(frozen=True)
class Prediction:
    """Predict's answer. probabilities[i, j] is p of states[j] at times[i] (shape times × states);
    None when states_only. states: p ≥ confidence, same shape, when a confidence was given.
    unobserved: indices j of the states the map has never observed (they predict 0.5)."""
    probabilities: Optional[Array]
    states: Optional[Array]
    unobserved: list[int]


@dataclasses.dataclass(frozen=True)
class Reconstruction:
    """Reconstruct's answer: slots[i, k] is states[i] in the slot starting at
    first_slot_time + k · slot_seconds: 0, 1, or UNOBSERVED (2) when nothing was observed then."""
    first_slot_time: float
    slot_seconds: float
    slots: Array

    UNOBSERVED = 2

    def slot_times(self) -> list[float]:
        """The start of every slot, seconds."""
        count = self.slots.shape[1] if len(self.slots.shape) == 2 else 0
        return [self.first_slot_time + k * self.slot_seconds for k in range(count)]


@dataclasses.dataclass(frozen=True)
class ScoredState:
    id: int
    name: str
    probability: float


@dataclasses.dataclass(frozen=True)
class NamedState:
    id: int
    name: str
    group: str


@dataclasses.dataclass(frozen=True)
class AnomalyCheck:
    """One element per observation checked."""
    probabilities: list[float]
    anomalous: list[bool]


_REGION_OUTPUTS = {
    "float": (query_pb2.REGION_OUTPUT_FLOAT, "float32"),
    "uint8": (query_pb2.REGION_OUTPUT_UINT8, "uint8"),
    "entropy": (query_pb2.REGION_OUTPUT_ENTROPY, "float32"),
    "states": (query_pb2.REGION_OUTPUT_STATES, "uint8"),
}

_CRITERIA = {
    "threshold": maps_pb2.ERROR_CRITERION_THRESHOLD,
    "squared": maps_pb2.ERROR_CRITERION_SQUARED,
}

_ORDER_SELECTIONS = {
    "weighted": maps_pb2.ORDER_SELECTION_WEIGHTED,
    "margin": maps_pb2.ORDER_SELECTION_MARGIN,
    "paper": maps_pb2.ORDER_SELECTION_PAPER,
}


class Client(AdminCalls):
    """Made by fremen.connect(). Usable as a context manager (closes the channel)."""

    def __init__(self, channel: grpc.Channel, token: Optional[str] = None, timeout: Optional[float] = 30.0,
                 use_numpy: Optional[bool] = None, reconnect: Optional[Backoff] = None) -> None:
        self._channel = channel
        self._reconnect = reconnect
        self._auth = [("authorization", f"Bearer {token}")] if token else []
        self._timeout = timeout
        self._use_numpy = arrays.numpy_available() if use_numpy is None else use_numpy
        if self._use_numpy and not arrays.numpy_available():
            raise errors.InvalidArgument("use_numpy=True, but numpy cannot be imported")
        self._maps = maps_pb2_grpc.MapServiceStub(channel)
        self._ingest = ingest_pb2_grpc.IngestServiceStub(channel)
        self._query = query_pb2_grpc.QueryServiceStub(channel)
        self._admin = admin_pb2_grpc.AdminServiceStub(channel)

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc_info: object) -> Literal[False]:
        self.close()
        return False

    # --- plumbing ---

    def _metadata(self, map_name: Optional[str] = None) -> list[tuple[str, str]]:
        return self._auth + ([("x-fremen-map", map_name)] if map_name else [])

    def _call(self, method: Any, request: Any, map_name: Optional[str] = None, idempotent: bool = True) -> Any:
        """One unary call; tried again after UNAVAILABLE (within the backoff) when `idempotent`."""
        def attempt() -> Any:
            try:
                return method(request, metadata=self._metadata(map_name), timeout=self._timeout)
            except grpc.RpcError as error:
                raise errors.error_from_rpc(error) from None
        return retrying(self._reconnect if idempotent else None, attempt)

    def _channel_ready(self, timeout: float) -> bool:
        """Whether the channel is connected (or connects) within `timeout` seconds."""
        future = grpc.channel_ready_future(self._channel)
        try:
            future.result(timeout=timeout)
            return True
        except grpc.FutureTimeoutError:
            future.cancel()  # stops watching the channel
            return False

    def _pages(self, method: Any, request: Any, field: str, map_name: Optional[str] = None) -> Iterator[Any]:
        """Every element of the repeated `field` over all the pages of a List call."""
        while True:
            page = self._call(method, request, map_name)
            yield from getattr(page, field)
            if not page.next_page_token:
                return
            request.page_token = page.next_page_token

    # --- maps ---

    def create_map(self, map_name: str, *, size: Optional[Sequence[int]] = None, resolution: Optional[float] = None,
                   origin: Optional[Sequence[float]] = None, kind: Optional[str] = None,
                   longest_period: Optional[float] = None, period_count: Optional[int] = None,
                   floor_periods: bool = False, periods: Optional[Sequence[float]] = None,
                   max_order: Optional[int] = None, persistence: Optional[bool] = None,
                   error_half_life: Optional[float] = None, criterion: Optional[str] = None,
                   order_selection: Optional[str] = None, order_margin: Optional[float] = None,
                   order_temperature: Optional[float] = None, lossless_sampling: float = 0.0,
                   lossless_origin: float = 0.0, shards: int = 0) -> MapInfo:
        """Creates a map and returns its MapInfo (every default filled in; its fields are named as
        these parameters).

        A grid map when `size` is given: (nx, ny) or (nx, ny, nz) cells of `resolution` metres from
        `origin` (x, y[, z]) metres; a generic map (states by id or name) otherwise. `kind` ("grid"
        or "generic") may say so explicitly. Model settings left None take the daemon's defaults:
        periods = `period_count` harmonics of `longest_period` seconds (24 of a week), or the
        explicit list `periods`; `max_order` 5; `persistence` True; `error_half_life` 7 days;
        `criterion` "threshold" or "squared"; `order_selection` "margin" (the default: a higher order
        must win by `order_margin`, 0.001), "weighted" (the mean order under weights
        exp(-(r - r_min)/`order_temperature`), temperature 0.01) or "paper" (the exact minimum);
        `lossless_sampling` seconds (0 = no lossless history); `shards` 0 = the daemon's default.
        """
        if kind is None:
            kind = "grid" if size is not None else "generic"
        kinds = {"grid": maps_pb2.MAP_KIND_GRID, "generic": maps_pb2.MAP_KIND_GENERIC}
        if kind not in kinds:
            raise errors.InvalidArgument(f"kind must be 'grid' or 'generic', got {kind!r}")
        spec = maps_pb2.Map(name=map_name, kind=kinds[kind], lossless_sampling_seconds=lossless_sampling,
                            lossless_origin=lossless_origin, shards=shards)
        if kind == "grid":
            if size is None or resolution is None:
                raise errors.InvalidArgument("a grid map needs size=(nx, ny[, nz]) and resolution= (metres)")
            s = list(size) + [0] * (3 - len(size))
            spec.grid.resolution = resolution
            spec.grid.size.CopyFrom(common_pb2.GridSize(x=s[0], y=s[1], z=s[2]))
            if origin is not None:
                o = list(origin) + [0.0] * (3 - len(origin))
                spec.grid.origin.CopyFrom(common_pb2.Point(x=o[0], y=o[1], z=o[2]))
        if longest_period is not None:
            spec.periods.longest_seconds = longest_period
        if period_count is not None:
            spec.periods.count = period_count
        spec.periods.floor_periods = floor_periods
        if periods is not None:
            spec.periods.explicit_seconds.extend(periods)
        if max_order is not None:
            spec.max_order = max_order
        if persistence is not None:
            spec.persistence = persistence
        if error_half_life is not None:
            spec.error_half_life_seconds = error_half_life
        if criterion is not None:
            if criterion not in _CRITERIA:
                raise errors.InvalidArgument(f"criterion must be 'threshold' or 'squared', got {criterion!r}")
            spec.criterion = _CRITERIA[criterion]
        if order_selection is not None:
            if order_selection not in _ORDER_SELECTIONS:
                raise errors.InvalidArgument(
                    f"order_selection must be 'weighted', 'margin' or 'paper', got {order_selection!r}")
            spec.order_selection = _ORDER_SELECTIONS[order_selection]
        if order_margin is not None:
            spec.order_margin = order_margin
        if order_temperature is not None:
            spec.order_temperature = order_temperature
        request = maps_pb2.CreateMapRequest(map=spec)
        return MapInfo.from_proto(self._call(self._maps.CreateMap, request, map_name, idempotent=False).map)

    def get_map(self, map_name: str) -> MapInfo:
        """The map's MapInfo. NotFound when there is none."""
        return MapInfo.from_proto(self._call(self._maps.GetMap, maps_pb2.GetMapRequest(map=map_name), map_name).map)

    def list_maps(self, page_size: int = 0) -> Iterator[MapInfo]:
        """Every map's MapInfo in name order, fetched a page of `page_size` at a time."""
        for message in self._pages(self._maps.ListMaps, maps_pb2.ListMapsRequest(page_size=page_size), "maps"):
            yield MapInfo.from_proto(message)

    def delete_map(self, map_name: str) -> None:
        """Deletes the map and all its data. NotFound when there is none."""
        self._call(self._maps.DeleteMap, maps_pb2.DeleteMapRequest(map=map_name), map_name, idempotent=False)

    # --- ingest ---

    def ingest(self, map_name: str, writer_id: Optional[int] = None, first_sequence: Optional[int] = None,
               max_in_flight: int = 64, timeout: Optional[float] = None, resume: bool = True) -> IngestSession:
        """An IngestSession streaming batches into `map_name`.

        (writer_id, sequence) names a batch: a robot that reconnects and resends batches not yet
        acknowledged must send them unchanged with the same writer_id and sequence numbers (the
        daemon answers the same batch applied before with duplicate=True; other content under a
        used sequence gets an Ack whose error is fremen.AlreadyExists). writer_id defaults to a
        random number, a new writer. first_sequence: the first batch's number; None = one above
        the writer's last sequence in the map (last_sequence()), so that a robot that rebooted and
        lost its count sends new batches as new. timeout: seconds the whole session may last
        (None = no limit). resume: after the stream fails with UNAVAILABLE, open a new one with
        the connect()'s backoff and resend the unanswered batches (False, or a client without
        backoff: the session fails instead).
        """
        if first_sequence is None:
            first_sequence = 1 if writer_id is None else self.last_sequence(map_name, writer_id) + 1
        if writer_id is None:
            writer_id = secrets.randbits(63) + 1
        return IngestSession(self._ingest.Ingest, map_name, self._metadata(map_name), writer_id, first_sequence,
                             max_in_flight, timeout, reconnect=self._reconnect if resume else None,
                             channel_ready=self._channel_ready)

    def last_sequence(self, map_name: str, writer_id: int) -> int:
        """The highest sequence number of `writer_id` the map has taken (0: none): a writer that
        lost its count continues one above it."""
        request = ingest_pb2.LastSequenceRequest(map=map_name, writer_id=writer_id)
        sequence: int = self._call(self._ingest.LastSequence, request, map_name).last_sequence
        return sequence

    # --- queries ---

    def predict(self, map_name: str, times: Times, *, ids: Optional[Ids] = None, names: Optional[Names] = None,
                cells: Optional[Cells] = None, points: Optional[Points] = None, persistence: bool = False,
                order: Optional[int] = None, confidence: Optional[float] = None,
                states_only: bool = False) -> Prediction:
        """p(t) of many states (exactly one of ids=, names=, cells=, points=) at many `times` (a
        number or a sequence, seconds). persistence: blend in the last observation (maps created
        with persistence). order: evaluate at this order instead of each state's selected one.
        confidence: also answer p ≥ confidence; states_only: only that."""
        request = query_pb2.PredictRequest(map=map_name, states=refs.state_refs("predict", ids, names, cells, points),
                                           times=_seconds(times), options=refs.prediction_options(persistence, order),
                                           states_only=states_only)
        if confidence is not None:
            request.confidence = confidence
        response = self._call(self._query.Predict, request, map_name)
        shape = (response.time_count, response.state_count)
        probabilities = None
        if not states_only:
            probabilities = arrays.shaped(response.probabilities, shape, "float32", self._use_numpy)
        states = None
        if confidence is not None:
            states = arrays.shaped(response.states, shape, "bool", self._use_numpy)
        return Prediction(probabilities, states, list(response.unobserved))

    def region(self, map_name: str, lo: Sequence[int], hi: Sequence[int], time: float, *, output: str = "float",
               confidence: float = 0.0, persistence: bool = False, order: Optional[int] = None,
               chunk_cells: int = 0) -> Array:
        """A box [lo, hi) of a grid at `time`, assembled from the daemon's chunks.

        lo, hi: (x, y) on a 2-D grid, giving an array of shape (ny, nx); or (x, y, z), giving
        (nz, ny, nx). Indexed [y, x] or [z, y, x]. output: "float" (p), "uint8" (round(255 p)),
        "entropy" (bits) or "states" (p ≥ confidence as 0/1). A numpy array (float32 or uint8), or
        a FlatArray without numpy.
        """
        kind, dtype, lo3, hi3, extent = _region_box(lo, hi, output)
        request = query_pb2.PredictRegionRequest(
            map=map_name, lo=common_pb2.CellIndex(x=lo3[0], y=lo3[1], z=lo3[2]),
            hi=common_pb2.CellIndex(x=hi3[0], y=hi3[1], z=hi3[2]), time=time,
            options=refs.prediction_options(persistence, order), output=kind, confidence=confidence,
            chunk_cells=chunk_cells)
        floats = dtype == "float32"

        def attempt() -> Union[list[float], bytearray]:  # the whole stream again after UNAVAILABLE: a read
            values: Union[list[float], bytearray, None] = None
            filled = 0
            try:
                for chunk in self._query.PredictRegion(request, metadata=self._metadata(map_name),
                                                       timeout=self._timeout):
                    if values is None:
                        values = [0.0] * chunk.box_cells if floats else bytearray(chunk.box_cells)
                    part = chunk.float_values if floats else chunk.bytes_values
                    values[chunk.offset:chunk.offset + len(part)] = part
                    filled += len(part)
            except grpc.RpcError as error:
                raise errors.error_from_rpc(error) from None
            if values is None or filled != len(values) or len(values) != math.prod(extent):
                raise errors.Error(grpc.StatusCode.DATA_LOSS,
                                   f"the region's chunks covered {filled} cells of a box of {extent} cells")
            return values

        values = retrying(self._reconnect, attempt)
        shape = tuple(reversed(extent))
        if isinstance(values, bytearray):
            return arrays.shaped_bytes(bytes(values), shape, self._use_numpy)
        return arrays.shaped(values, shape, dtype, self._use_numpy)

    def region_series(self, map_name: str, lo: Sequence[int], hi: Sequence[int], times: Sequence[float], *,
                      output: str = "float", confidence: float = 0.0, persistence: bool = False,
                      order: Optional[int] = None, chunk_cells: int = 0) -> list[Array]:
        """The box [lo, hi) at each of `times` (1 to 1000), one array per time as region() gives it,
        from one PredictRegionSeries stream: the cells whose prediction cannot change with time are
        sent once, the others once per time. Arguments as region()'s."""
        kind, dtype, lo3, hi3, extent = _region_box(lo, hi, output)
        request = query_pb2.PredictRegionSeriesRequest(
            map=map_name, lo=common_pb2.CellIndex(x=lo3[0], y=lo3[1], z=lo3[2]),
            hi=common_pb2.CellIndex(x=hi3[0], y=hi3[1], z=hi3[2]), times=_seconds(times),
            options=refs.prediction_options(persistence, order), output=kind, confidence=confidence,
            chunk_cells=chunk_cells)
        floats = dtype == "float32"
        box_cells = math.prod(extent)

        def attempt() -> list[Union[list[float], bytearray]]:  # the whole stream again after UNAVAILABLE
            base: Union[list[float], bytearray] = [0.0] * box_cells if floats else bytearray(box_cells)
            varying: list[int] = []
            covered = 0
            frames: list[Union[list[float], bytearray]] = []
            try:
                for chunk in self._query.PredictRegionSeries(request, metadata=self._metadata(map_name),
                                                             timeout=self._timeout):
                    part = chunk.float_values if floats else chunk.bytes_values
                    if chunk.base:
                        mask = chunk.varying_mask
                        constant = [chunk.offset + j for j in range(chunk.cells) if not (mask[j // 8] >> (j % 8)) & 1]
                        varying.extend(chunk.offset + j for j in range(chunk.cells) if (mask[j // 8] >> (j % 8)) & 1)
                        if chunk.offset != covered or len(constant) != len(part) or \
                                chunk.offset + chunk.cells > box_cells:
                            raise errors.Error(grpc.StatusCode.DATA_LOSS, "a region series base chunk does not fit")
                        for cell, value in zip(constant, part):
                            base[cell] = value
                        covered += chunk.cells
                        continue
                    if chunk.offset == 0:
                        if chunk.time_index != len(frames) or covered != box_cells:
                            raise errors.Error(grpc.StatusCode.DATA_LOSS, "a region series frame out of order")
                        frames.append(base[:])
                    for cell, value in zip(varying[chunk.offset:chunk.offset + len(part)], part):
                        frames[-1][cell] = value
            except grpc.RpcError as error:
                raise errors.error_from_rpc(error) from None
            if not varying:
                frames = [base[:] for _ in request.times]
            if covered != box_cells or len(frames) != len(request.times):
                raise errors.Error(grpc.StatusCode.DATA_LOSS,
                                   f"the region series covered {covered} of {box_cells} cells and "
                                   f"{len(frames)} of {len(request.times)} times")
            return frames

        shape = tuple(reversed(extent))
        result: list[Array] = []
        for values in retrying(self._reconnect, attempt):
            if isinstance(values, bytearray):
                result.append(arrays.shaped_bytes(bytes(values), shape, self._use_numpy))
            else:
                result.append(arrays.shaped(values, shape, dtype, self._use_numpy))
        return result

    def model(self, map_name: str, *, id: Optional[int] = None, name: Optional[str] = None,  # noqa: A002
              cell: Optional[Sequence[int]] = None, point: Optional[Sequence[float]] = None,
              include_spectrum: bool = False) -> Optional[StateModel]:
        """One state's StateModel (exactly one of id=, name=, cell=, point=; its `proto` is the
        fremen.v1.StateModel, with the lossless history's details); None when the state was never
        observed."""
        request = query_pb2.GetStateModelRequest(map=map_name, state=refs.state_ref("model", id, name, cell, point),
                                                 include_spectrum=include_spectrum)
        response = self._call(self._query.GetStateModel, request, map_name)
        if not response.HasField("model"):
            return None
        return StateModel.from_proto(response.model)

    def reconstruct(self, map_name: str, start: float, end: float, *, ids: Optional[Ids] = None,
                    names: Optional[Names] = None, cells: Optional[Cells] = None,
                    points: Optional[Points] = None) -> Reconstruction:
        """The exact past states of a lossless map (created with lossless_sampling > 0) in the
        sampling slots overlapping [start, end) seconds, of the states named (exactly one of ids=,
        names=, cells=, points=): a Reconstruction whose slots[state, slot] is 0, 1 or 2 =
        unobserved (a uint8 array of shape (states, slots), or a FlatArray). FailedPrecondition on
        a map without lossless history."""
        request = query_pb2.ReconstructRequest(map=map_name,
                                               states=refs.state_refs("reconstruct", ids, names, cells, points),
                                               start_time=start, end_time=end)
        response = self._call(self._query.Reconstruct, request, map_name)
        count = len(response.histories[0].slots) if response.histories else 0
        data = b"".join(history.slots for history in response.histories)
        slots = arrays.shaped_bytes(data, (len(response.histories), count), self._use_numpy)
        return Reconstruction(response.first_slot_time, response.slot_seconds, slots)

    def stats(self, map_name: str) -> MapStats:
        """The map's MapStats: states, observations, bytes, orders, errors, its last update."""
        request = query_pb2.GetMapStatsRequest(map=map_name)
        return MapStats.from_proto(self._call(self._query.GetMapStats, request, map_name).stats)

    def top(self, map_name: str, group: str, time: float, n: int = 10, *, persistence: bool = False,
            order: Optional[int] = None) -> list[ScoredState]:
        """The n states of `group` most likely to be 1 at `time`, most likely first (generic maps)."""
        request = query_pb2.TopStatesRequest(map=map_name, group=group, time=time, n=n,
                                             options=refs.prediction_options(persistence, order))
        response = self._call(self._query.TopStates, request, map_name)
        return [ScoredState(s.id, s.name, s.probability) for s in response.states]

    def list_states(self, map_name: str, group: str = "", page_size: int = 0) -> Iterator[NamedState]:
        """The named states of a generic map (or of one `group`) in name order, a page at a time."""
        request = query_pb2.ListStatesRequest(map=map_name, group=group, page_size=page_size)
        for s in self._pages(self._query.ListStates, request, "states", map_name):
            yield NamedState(s.id, s.name, s.group)

    def anomalies(self, map_name: str, values: Sequence[float], times: Times, confidence: float, *,
                  ids: Optional[Ids] = None, names: Optional[Names] = None, cells: Optional[Cells] = None,
                  points: Optional[Points] = None, persistence: bool = False,
                  order: Optional[int] = None) -> AnomalyCheck:
        """Which observations (`values` of the states named, at `times`: one per state or a single
        one) are anomalous at `confidence` in [0.5, 1]."""
        request = query_pb2.CheckAnomaliesRequest(
            map=map_name, states=refs.state_refs("anomalies", ids, names, cells, points),
            values=[float(v) for v in values], times=_seconds(times), confidence=confidence,
            options=refs.prediction_options(persistence, order))
        response = self._call(self._query.CheckAnomalies, request, map_name)
        return AnomalyCheck(list(response.probabilities), list(response.anomalous))


def _seconds(times: Times) -> list[float]:
    """One time or many as the list the requests carry."""
    if isinstance(times, (int, float)):
        return [float(times)]
    return [float(t) for t in times]


def _region_box(lo: Sequence[int], hi: Sequence[int],
                output: str) -> tuple[query_pb2.RegionOutput, str, list[int], list[int], list[int]]:
    """A region request's output kind and dtype, its corners as (x, y, z), and the box's extent as
    given ((x, y) or (x, y, z))."""
    if len(lo) != len(hi) or len(lo) not in (2, 3):
        raise errors.InvalidArgument(f"lo and hi must both be (x, y) or (x, y, z), got {lo!r} and {hi!r}")
    if output not in _REGION_OUTPUTS:
        raise errors.InvalidArgument(f"output must be one of {', '.join(_REGION_OUTPUTS)}, got {output!r}")
    kind, dtype = _REGION_OUTPUTS[output]
    lo3 = list(lo) + [0] * (3 - len(lo))
    hi3 = list(hi) + [0] * (3 - len(hi))
    extent = [max(high - low, 0) for low, high in zip(lo, hi)]
    return kind, dtype, lo3, hi3, extent
