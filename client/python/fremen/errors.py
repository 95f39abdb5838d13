"""Errors raised by the fremen client: one exception class per gRPC status code that a caller may
want to handle on its own, all subclasses of fremen.Error, which carries the code and the server's
message (it names the field at fault, e.g. "map.grid.resolution must be ...").

The client raises the same classes for arguments it refuses before calling the daemon (with code
INVALID_ARGUMENT), so that a caller needs one except clause for both.
"""

import grpc


class Error(Exception):
    """A failed call. `code` is a grpc.StatusCode, `message` the server's (or client's) message."""

    def __init__(self, code: grpc.StatusCode, message: str) -> None:
        super().__init__(f"{code.name}: {message}")
        self.code = code
        self.message = message


class InvalidArgument(Error, ValueError):
    """A bad argument or field; the message names it."""

    def __init__(self, message: str) -> None:
        super().__init__(grpc.StatusCode.INVALID_ARGUMENT, message)


class NotFound(Error):
    """No such map (or operation, or group)."""


class AlreadyExists(Error):
    """A map of that name exists already."""


class Unauthenticated(Error):
    """The daemon wants a bearer token, and none or an unknown one was sent."""


class PermissionDenied(Error):
    """The token may only read, and the call writes."""


class FailedPrecondition(Error):
    """The map's settings do not allow the call (e.g. persistence on a map without it)."""


class OutOfRange(Error):
    """A box or an index outside the map."""


class ResourceExhausted(Error):
    """The request is too large (split it), or the daemon is out of a resource."""


class Unavailable(Error):
    """The daemon cannot be reached (or is shutting down); retrying later may succeed."""


class DeadlineExceeded(Error):
    """The call did not finish within its timeout."""


_CLASS_OF_CODE: dict[grpc.StatusCode, type[Error]] = {
    grpc.StatusCode.NOT_FOUND: NotFound,
    grpc.StatusCode.ALREADY_EXISTS: AlreadyExists,
    grpc.StatusCode.UNAUTHENTICATED: Unauthenticated,
    grpc.StatusCode.PERMISSION_DENIED: PermissionDenied,
    grpc.StatusCode.FAILED_PRECONDITION: FailedPrecondition,
    grpc.StatusCode.OUT_OF_RANGE: OutOfRange,
    grpc.StatusCode.RESOURCE_EXHAUSTED: ResourceExhausted,
    grpc.StatusCode.UNAVAILABLE: Unavailable,
    grpc.StatusCode.DEADLINE_EXCEEDED: DeadlineExceeded,
}

_CODE_OF_NUMBER = {code.value[0]: code for code in grpc.StatusCode}


def error_for(code: grpc.StatusCode, message: str) -> Error:
    """The Error (of the most specific class) for a grpc.StatusCode and a message."""
    if code == grpc.StatusCode.INVALID_ARGUMENT:
        return InvalidArgument(message)
    return _CLASS_OF_CODE.get(code, Error)(code, message)


def error_from_status(number: int, message: str) -> Error:
    """The Error for a status carried inside a response (fremen.v1.Status: a numeric code)."""
    return error_for(_CODE_OF_NUMBER.get(number, grpc.StatusCode.UNKNOWN), message)


def error_from_rpc(rpc_error: grpc.RpcError) -> Error:
    """The Error for a grpc.RpcError raised by a stub."""
    return error_for(rpc_error.code(), rpc_error.details() or "")
