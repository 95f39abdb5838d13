"""fremen: the Python client of fremend, the FreMEn map database.

    import fremen
    with fremen.connect("127.0.0.1:50051") as client:
        client.create_map("doors")
        with client.ingest("doors") as session:
            session.send(1.7e9, [1, 0], names=["front", "back"])
        print(client.predict("doors", [1.7e9 + 3600], names=["front", "back"]).probabilities)

fremen.FleetClient(["a:50051", "b:50051"] or "all:fremend:50051") asks every daemon of a fleet for
its maps and status and merges the answers (fremen.fleet).

Every call answers the package's own frozen dataclasses (MapInfo, Prediction, Operation, ...), each
result of a single message keeping it as `proto`. The package is the hand-written modules beside
this file plus the generated messages and stubs in the subpackage fremen.v1 (protoc's output for
proto/fremen/v1/*.proto, which imports itself as `fremen.v1`) and _version.py (the project's
version, from CMake). The build assembles them into <build>/python/fremen; see
client/python/README.md.
"""

from fremen._version import __version__
from fremen.arrays import Array, FlatArray
from fremen.client import (DEFAULT_ADDRESS, AnomalyCheck, Client, NamedState, Prediction, Reconstruction, ScoredState,
                           connect)
from fremen.errors import (AlreadyExists, DeadlineExceeded, Error, FailedPrecondition, InvalidArgument, NotFound,
                           OutOfRange, PermissionDenied, ResourceExhausted, Unauthenticated, Unavailable)
from fremen.fleet import DaemonError, DaemonStatus, FleetClient, FleetMap, FleetMaps, FleetStatus, FleetSummary
from fremen.ingest import Ack, Batch, IngestSession, Rejection
from fremen.maps import MapInfo, MapStats, MapUpdate
from fremen.model import Component, OrderError, Persistence, StateModel
from fremen.operations import Operation, Progress, UpdateResult
from fremen.placement import Placement
from fremen.retry import Backoff
from fremen.status import Backup, CheckProblem, MapScrub, ServerStatus

__all__ = [
    "DEFAULT_ADDRESS", "Ack", "AlreadyExists", "AnomalyCheck", "Array", "Backoff", "Backup", "Batch",
    "CheckProblem", "Client", "Component", "DaemonError", "DaemonStatus", "DeadlineExceeded", "Error",
    "FailedPrecondition", "FlatArray", "FleetClient", "FleetMap", "FleetMaps", "FleetStatus", "FleetSummary",
    "IngestSession", "InvalidArgument", "MapInfo", "MapScrub", "MapStats", "MapUpdate", "NamedState", "NotFound",
    "Operation", "OrderError", "OutOfRange", "PermissionDenied", "Persistence", "Placement", "Prediction", "Progress",
    "Reconstruction", "Rejection", "ResourceExhausted", "ScoredState", "ServerStatus", "StateModel",
    "Unauthenticated", "Unavailable", "UpdateResult", "__version__", "connect",
]
