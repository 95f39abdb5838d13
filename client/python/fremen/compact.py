"""The API's compact scan (fremen.v1.CompactCells): strictly increasing linear cell indices
x + nx·(y + ny·z) as LEB128 varints of their gaps, and binary values as one bit per cell (cell i
in bit i % 8 of byte i / 8). About 1.1 bytes per binary observation of a coherent scan, against 7
for cells=; IngestSession.send_compact sends it."""

from typing import Iterable, Optional, Sequence

from fremen import errors


def index_gaps(indices: Iterable[int]) -> bytes:
    """The varints of the first index, then of each gap to the next (each ≥ 1)."""
    out = bytearray()
    previous: Optional[int] = None
    for index in indices:
        index = int(index)
        if index < 0 or (previous is not None and index <= previous):
            raise errors.InvalidArgument(
                f"compact indices must be ≥ 0 and increase strictly: {index} after {previous}")
        gap = index if previous is None else index - previous
        previous = index
        while gap >= 0x80:
            out.append((gap & 0x7F) | 0x80)
            gap >>= 7
        out.append(gap)
    return bytes(out)


def occupied_bits(values: Sequence[float]) -> bytes:
    """One bit per value, set for 1; every value must be 0 or 1 (soft ones go as probabilities)."""
    out = bytearray((len(values) + 7) // 8)
    for i, v in enumerate(values):
        if v == 1:
            out[i // 8] |= 1 << (i % 8)
        elif v != 0:
            raise errors.InvalidArgument(
                f"occupied values are 0 or 1, got {v} at {i}: send soft values as probabilities=")
    return bytes(out)
