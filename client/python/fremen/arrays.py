"""Dense results (predictions, regions) as numpy arrays when numpy is importable, and as FlatArray
(a flat list and a shape) when it is not, so that the package works without numpy.
"""

import math
from typing import TYPE_CHECKING, Any, Sequence, Union

try:
    import numpy
except ImportError:  # numpy is optional
    numpy = None  # type: ignore[assignment]

if TYPE_CHECKING:
    import numpy.typing


def numpy_available() -> bool:
    return numpy is not None


class FlatArray:
    """Values in C order (the last index fastest) and their shape: what a numpy array would hold.

    array[i, j, ...] reads one element; tolist() gives nested lists, as numpy's tolist() does.
    """

    def __init__(self, values: list[Any], shape: Sequence[int]) -> None:
        if len(values) != math.prod(shape):
            raise ValueError(f"{len(values)} values do not fill shape {shape}")
        self.values = values
        self.shape = tuple(shape)

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, index: Union[int, tuple[int, ...]]) -> Any:
        if not isinstance(index, tuple):
            index = (index,)
        if len(index) != len(self.shape):
            raise IndexError(f"FlatArray of shape {self.shape} needs {len(self.shape)} indices, got {len(index)}")
        offset = 0
        for i, n in zip(index, self.shape):
            if not -n <= i < n:
                raise IndexError(f"index {index} outside shape {self.shape}")
            offset = offset * n + (i % n)
        return self.values[offset]

    def tolist(self) -> list[Any]:
        def nest(values: list[Any], shape: tuple[int, ...]) -> list[Any]:
            if len(shape) == 1:
                return list(values)
            step = len(values) // shape[0]
            return [nest(values[i * step:(i + 1) * step], shape[1:]) for i in range(shape[0])]
        return nest(self.values, self.shape)

    def __repr__(self) -> str:
        return f"FlatArray(shape={self.shape})"


# A dense result: a numpy array, or a FlatArray when numpy is not used. Both have `shape`, `[i, j]`
# indexing and tolist().
Array = Union["numpy.typing.NDArray[Any]", FlatArray]


def shaped(values: Sequence[Any], shape: tuple[int, ...], dtype: str, use_numpy: bool) -> Array:
    """`values` (a sequence in C order) as a numpy array of `dtype` ("float32", "uint8", "bool") and
    `shape` when `use_numpy`, else as a FlatArray."""
    if use_numpy:
        return numpy.asarray(values, dtype=dtype).reshape(shape)
    return FlatArray(list(values), shape)


def shaped_bytes(data: bytes, shape: tuple[int, ...], use_numpy: bool) -> Array:
    """Bytes (one uint8 per element) shaped as by shaped()."""
    if use_numpy:
        return numpy.frombuffer(data, dtype=numpy.uint8).reshape(shape).copy()
    return FlatArray(list(data), shape)
