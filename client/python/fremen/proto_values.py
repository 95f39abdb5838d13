"""How the API's message values become the Python values the package's results carry: a
Timestamp as float seconds since the epoch (the unit of every time the calls take), an enum as a
lowercase word (the words create_map and region take, e.g. "grid", "squared"), a fremen.v1.Status
as a fremen.Error or None. One place, so that every result class converts alike.
"""

from typing import Any, Optional

from fremen import errors


def seconds(timestamp: Any) -> Optional[float]:
    """A google.protobuf.Timestamp as seconds since the epoch; None when unset (all zero)."""
    if timestamp.seconds == 0 and timestamp.nanos == 0:
        return None
    return float(timestamp.seconds + timestamp.nanos / 1e9)


def word(enum_type: Any, value: int, prefix: str) -> str:
    """An enum value as a lowercase word without its prefix: MAP_KIND_GRID -> "grid"; a number this
    package does not know (a newer daemon) as "unknown_<number>"."""
    try:
        name: str = enum_type.Name(value)
    except ValueError:
        return f"unknown_{value}"
    return name.removeprefix(prefix).lower()


def error(status: Any) -> Optional[errors.Error]:
    """The fremen.Error a fremen.v1.Status carries; None for code 0 (OK)."""
    if status.code == 0:
        return None
    return errors.error_from_status(status.code, status.message)


def triple(message: Any) -> tuple[Any, Any, Any]:
    """(x, y, z) of a Point, CellIndex or GridSize."""
    return (message.x, message.y, message.z)
