"""How callers name states, turned into the API's messages.

Every method about states takes exactly one of four keyword arguments: `ids` (generic states by
64-bit id), `names` (generic states by name), `cells` (grid cells by integer index (x, y) or
(x, y, z)) or `points` (metric points (x, y) or (x, y, z), metres, in the map's frame). Cells and
points may be sequences of tuples or numpy arrays of shape (n, 2) or (n, 3).
"""

from typing import TYPE_CHECKING, Any, Iterable, Mapping, Optional, Sequence, Union

from fremen.errors import InvalidArgument
from fremen.v1 import common_pb2

if TYPE_CHECKING:
    import numpy.typing

# What the calls take to name states (see above).
Ids = Iterable[int]
Names = Iterable[str]
Cells = Union[Iterable[Sequence[int]], "numpy.typing.NDArray[Any]"]
Points = Union[Iterable[Sequence[float]], "numpy.typing.NDArray[Any]"]


def chosen_kind(refs: Mapping[str, object], what: str) -> str:
    """The one keyword of `refs` (keyword -> value, None = not given) that was given; InvalidArgument
    naming them all otherwise."""
    given = [keyword for keyword, value in refs.items() if value is not None]
    if len(given) != 1:
        choices = ", ".join(f"{keyword}=" for keyword in refs)
        raise InvalidArgument(f"{what} needs exactly one of {choices}; got " + (", ".join(given) or "none"))
    return given[0]


def columns(rows: Iterable[Sequence[Any]], argument: str) -> tuple[list[Any], list[Any], list[Any]]:
    """Parallel x, y, z lists of a sequence of 2- or 3-tuples; z is empty when every row is 2-D."""
    xs: list[Any] = []
    ys: list[Any] = []
    zs: list[Any] = []
    three_d = False
    for i, given in enumerate(rows):
        row = list(given)
        if len(row) not in (2, 3):
            raise InvalidArgument(f"{argument}[{i}] must be (x, y) or (x, y, z), got {len(row)} numbers")
        xs.append(row[0])
        ys.append(row[1])
        zs.append(row[2] if len(row) == 3 else 0)
        three_d = three_d or len(row) == 3
    return xs, ys, (zs if three_d else [])


def cell_indices(rows: Cells, argument: str = "cells") -> common_pb2.CellIndices:
    xs, ys, zs = columns(rows, argument)
    try:
        return common_pb2.CellIndices(x=[int(v) for v in xs], y=[int(v) for v in ys], z=[int(v) for v in zs])
    except ValueError as error:  # a negative index does not fit uint32
        raise InvalidArgument(f"{argument} must hold non-negative integer indices: {error}") from None


def points(rows: Points, argument: str = "points") -> common_pb2.Points:
    xs, ys, zs = columns(rows, argument)
    return common_pb2.Points(x=[float(v) for v in xs], y=[float(v) for v in ys], z=[float(v) for v in zs])


def state_refs(what: str, ids: Optional[Ids] = None, names: Optional[Names] = None, cells: Optional[Cells] = None,
               points_: Optional[Points] = None) -> common_pb2.StateRefs:
    """fremen.v1.StateRefs for many states (exactly one keyword given)."""
    chosen_kind({"ids": ids, "names": names, "cells": cells, "points": points_}, what)
    if ids is not None:
        return common_pb2.StateRefs(ids=[int(i) for i in ids])
    if names is not None:
        return common_pb2.StateRefs(names=list(names))
    if cells is not None:
        return common_pb2.StateRefs(cells=cell_indices(cells))
    assert points_ is not None  # chosen_kind saw exactly one given
    return common_pb2.StateRefs(points=points(points_))


def state_ref(what: str, id: Optional[int] = None, name: Optional[str] = None,  # noqa: A002 (the API's word)
              cell: Optional[Sequence[int]] = None, point: Optional[Sequence[float]] = None) -> common_pb2.StateRef:
    """fremen.v1.StateRef for one state (exactly one keyword given)."""
    chosen_kind({"id": id, "name": name, "cell": cell, "point": point}, what)
    if id is not None:
        return common_pb2.StateRef(id=int(id))
    if name is not None:
        return common_pb2.StateRef(name=name)
    if cell is not None:
        c = cell_indices([cell], "cell")
        return common_pb2.StateRef(cell=common_pb2.CellIndex(x=c.x[0], y=c.y[0], z=c.z[0] if c.z else 0))
    assert point is not None  # chosen_kind saw exactly one given
    p = points([point], "point")
    return common_pb2.StateRef(point=common_pb2.Point(x=p.x[0], y=p.y[0], z=p.z[0] if p.z else 0.0))


def prediction_options(persistence: bool = False, order: Optional[int] = None) -> common_pb2.PredictionOptions:
    options = common_pb2.PredictionOptions(persistence=persistence)
    if order is not None:
        options.order = order
    return options
