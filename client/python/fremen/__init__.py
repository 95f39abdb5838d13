"""fremen: the Python client of fremend, the FreMEn map database.

    import fremen
    with fremen.connect("127.0.0.1:50051") as client:
        client.create_map("doors")
        with client.ingest("doors") as session:
            session.send(1.7e9, [1, 0], names=["front", "back"])
        print(client.predict("doors", [1.7e9 + 3600], names=["front", "back"]).probabilities)

The package is the hand-written modules beside this file plus the generated messages and stubs in
the subpackage fremen.v1 (protoc's output for proto/fremen/v1/*.proto, which imports itself as
`fremen.v1`). The build assembles both into <build>/python/fremen; see client/python/README.md.
"""

from fremen.arrays import FlatArray
from fremen.client import DEFAULT_ADDRESS, AnomalyCheck, Client, Prediction, Reconstruction, ScoredState, connect
from fremen.errors import (AlreadyExists, DeadlineExceeded, Error, FailedPrecondition, InvalidArgument, NotFound,
                           OutOfRange, PermissionDenied, ResourceExhausted, Unauthenticated, Unavailable)
from fremen.ingest import Ack, IngestSession, Rejection
from fremen.model import Component, OrderError, Persistence, StateModel
from fremen.retry import Backoff

__all__ = [
    "DEFAULT_ADDRESS", "Ack", "AlreadyExists", "AnomalyCheck", "Backoff", "Client", "Component", "DeadlineExceeded",
    "Error", "FailedPrecondition", "FlatArray", "IngestSession", "InvalidArgument", "NotFound", "OrderError",
    "OutOfRange", "PermissionDenied", "Persistence", "Prediction", "Reconstruction", "Rejection", "ResourceExhausted",
    "ScoredState", "StateModel", "Unauthenticated", "Unavailable", "connect",
]
