// Client: the AdminService calls, and waiting for an operation.
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/lib/client.h"

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

}  // namespace fremen::client
