"""The daemon's operations (update jobs) as the admin calls return them: Operation, its Progress
and, once done, its UpdateResult or its error."""

import dataclasses
from typing import Optional

from fremen import errors, proto_values
from fremen.v1 import admin_pb2


@dataclasses.dataclass(frozen=True)
class Progress:
    states_done: int
    states_total: int
    rate: float  # states per second, so far
    eta_seconds: float  # 0 when unknown


@dataclasses.dataclass(frozen=True)
class UpdateResult:
    """What a finished update did."""
    states_published: int  # states whose P was recomputed (observed since their last update)
    duration_seconds: float
    order_histogram: list[int]  # dynamic states by selected order 0..L once published
    prediction_error_before: float  # mean decayed ε_p at the previous orders and at the new ones
    prediction_error_after: float


@dataclasses.dataclass(frozen=True)
class Operation:
    """An update job of a map, as it is when asked."""
    name: str  # "operations/<id>"
    map_name: str
    trigger: str  # what started it: "RunUpdate" or "schedule"
    stage: str  # "queued", "running", "publishing" or "done"
    done: bool
    progress: Progress
    error: Optional[errors.Error]  # when done in error (fremen.Error with code CANCELLED once cancelled)
    update: Optional[UpdateResult]  # when done without error
    cancel_requested: bool
    message: str  # what it is doing, for people: e.g. why a cancellation did not stop it
    create_time: Optional[float]  # seconds since the epoch
    end_time: Optional[float]  # once done
    proto: admin_pb2.Operation = dataclasses.field(repr=False, compare=False)

    @classmethod
    def from_proto(cls, message: admin_pb2.Operation) -> "Operation":
        p = message.progress
        update = None
        if message.HasField("update"):
            u = message.update
            update = UpdateResult(u.states_published, u.duration_seconds, list(u.order_histogram),
                                  u.prediction_error_before, u.prediction_error_after)
        return cls(
            name=message.name,
            map_name=message.map,
            trigger=message.trigger,
            stage=proto_values.word(admin_pb2.OperationStage, message.stage, "OPERATION_STAGE_"),
            done=message.done,
            progress=Progress(p.states_done, p.states_total, p.rate, p.eta_seconds),
            error=proto_values.error(message.error) if message.done else None,
            update=update,
            cancel_requested=message.cancel_requested,
            message=message.message,
            create_time=proto_values.seconds(message.create_time),
            end_time=proto_values.seconds(message.end_time),
            proto=message,
        )
