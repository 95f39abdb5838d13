"""The Client's AdminService calls: the update job and the operations that track it, backups and
restores of maps, and the daemon's status.

AdminCalls is a base of fremen.Client (it uses the Client's _call, _pages and _admin stub); it
lives apart so that client.py keeps the map and query calls. RunUpdate, CancelOperation and the
reads are retried after UNAVAILABLE (RunUpdate answers the running job instead of starting another;
a cancellation of an ended operation answers it unchanged); BackupMap and RestoreMap are not, since
a first try that took effect makes the second one ALREADY_EXISTS.

Thread-safety: as the Client's (calls may come from many threads).
"""

import time as time_module
from typing import Any, Callable, Iterator, Optional

from fremen.maps import MapInfo
from fremen.operations import Operation
from fremen.status import Backup, ServerStatus
from fremen.v1 import admin_pb2


class AdminCalls:
    # Provided by fremen.Client.
    _admin: Any
    _call: Callable[..., Any]
    _pages: Callable[..., Iterator[Any]]

    def update(self, map_name: str, wait: bool = True, poll_interval: float = 0.05) -> Operation:
        """Runs the update job on the map now (order selection and republication of P) and, when
        `wait`, waits for it to finish; returns its Operation. A job that ends in error raises
        that error."""
        message = self._call(self._admin.RunUpdate, admin_pb2.RunUpdateRequest(map=map_name), map_name)
        operation = Operation.from_proto(message)
        while wait and not operation.done:
            time_module.sleep(poll_interval)
            operation = self.get_operation(operation.name, map_name)
        if operation.error is not None:
            raise operation.error
        return operation

    def get_operation(self, operation_name: str, map_name: Optional[str] = None) -> Operation:
        """The Operation called `operation_name` ("operations/..."), as it is now. NotFound for an
        unknown one, or one of another map than `map_name` when given."""
        request = admin_pb2.GetOperationRequest(map=map_name or "", name=operation_name)
        return Operation.from_proto(self._call(self._admin.GetOperation, request, map_name))

    def list_operations(self, map_name: Optional[str] = None, running_only: bool = False,
                        page_size: int = 0) -> Iterator[Operation]:
        """Every Operation the daemon keeps (of `map_name` only when given; only those not yet done
        when `running_only`), newest first, fetched a page of `page_size` at a time."""
        request = admin_pb2.ListOperationsRequest(map=map_name or "", page_size=page_size,
                                                  running_only=running_only)
        for message in self._pages(self._admin.ListOperations, request, "operations", map_name):
            yield Operation.from_proto(message)

    def cancel_operation(self, operation_name: str, map_name: Optional[str] = None) -> Operation:
        """Asks the operation to stop and returns it: done with error CANCELLED once it stopped (a
        queued update stops at once; one that publishes runs to its end, and its `message` says
        so). An operation that already ended is returned unchanged."""
        request = admin_pb2.CancelOperationRequest(map=map_name or "", name=operation_name)
        return Operation.from_proto(self._call(self._admin.CancelOperation, request, map_name))

    def backup_map(self, map_name: str, directory: str) -> Backup:
        """A consistent copy of the map (it keeps serving meanwhile) in `directory`, a new directory
        relative to the daemon's backup root (--backup-dir): a Backup (`path` as the daemon sees
        it, `bytes`, `duration_seconds`). InvalidArgument for an absolute path or "..",
        AlreadyExists when the directory holds something."""
        request = admin_pb2.BackupMapRequest(map=map_name, directory=directory)
        return Backup.from_proto(self._call(self._admin.BackupMap, request, map_name, idempotent=False))

    def restore_map(self, directory: str, map_name: Optional[str] = None) -> MapInfo:
        """The backup in `directory` (relative to the backup root) as a new map called `map_name`
        (None: the backed-up map's name); returns its MapInfo. AlreadyExists when the name is
        taken, NotFound when there is no backup there."""
        request = admin_pb2.RestoreMapRequest(map=map_name or "", directory=directory)
        return MapInfo.from_proto(self._call(self._admin.RestoreMap, request, map_name, idempotent=False).map)

    def server_status(self) -> ServerStatus:
        """The daemon's ServerStatus: version, uptime, maps and states, running operations, the
        update schedule, TLS and tokens, store state, free disk space, each map's last update,
        maps whose writes failed, and the background scrub's findings."""
        return ServerStatus.from_proto(self._call(self._admin.GetServerStatus, admin_pb2.GetServerStatusRequest()))
