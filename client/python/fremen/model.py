"""A state's model (QueryService.GetStateModel) as plain Python objects, and p(t) computed from it.

p(t) = clamp(α0 + Σ_{j < order} α_j cos(2π t / T_j + φ_j), 0, 1) over the published components
(docs/model.md, "Published model P"; the FreMEn paper's eq. 10): the same formula the daemon's
Predict evaluates (without persistence).
"""

import dataclasses
import math
from typing import Iterable, Optional

from fremen.v1 import query_pb2


@dataclasses.dataclass(frozen=True)
class Component:
    """α cos(2π t / period + φ)."""
    period_seconds: float
    amplitude: float
    phase: float  # radians

    def value(self, t: float) -> float:
        return self.amplitude * math.cos(2 * math.pi * t / self.period_seconds + self.phase)


@dataclasses.dataclass(frozen=True)
class OrderError:
    order: int
    error: float  # the decayed prequential error ε_p of P at this order
    weight: float  # the decayed number of observations behind it


@dataclasses.dataclass(frozen=True)
class Persistence:
    last_time: float
    last_value: float
    tau_seconds: float  # 0 before two observations


@dataclasses.dataclass(frozen=True)
class StateModel:
    """What the daemon knows of one state. `proto` is the fremen.v1.StateModel it came from (with
    the lossless history's details for lossless maps)."""
    id: int
    cell: Optional[tuple[int, int, int]]  # (x, y, z) in grid maps, None in generic ones
    name: str
    group: str
    never_changed: bool
    observations: int
    first_time: float
    last_time: float
    mean: float
    spectrum: list[Component]  # every modelled period, when asked for
    published_mean: float
    selected_order: int
    published: list[Component]  # P's, strongest first
    order_errors: list[OrderError]
    persistence: Persistence
    proto: query_pb2.StateModel = dataclasses.field(repr=False, compare=False)

    def probability(self, t: float, order: Optional[int] = None) -> float:
        """p(t) of the published model at `order` (default: the selected one)."""
        order = self.selected_order if order is None else order
        p = self.published_mean + sum(c.value(t) for c in self.published[:order])
        return min(1.0, max(0.0, p))

    @classmethod
    def from_proto(cls, model: query_pb2.StateModel) -> "StateModel":
        def components(items: Iterable[query_pb2.Component]) -> list[Component]:
            return [Component(c.period_seconds, c.amplitude, c.phase) for c in items]
        return cls(
            id=model.id,
            cell=(model.cell.x, model.cell.y, model.cell.z) if model.HasField("cell") else None,
            name=model.name,
            group=model.group,
            never_changed=model.never_changed,
            observations=model.observations,
            first_time=model.first_time,
            last_time=model.last_time,
            mean=model.mean,
            spectrum=components(model.spectrum),
            published_mean=model.published_mean,
            selected_order=model.selected_order,
            published=components(model.published),
            order_errors=[OrderError(e.order, e.error, e.weight) for e in model.order_errors],
            persistence=Persistence(model.persistence.last_time, model.persistence.last_value,
                                    model.persistence.tau_seconds),
            proto=model,
        )
