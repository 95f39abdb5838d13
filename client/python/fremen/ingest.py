"""A batched ingest session over IngestService.Ingest streams (bidirectional).

Each send() puts one batch (one scan: a time and many (state, value) pairs) on the stream with the
session's writer id and the next sequence number, and returns that number. The daemon answers every
batch, in order, once it is durable and applied (or refused): wait() blocks until every batch sent
so far is answered and returns the new acknowledgements; close() ends the stream and returns the
rest.

Why a reader thread: gRPC delivers answers only while someone reads them, and the daemon stops
reading batches (flow control) while its answers pile up, so a caller that sends many batches
before waiting would stall both sides. The reader keeps answers flowing; `max_in_flight` bounds the
batches sent but not yet answered, so send() blocks instead of queueing without bound.

Resuming: when the stream fails with UNAVAILABLE (the daemon restarted, the network dropped) and
the session has a fremen.Backoff, the reader opens a new stream after each of its pauses and puts
the unanswered() batches on it again, unchanged, with their writer id and sequence numbers: the
daemon applies those it lacks and answers the others with duplicate=True (it recognises the same
batch among a writer's last 256 sequences), so every batch is answered once and applied once.

Writers: a batch is a duplicate only if it is the same batch. Other content under a sequence the
writer already used (a robot that rebooted and counts from 1 again) is refused, never dropped: its
Ack's error is a fremen.AlreadyExists naming the sequence to continue after. Client.ingest() with
a writer_id and no first_sequence starts after the writer's last sequence in the map, so that a
rebooted writer loses nothing. Each stream has its own queue of requests, because gRPC's sender thread of a dead
stream may still take one batch from its queue (that batch is among the unanswered ones resent).

A batch refused as a whole comes back as an Ack whose `error` is set (the stream goes on); a stream
that fails otherwise (unknown map, missing token, a message the daemon cannot parse —
InvalidArgument naming its position —, the daemon away longer than the backoff allows) makes the
next send/wait/close raise the fremen.Error. Its unanswered() batches may then have been
applied or not: a new session of the same writer id resend()s them, and the daemon applies each
exactly once. Thread-safety: one thread sends; wait/close from that thread too.
"""

import collections
import dataclasses
import queue
import threading
import time as time_module
from types import TracebackType
from typing import Any, Callable, Iterable, Iterator, Literal, Optional, Sequence, Union

import grpc

from fremen import compact, errors, proto_values, refs
from fremen.refs import Cells, Ids, Names, Points
from fremen.retry import Backoff
from fremen.v1 import common_pb2, ingest_pb2

# A batch as sent: what unanswered() gives and resend() takes (opaque to callers, who pass it on).
Batch = ingest_pb2.IngestRequest
_END = object()  # ends the request iterator
# Seconds a stream's answers may take to end after its call ended before the stream counts as
# failed with the call's status (see _read_stream).
STUCK_GRACE = 5.0


@dataclasses.dataclass(frozen=True)
class Rejection:
    """One observation not applied: its position in the batch and why ("value_out_of_range",
    "outside_map")."""
    index: int
    reason: str


@dataclasses.dataclass(frozen=True)
class Ack:
    """The daemon's answer to one batch."""
    sequence: int
    accepted: int
    rejected: int
    duplicate: bool  # a retry of a batch applied before: nothing applied this time
    rejections: list[Rejection]  # the first ones (at most 16)
    error: Optional[errors.Error]  # when the batch was refused as a whole

    @property
    def ok(self) -> bool:
        return self.error is None

    @classmethod
    def from_proto(cls, response: ingest_pb2.IngestResponse) -> "Ack":
        error = proto_values.error(response.error) if response.HasField("error") else None
        rejections = [Rejection(r.index, proto_values.word(ingest_pb2.RejectReason, r.reason, "REJECT_REASON_"))
                      for r in response.rejections]
        return cls(response.sequence, response.accepted, response.rejected, response.duplicate, rejections, error)


