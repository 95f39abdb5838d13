// Client: the AdminService calls, and waiting for an operation.
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/lib/client.h"
#include "client/lib/status.h"

namespace fremen::client {

absl::StatusOr<v1::Operation> Client::RunUpdate(absl::string_view map, const CallOptions& call) const {
  v1::RunUpdateRequest request;
  request.set_map(std::string(map));
  v1::Operation response;
  // Safe to repeat: while an update of the map runs, RunUpdate answers that operation.
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().RunUpdate(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<v1::Operation> Client::GetOperation(absl::string_view map, absl::string_view name,
                                                   const CallOptions& call) const {
  v1::GetOperationRequest request;
  request.set_map(std::string(map));
  request.set_name(std::string(name));
  v1::Operation response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().GetOperation(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<OperationPage> Client::ListOperations(absl::string_view map, bool running_only, int page_size,
                                                     const std::string& page_token, const CallOptions& call) const {
  v1::ListOperationsRequest request;
  request.set_map(std::string(map));
  request.set_running_only(running_only);
  request.set_page_size(page_size);
  request.set_page_token(page_token);
  v1::ListOperationsResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().ListOperations(&context, request, &response);
  });
  if (!status.ok()) return status;
  OperationPage page;
  page.operations.assign(response.operations().begin(), response.operations().end());
  page.next_page_token = response.next_page_token();
  return page;
}

absl::StatusOr<v1::Operation> Client::CancelOperation(absl::string_view map, absl::string_view name,
                                                      const CallOptions& call) const {
  v1::CancelOperationRequest request;
  request.set_map(std::string(map));
  request.set_name(std::string(name));
  v1::Operation response;
  // Safe to repeat: cancelling an operation twice, or one that ended, answers it unchanged.
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().CancelOperation(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<v1::Operation> Client::WaitOperation(absl::string_view map, absl::string_view name,
                                                    const WaitOptions& wait, const CallOptions& call) const {
  const absl::Time give_up =
      wait.timeout == absl::InfiniteDuration() ? absl::InfiniteFuture() : absl::Now() + wait.timeout;
  for (;;) {
    auto operation = GetOperation(map, name, call);
    if (!operation.ok()) return operation.status();
    if (wait.on_progress) wait.on_progress(*operation);
    if (operation->done()) return operation;
    if (absl::Now() + wait.poll_interval > give_up) {
      return absl::DeadlineExceededError(absl::StrCat("operation \"", name, "\" of map \"", map,
                                                      "\" still running after ", absl::FormatDuration(wait.timeout)));
    }
    absl::SleepFor(wait.poll_interval);
  }
}

absl::StatusOr<v1::BackupMapResponse> Client::BackupMap(absl::string_view map, absl::string_view directory,
                                                        const CallOptions& call) const {
  v1::BackupMapRequest request;
  request.set_map(std::string(map));
  request.set_directory(std::string(directory));
  v1::BackupMapResponse response;
  absl::Status status = connection_->CallOnce(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().BackupMap(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<v1::Map> Client::RestoreMap(absl::string_view directory, absl::string_view map,
                                           const CallOptions& call) const {
  v1::RestoreMapRequest request;
  request.set_map(std::string(map));
  request.set_directory(std::string(directory));
  v1::RestoreMapResponse response;
  absl::Status status = connection_->CallOnce(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().RestoreMap(&context, request, &response);
  });
  if (!status.ok()) return status;
  return std::move(*response.mutable_map());
}

absl::StatusOr<v1::GetServerStatusResponse> Client::GetServerStatus(const CallOptions& call) const {
  v1::GetServerStatusRequest request;
  v1::GetServerStatusResponse response;
  absl::Status status = connection_->CallIdempotent(call, "", [&](grpc::ClientContext& context) {
    return connection_->admin().GetServerStatus(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<v1::CheckMapResponse> Client::CheckMap(absl::string_view map, const CallOptions& call) const {
  v1::CheckMapRequest request;
  request.set_map(std::string(map));
  v1::CheckMapResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().CheckMap(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<v1::SalvageMapResponse> Client::SalvageMap(absl::string_view map, absl::string_view new_map,
                                                          const CallOptions& call) const {
  v1::SalvageMapRequest request;
  request.set_map(std::string(map));
  request.set_new_map(std::string(new_map));
  v1::SalvageMapResponse response;
  absl::Status status = connection_->CallOnce(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().SalvageMap(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

absl::Status Client::ExportMap(absl::string_view map,
                              const std::function<absl::Status(const v1::MapChunk&)>& receive,
                              const CallOptions& call, uint32_t chunk_bytes, v1::MapExportKind kind,
                              uint64_t tail_after_lsn) const {
  v1::ExportMapRequest request;
  request.set_map(std::string(map));
  request.set_chunk_bytes(chunk_bytes);
  request.set_kind(kind);
  request.set_tail_after_lsn(tail_after_lsn);
  absl::Status refused;
  absl::Status status = connection_->CallOnce(call, map, [&](grpc::ClientContext& context) {
    auto reader = connection_->admin().ExportMap(&context, request);
    v1::MapChunk chunk;
    while (reader->Read(&chunk)) {
      refused = receive(chunk);
      if (!refused.ok()) {
        context.TryCancel();
        while (reader->Read(&chunk)) {
        }
        break;
      }
    }
    return reader->Finish();
  });
  return refused.ok() ? status : refused;
}

absl::StatusOr<v1::ImportMapResponse> Client::ImportMap(
    absl::string_view map, const std::function<absl::StatusOr<bool>(v1::MapChunk&)>& next,
    const CallOptions& call) const {
  v1::ImportMapResponse response;
  absl::Status local;
  absl::Status status = connection_->CallOnce(call, map, [&](grpc::ClientContext& context) {
    auto writer = connection_->admin().ImportMap(&context, &response);
    v1::MapChunk chunk;
    for (;;) {
      absl::StatusOr<bool> more = next(chunk);
      if (!more.ok()) {
        // Nothing may be created from a stream cut short on this side.
        local = more.status();
        context.TryCancel();
        break;
      }
      if (!*more) break;
      if (!writer->Write(chunk)) break;  // the daemon has ended the call: Finish says why
    }
    if (local.ok()) writer->WritesDone();
    return writer->Finish();
  });
  if (!local.ok()) return local;
  if (!status.ok()) return status;
  return response;
}

absl::StatusOr<v1::ImportMapResponse> Client::CopyMapTo(const Client& target, absl::string_view map,
                                                        absl::string_view new_name, const CallOptions& call,
                                                        v1::MapExportKind kind, uint64_t tail_after_lsn) const {
  const std::string name(new_name.empty() ? map : new_name);
  v1::ExportMapRequest request;
  request.set_map(std::string(map));
  request.set_kind(kind);
  request.set_tail_after_lsn(tail_after_lsn);
  auto context = connection_->NewContext(connection_->DeadlineOf(call), map);
  auto reader = connection_->admin().ExportMap(context.get(), request);
  bool ended = false;
  auto imported = target.ImportMap(
      name,
      [&](v1::MapChunk& chunk) -> absl::StatusOr<bool> {
        if (ended) return false;
        if (!reader->Read(&chunk)) {
          // The export ended: after its trailer (the importer has it), or failed.
          ended = true;
          absl::Status exported = FromGrpcStatus(reader->Finish(), connection_->address());
          if (!exported.ok()) return exported;
          return false;
        }
        if (chunk.has_header()) chunk.mutable_header()->set_map(name);
        return true;
      },
      call);
  if (!ended) {
    context->TryCancel();
    v1::MapChunk rest;
    while (reader->Read(&rest)) {
    }
    (void)reader->Finish();
  }
  return imported;
}

absl::StatusOr<v1::SetMapMoveResponse> Client::SetMapMove(absl::string_view map, v1::MapMoveStep step,
                                                          absl::string_view to, const CallOptions& call) const {
  v1::SetMapMoveRequest request;
  request.set_map(std::string(map));
  request.set_step(step);
  request.set_to(std::string(to));
  v1::SetMapMoveResponse response;
  absl::Status status = connection_->CallIdempotent(call, map, [&](grpc::ClientContext& context) {
    return connection_->admin().SetMapMove(&context, request, &response);
  });
  if (!status.ok()) return status;
  return response;
}

}  // namespace fremen::client