class IngestSession:
    """Made by Client.ingest(); use as a context manager or call close()."""

    def __init__(self, ingest_method: Any, map_name: str, metadata: list[tuple[str, str]], writer_id: int,
                 first_sequence: int, max_in_flight: int, timeout: Optional[float], reconnect: Optional[Backoff] = None,
                 channel_ready: Optional[Callable[[float], bool]] = None) -> None:
        """reconnect: the fremen.Backoff to resume with after UNAVAILABLE (None = do not resume);
        channel_ready(timeout): whether the channel is connected within `timeout` seconds."""
        if max_in_flight < 1:
            raise errors.InvalidArgument(f"max_in_flight must be at least 1, got {max_in_flight}")
        self.map_name = map_name
        self.writer_id = writer_id
        # The sequence number the next send() uses unless told otherwise.
        self.next_sequence = first_sequence
        self._max_in_flight = max_in_flight
        self._reconnect = reconnect
        self._channel_ready = channel_ready
        self._deadline = None if timeout is None else time_module.monotonic() + timeout
        self._open_call: Callable[[Iterator[Batch], Optional[float]], Any] = (
            lambda requests, timeout: ingest_method(requests, metadata=metadata, timeout=timeout))
        self._lock = threading.Condition()
        self._unanswered: collections.deque[Batch] = collections.deque()  # sent, oldest first, not yet answered
        self._new_acks: list[Ack] = []
        self._failure: Optional[errors.Error] = None  # the fremen.Error that ended the session
        self._ended = False  # the reader is done: no more answers will come
        self._closed = False
        self._cancelled = threading.Event()
        self._reconnects = 0
        self._requests: queue.Queue[Any] = queue.Queue()  # the current stream's: batches, then _END
        self._call = self._open_stream(self._requests)
        self._reader = threading.Thread(target=self._read_acks, name=f"fremen-ingest-{map_name}", daemon=True)
        self._reader.start()

    # --- sending ---

    def send(self, time: float, values: Iterable[float], *, ids: Optional[Ids] = None, names: Optional[Names] = None,
             groups: Optional[Iterable[str]] = None, cells: Optional[Cells] = None, points: Optional[Points] = None,
             sequence: Optional[int] = None) -> int:
        """Sends one batch: observations `values` (each in [0, 1]) at `time` (seconds) of the states
        named by exactly one of ids= / names= (generic maps; groups= optionally labels each state
        the first time it is seen) or cells= / points= (grid maps). sequence: the batch's number
        instead of the next one (later batches continue above it). Returns its sequence number."""
        request = ingest_pb2.IngestRequest(map=self.map_name, writer_id=self.writer_id, time=time)
        floats = [float(v) for v in values]
        kind = refs.chosen_kind({"ids": ids, "names": names, "cells": cells, "points": points}, "send")
        if groups is not None and kind not in ("ids", "names"):
            raise errors.InvalidArgument("groups= labels generic states (ids= or names=), not grid cells")
        labels = list(groups) if groups is not None else []
        if ids is not None:
            request.states.ids.extend(int(i) for i in ids)
            request.states.values.extend(floats)
            request.states.groups.extend(labels)
        elif names is not None:
            request.named_states.names.extend(names)
            request.named_states.values.extend(floats)
            request.named_states.groups.extend(labels)
        elif cells is not None:
            request.cells.cells.CopyFrom(refs.cell_indices(cells))
            request.cells.values.extend(floats)
        else:
            assert points is not None  # chosen_kind saw exactly one given
            request.points.points.CopyFrom(refs.points(points))
            request.points.values.extend(floats)
        return self._put(request, sequence)

    def send_history(self, times: Iterable[float], values: Iterable[float], *, ids: Optional[Ids] = None,
                     names: Optional[Names] = None, groups: Optional[Iterable[str]] = None,
                     sequence: Optional[int] = None) -> int:
        """Sends a history (generic maps): observations `values` (each in [0, 1]) each at its own
        time in `times` (seconds) — a robot's log uploaded, a dataset imported — as one batch
        instead of one per time. The states: exactly one of ids= / names=, either one per value or
        a single one (one state's history, sent once); groups= optionally labels each of them. The
        daemon applies it exactly as one scan per run of consecutive observations with the same
        time, in the order given (so give a log in time order). Returns its sequence number."""
        request = ingest_pb2.IngestRequest(map=self.map_name, writer_id=self.writer_id)
        kind = refs.chosen_kind({"ids": ids, "names": names}, "send_history")
        history = request.history
        history.times.extend(float(t) for t in times)
        history.values.extend(float(v) for v in values)
        if kind == "ids":
            assert ids is not None
            history.ids.extend(int(i) for i in ids)
        else:
            assert names is not None
            history.names.extend(names)
        if groups is not None:
            history.groups.extend(groups)
        return self._put(request, sequence)

    def send_patch(self, time: float, origin: Sequence[int], size: Sequence[int], *, values: Optional[Any] = None,
                   probabilities: Optional[Union[bytes, bytearray, Sequence[int]]] = None,
                   sequence: Optional[int] = None) -> int:
        """Sends a dense box of a grid map: `origin` (x, y[, z]) its first cell, `size` (nx, ny[, nz])
        its cells, and either `values` (floats in [0, 1], x fastest, then y, then z; a numpy array
        of shape (nz, ny, nx) or (ny, nx) is flattened in that order) or `probabilities` (bytes, one
        per cell, s = byte / 255). Returns its sequence number."""
        if (values is None) == (probabilities is None):
            raise errors.InvalidArgument("send_patch needs exactly one of values= and probabilities=")
        request = ingest_pb2.IngestRequest(map=self.map_name, writer_id=self.writer_id, time=time)
        o = list(origin) + [0] * (3 - len(origin))
        s = list(size) + [1] * (3 - len(size))
        request.patch.origin.CopyFrom(common_pb2.CellIndex(x=o[0], y=o[1], z=o[2]))
        request.patch.size.CopyFrom(common_pb2.GridSize(x=s[0], y=s[1], z=s[2]))
        if values is not None:
            flat = values.ravel() if hasattr(values, "ravel") else values
            request.patch.values.extend(float(v) for v in flat)
        elif probabilities is not None:
            request.patch.probabilities = bytes(probabilities)
        return self._put(request, sequence)

    def send_compact(self, time: float, indices: Iterable[int], *, occupied: Optional[Sequence[float]] = None,
                     probabilities: Optional[Union[bytes, bytearray, Sequence[int]]] = None,
                     sequence: Optional[int] = None) -> int:
        """Sends cells of a grid map compactly (fremen.v1.CompactCells, ~1.1 bytes a binary
        observation): `indices` their linear indices x + nx·(y + ny·z), strictly increasing, and
        either `occupied` (0 or 1 per cell, one bit each on the wire) or `probabilities` (bytes,
        one per cell, s = byte / 255). Cells past the grid are rejected one by one as outside the
        map, as with cells=. Returns its sequence number."""
        if (occupied is None) == (probabilities is None):
            raise errors.InvalidArgument("send_compact needs exactly one of occupied= and probabilities=")
        request = ingest_pb2.IngestRequest(map=self.map_name, writer_id=self.writer_id, time=time)
        request.compact.indices = compact.index_gaps(indices)
        if occupied is not None:
            request.compact.occupied = compact.occupied_bits(list(occupied))
        elif probabilities is not None:
            request.compact.probabilities = bytes(probabilities)
        return self._put(request, sequence)

    def resend(self, batches: Iterable[Batch]) -> None:
        """Sends again batches that another session of the same writer sent but never saw answered
        (its unanswered() after the stream failed), with their own sequence numbers: the daemon
        applies those it lacks and answers the others with duplicate=True, so that nothing is lost
        or applied twice. Later send()s continue after the highest sequence resent."""
        for batch in batches:
            if batch.writer_id != self.writer_id:
                raise errors.InvalidArgument(
                    f"resend: batch {batch.sequence} is of writer {batch.writer_id}, this session writes as "
                    f"{self.writer_id}: open it with ingest(..., writer_id={batch.writer_id})")
            request = ingest_pb2.IngestRequest()
            request.CopyFrom(batch)
            request.map = self.map_name
            self._put(request, request.sequence)

    def unanswered(self) -> list[Batch]:
        """The batches (fremen.v1.IngestRequest messages) sent and not answered yet, oldest first: after the
        stream failed, the ones to resend() in a new session."""
        with self._lock:
            return list(self._unanswered)

    def _put(self, request: Batch, sequence: Optional[int]) -> int:
        """Numbers the batch (`sequence`, or the next one when None) and queues it for the stream;
        blocks while max_in_flight batches are unanswered. The batch's sequence number."""
        with self._lock:
            if self._closed:
                raise errors.error_for(grpc.StatusCode.FAILED_PRECONDITION, "the ingest session is closed")
            self._lock.wait_for(lambda: self._failure or self._ended or len(self._unanswered) < self._max_in_flight)
            self._raise_if_ended()
            request.sequence = self.next_sequence if sequence is None else sequence
            # Numbers only go up, so that the next batch is never under a sequence already used.
            self.next_sequence = max(self.next_sequence, request.sequence + 1)
            self._unanswered.append(request)
            # Under the lock: a resumed stream takes either this batch from unanswered or this
            # queue, never neither.
            self._requests.put(request)
        return request.sequence

    @property
    def reconnects(self) -> int:
        """How many times the session opened a new stream after UNAVAILABLE."""
        with self._lock:
            return self._reconnects

    # --- streams ---

    def _open_stream(self, requests: "queue.Queue[Any]") -> Any:
        """Starts an Ingest call that sends what `requests` (a queue ended by _END) holds."""
        def iterate() -> Iterator[Batch]:
            while (request := requests.get()) is not _END:
                yield request
        timeout = None
        if self._deadline is not None:
            timeout = max(self._deadline - time_module.monotonic(), 0.001)
        return self._open_call(iterate(), timeout)

    def _resume(self) -> bool:
        """Replaces the failed stream by a new one that starts with the unanswered batches. False
        when the session was cancelled meanwhile."""
        with self._lock:
            if self._cancelled.is_set():
                return False
            dead, self._requests = self._requests, queue.Queue()
            for batch in self._unanswered:
                self._requests.put(batch)
            if self._closed:
                self._requests.put(_END)
            self._reconnects += 1
            self._call = self._open_stream(self._requests)
        dead.put(_END)  # the failed stream's sender, if it still waits for a batch, stops
        return True

    # --- acknowledgements ---

    def _read_acks(self) -> None:
        """The reader thread: the answers of each stream, and a new stream after UNAVAILABLE for as
        long as the backoff allows (its count of tries starts again once a stream answered)."""
        pauses: Optional[Iterator[float]] = None
        failure = None
        try:
            while True:
                answered, failure = self._read_stream(self._call)
                backoff = self._reconnect
                if backoff is None or not self._may_resume(failure):
                    break
                if pauses is None or answered:
                    pauses = backoff.pauses()
                if not self._await_daemon(pauses) or not self._resume():
                    break
        finally:
            with self._lock:
                self._failure = failure
                self._ended = True
                self._lock.notify_all()
                requests = self._requests
            requests.put(_END)  # the daemon is gone: stop the sender

    def _await_daemon(self, pauses: Iterator[float]) -> bool:
        """Waits, a pause at a time, until the channel is connected again; False when the pauses
        ran out or the session was cancelled. Why not simply open a stream after each pause: a
        stream that fails at once (connection refused) while gRPC sends the batches queued on it
        can leave gRPC's response iterator waiting for ever (python3-grpcio 1.51), so a new stream
        is opened only on a connected channel. A session made without channel_ready does not
        resume."""
        ready = self._channel_ready
        if ready is None:
            return False
        for pause in pauses:
            if ready(pause):
                return not self._cancelled.is_set()
            if self._cancelled.is_set():
                return False
        return False

    def _read_stream(self, call: Any) -> tuple[int, Optional[errors.Error]]:
        """(answers read, the fremen.Error that ended the stream or None).

        The answers are read on a thread of their own because gRPC's response iterator can wait for
        ever after its call ended (python3-grpcio 1.51, rarely, for a call that fails at once):
        once the call is done, its answers must end within STUCK_GRACE seconds, or the stream
        counts as failed with the call's status and the stuck thread is abandoned (anything it
        might still read is dropped; those batches stay unanswered and are resent)."""
        state: dict[str, Any] = {"answered": 0, "abandoned": False, "failure": None}
        finished = threading.Event()
        call_done = threading.Event()

        def receive() -> None:
            try:
                for response in call:
                    with self._lock:
                        if state["abandoned"]:
                            return
                        self._new_acks.append(Ack.from_proto(response))
                        self._unanswered.popleft()  # answers come in the order of the batches
                        state["answered"] += 1
                        self._lock.notify_all()
            except grpc.RpcError as error:
                state["failure"] = errors.error_from_rpc(error)
            finally:
                finished.set()

        threading.Thread(target=receive, name=f"fremen-ingest-answers-{self.map_name}", daemon=True).start()
        call.add_done_callback(lambda _: call_done.set())
        call_done.wait()
        if finished.wait(STUCK_GRACE):
            return state["answered"], state["failure"]
        with self._lock:
            state["abandoned"] = True
            return state["answered"], errors.error_for(call.code(), call.details() or "the ingest stream ended")

    def _may_resume(self, failure: Optional[errors.Error]) -> bool:
        """Whether to open another stream (the session having a backoff): after UNAVAILABLE, unless
        the session was cancelled or was closed with every batch answered (nothing left to send)."""
        with self._lock:
            finished = self._closed and not self._unanswered
        return isinstance(failure, errors.Unavailable) and not self._cancelled.is_set() and not finished

    def _raise_if_ended(self) -> None:
        # Called with the lock held.
        if self._failure is not None:
            raise self._failure
        if self._ended and self._unanswered:
            raise errors.error_for(grpc.StatusCode.UNKNOWN,
                                   f"the ingest stream ended with {len(self._unanswered)} batches unanswered")

    def wait(self, timeout: Optional[float] = None) -> list[Ack]:
        """Blocks until every batch sent so far is answered; returns the Acks that came since the
        last wait() (in sequence order). Raises the stream's fremen.Error if it failed, and
        DeadlineExceeded after `timeout` seconds."""
        deadline = None if timeout is None else time_module.monotonic() + timeout
        with self._lock:
            while self._unanswered and not self._failure and not self._ended:
                remaining = None if deadline is None else deadline - time_module.monotonic()
                if remaining is not None and remaining <= 0:
                    raise errors.error_for(
                        grpc.StatusCode.DEADLINE_EXCEEDED,
                        f"{len(self._unanswered)} batches still unanswered after {timeout} s")
                self._lock.wait(remaining)
            self._raise_if_ended()
            acks, self._new_acks = self._new_acks, []
            return acks

    def close(self, timeout: Optional[float] = None) -> list[Ack]:
        """Ends the stream after the batches sent, waits for their answers and the daemon's end of
        the call; returns the Acks not yet returned by wait(). Raises the stream's fremen.Error."""
        with self._lock:
            if not self._closed:
                self._closed = True
                self._requests.put(_END)
        self._reader.join(timeout)
        if self._reader.is_alive():
            self.cancel()
            raise errors.error_for(grpc.StatusCode.DEADLINE_EXCEEDED,
                                   f"the ingest stream did not end within {timeout} s")
        return self.wait()

    def cancel(self) -> None:
        """Abandons the stream: batches not yet answered may or may not have been applied (resend
        them with the same writer id and sequence numbers to find out)."""
        with self._lock:
            self._closed = True
            self._cancelled.set()
            call, requests = self._call, self._requests
        call.cancel()
        requests.put(_END)
        self._reader.join()

    def __enter__(self) -> "IngestSession":
        return self

    def __exit__(self, exc_type: Optional[type[BaseException]], exc: Optional[BaseException],
                 traceback: Optional[TracebackType]) -> Literal[False]:
        if exc_type is None:
            self.close()
        else:
            self.cancel()
        return False
