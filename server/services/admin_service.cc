#include "server/services/admin_service.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <filesystem>
#include <system_error>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "server/services/backup_path.h"
#include "server/services/map_tail.h"
#include "server/rpc/logging.h"
#include "server/convert/map_convert.h"
#include "server/jobs/map_list.h"
#include "server/rpc/map_lookup.h"
#include "server/rpc/map_name.h"
#include "server/convert/operation_convert.h"
#include "server/convert/query_convert.h"
#include "storage/map_page.h"
#include "storage/verify.h"

namespace fremen::server {

namespace {

namespace fs = std::filesystem;

constexpr MethodSpec kRunUpdate{"RunUpdate", Access::kWrite, /*blocking=*/false};
constexpr MethodSpec kGetOperation{"GetOperation", Access::kRead, /*blocking=*/false};
constexpr MethodSpec kListOperations{"ListOperations", Access::kRead, /*blocking=*/false};
constexpr MethodSpec kCancelOperation{"CancelOperation", Access::kWrite, /*blocking=*/false};
constexpr MethodSpec kBackupMap{"BackupMap", Access::kWrite, /*blocking=*/true};
constexpr MethodSpec kRestoreMap{"RestoreMap", Access::kWrite, /*blocking=*/true};
constexpr MethodSpec kGetServerStatus{"GetServerStatus", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kCheckMap{"CheckMap", Access::kRead, /*blocking=*/true};
constexpr MethodSpec kSalvageMap{"SalvageMap", Access::kWrite, /*blocking=*/true};
constexpr MethodSpec kExportMap{"ExportMap", Access::kWrite, /*blocking=*/true};
constexpr MethodSpec kImportMap{"ImportMap", Access::kWrite, /*blocking=*/true};
constexpr MethodSpec kSetMapMove{"SetMapMove", Access::kWrite, /*blocking=*/true};

constexpr char kOperationPrefix[] = "operations/";

// The map a call names in its field or header, or "" when it names none (where that is allowed:
// operations are found by name, and a restore may keep the backed-up name).
absl::StatusOr<std::string> OptionalMapName(const grpc::ServerContextBase& context, const std::string& request_map,
                                            absl::string_view field) {
  const auto& metadata = context.client_metadata();
  const auto header = metadata.find(kMapHeader);
  if (request_map.empty() && (header == metadata.end() || header->second.empty())) return std::string();
  return ResolveMapName(context, request_map, field);
}

// Storage names the new map "name"; the restore request calls it "map", the salvage request "new_map".
absl::Status RenameNameField(const absl::Status& status, absl::string_view field) {
  if (status.code() != absl::StatusCode::kInvalidArgument || !absl::StartsWith(status.message(), "name")) return status;
  return absl::InvalidArgumentError(absl::StrCat(field, status.message().substr(4)));
}

void ProblemToProto(const storage::VerifyProblem& p, v1::CheckProblem& problem) {
  problem.set_file(p.file);
  problem.set_location(p.where);
  problem.set_description(p.what);
}

void ScrubsToProto(const Scrubber& scrubber, v1::GetServerStatusResponse& response) {
  if (const absl::Time next = scrubber.NextPass(); next != absl::InfiniteFuture()) {
    TimeToProto(next, *response.mutable_next_scrub_time());
  }
  for (const Scrubber::Result& result : scrubber.Results()) {
    v1::MapScrub& scrub = *response.add_map_scrubs();
    scrub.set_map(result.map);
    TimeToProto(result.finished, *scrub.mutable_finish_time());
    scrub.set_duration_seconds(absl::ToDoubleSeconds(result.took));
    scrub.set_clean(result.clean);
    scrub.set_problem_count(result.problem_count);
    for (const storage::VerifyProblem& p : result.problems) ProblemToProto(p, *scrub.add_problems());
    scrub.set_records(result.records);
  }
}

void VerifyReportToProto(const storage::VerifyReport& report, v1::CheckMapResponse& response) {
  response.set_map(report.map);
  response.set_clean(report.clean());
  for (const storage::VerifyProblem& p : report.problems) ProblemToProto(p, *response.add_problems());
  for (const std::string& note : report.notes) response.add_notes(note);
  for (const storage::ShardVerifyReport& s : report.shards) {
    v1::ShardCheck* shard = response.add_shards();
    shard->set_shard(s.shard);
    shard->set_records(s.records);
    shard->set_record_bytes(s.record_bytes);
    shard->set_file_bytes(s.file_bytes);
    shard->set_checkpoint_lsn(s.checkpoint_lsn.value_or(0));
    shard->set_read_to_end(s.read);
  }
  v1::LogCheck* log = response.mutable_log();
  log->set_segments(report.log.segments);
  log->set_records(report.log.records);
  log->set_bytes(report.log.bytes);
  log->set_first_lsn(report.log.first_lsn);
  log->set_last_lsn(report.log.last_lsn);
  log->set_torn_tail_bytes(report.log.torn_tail_bytes);
}

void SalvageReportToProto(const storage::SalvageReport& report, v1::SalvageMapResponse& response) {
  MapInfoToProto(report.map, *response.mutable_map());
  response.mutable_map()->set_move_state(v1::MAP_MOVE_STATE_SERVING);  // a new map
  response.set_records_kept(report.records_kept());
  response.set_records_lost(report.records_lost());
  for (const storage::SalvageShard& s : report.shards) {
    v1::ShardSalvage* shard = response.add_shards();
    shard->set_shard(s.shard);
    for (const storage::SalvageDatabase& d : s.databases) {
      v1::DatabaseSalvage* db = shard->add_databases();
      db->set_name(d.name);
      db->set_kept(d.kept);
      db->set_lost(d.lost);
    }
  }
  response.set_log_records_kept(report.log.records_kept);
  response.set_log_records_lost(report.log.records_lost);
  response.set_log_bytes_lost(report.log.bytes_lost);
  response.set_log_torn_tail_bytes(report.log.torn_tail_bytes);
  for (const storage::VerifyProblem& p : report.lost) ProblemToProto(p, *response.add_lost());
  response.set_losses(report.losses);
}

}  // namespace

grpc::ServerUnaryReactor* AdminServiceImpl::RunUpdate(grpc::CallbackServerContext* context,
                                                      const v1::RunUpdateRequest* request, v1::Operation* response) {
  return ServeUnary(deps_, context, kRunUpdate, [this, context, request, response]() -> absl::Status {
    auto name = ResolveMapName(*context, request->map(), "map");
    if (!name.ok()) return name.status();
    auto map = LookUpMap(*deps_.store, *context, *name);
    if (!map.ok()) return map.status();
    // The job's publication would be refused anyway; the caller learns it now, as a retry.
    if ((*map)->Move().state != storage::MoveState::kServing) return storage::MovingError(*name);
    auto op = admin_.operations->StartUpdate(*name, "RunUpdate");
    if (!op.ok()) return op.status();
    OperationToProto(*op, *response);
    return absl::OkStatus();
  });
}

absl::StatusOr<OperationView> AdminServiceImpl::FindOperation(const grpc::CallbackServerContext& context,
                                                              const std::string& request_map,
                                                              const std::string& name) const {
  if (name.empty()) return absl::InvalidArgumentError("name is required");
  if (!absl::StartsWith(name, kOperationPrefix)) {
    return absl::InvalidArgumentError(
        absl::StrCat("name: \"", name, "\" is not an operation name (", kOperationPrefix, "...)"));
  }
  auto map = OptionalMapName(context, request_map, "map");
  if (!map.ok()) return map.status();
  auto op = admin_.operations->Get(name);
  if (!op.ok()) return op.status();
  // A daemon answers only about the map a call was routed for (docs/storage.md, "Maps across
  // daemons").
  if (!map->empty() && op->map != *map) {
    return absl::NotFoundError(absl::StrCat("no operation named \"", name, "\" on map \"", *map, "\""));
  }
  return op;
}

grpc::ServerUnaryReactor* AdminServiceImpl::GetOperation(grpc::CallbackServerContext* context,
                                                         const v1::GetOperationRequest* request,
                                                         v1::Operation* response) {
  return ServeUnary(deps_, context, kGetOperation, [this, context, request, response]() -> absl::Status {
    auto op = FindOperation(*context, request->map(), request->name());
    if (!op.ok()) return op.status();
    OperationToProto(*op, *response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* AdminServiceImpl::ListOperations(grpc::CallbackServerContext* context,
                                                           const v1::ListOperationsRequest* request,
                                                           v1::ListOperationsResponse* response) {
  return ServeUnary(deps_, context, kListOperations, [this, context, request, response]() -> absl::Status {
    if (request->page_size() < 0) {
      return absl::InvalidArgumentError(absl::StrCat("page_size must be ≥ 0, got ", request->page_size()));
    }
    const size_t page_size = request->page_size() == 0 ? storage::kDefaultPageSize
                                                       : std::min<size_t>(request->page_size(), storage::kMaxPageSize);
    auto map = OptionalMapName(*context, request->map(), "map");
    if (!map.ok()) return map.status();
    auto page = admin_.operations->List(*map, request->running_only(), page_size, request->page_token());
    if (!page.ok()) return page.status();
    for (const OperationView& view : page->operations) OperationToProto(view, *response->add_operations());
    response->set_next_page_token(page->next_page_token);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* AdminServiceImpl::CancelOperation(grpc::CallbackServerContext* context,
                                                            const v1::CancelOperationRequest* request,
                                                            v1::Operation* response) {
  return ServeUnary(deps_, context, kCancelOperation, [this, context, request, response]() -> absl::Status {
    auto found = FindOperation(*context, request->map(), request->name());
    if (!found.ok()) return found.status();
    auto op = admin_.operations->Cancel(found->name);
    if (!op.ok()) return op.status();
    OperationToProto(*op, *response);
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* AdminServiceImpl::BackupMap(grpc::CallbackServerContext* context,
                                                      const v1::BackupMapRequest* request,
                                                      v1::BackupMapResponse* response) {
  return ServeUnary(deps_, context, kBackupMap, [this, context, request, response] {
    return Backup(*request, *context, *response);
  });
}

absl::Status AdminServiceImpl::Backup(const v1::BackupMapRequest& request, const grpc::CallbackServerContext& context,
                                      v1::BackupMapResponse& response) const {
  auto name = ResolveMapName(context, request.map(), "map");
  if (!name.ok()) return name.status();
  auto dir = ResolveBackupPath(admin_.config->backup_dir, request.directory(), "directory");
  if (!dir.ok()) return dir.status();
  auto store = deps_.store->Get();
  if (!store.ok()) return store.status();
  if (auto info = (*store)->GetMap(*name); !info.ok()) return info.status();
  if (!ClaimBackupDir(*dir)) {
    return absl::AlreadyExistsError(
        absl::StrCat("directory: another backup is being written to \"", request.directory(), "\""));
  }
  const absl::Status status = BackupInto(*name, *dir, request.directory(), **store, response);
  ReleaseBackupDir(*dir);
  return status;
}

bool AdminServiceImpl::ClaimBackupDir(const std::string& dir) const {
  base::MutexLock lock(&backups_mutex_);
  return backups_in_progress_.insert(dir).second;
}

void AdminServiceImpl::ReleaseBackupDir(const std::string& dir) const {
  base::MutexLock lock(&backups_mutex_);
  backups_in_progress_.erase(dir);
}

absl::Status AdminServiceImpl::BackupInto(const std::string& name, const std::string& dir,
                                          const std::string& requested_dir, storage::Store& store,
                                          v1::BackupMapResponse& response) const {
  std::error_code error;
  const bool existed = fs::exists(dir, error);
  if (existed && !(fs::is_directory(dir, error) && fs::is_empty(dir, error))) {
    return absl::AlreadyExistsError(absl::StrCat("directory: \"", requested_dir,
                                                 "\" already exists in the backup root and is not empty"));
  }
  if (fs::create_directories(fs::path(dir).parent_path(), error); error) {
    return absl::FailedPreconditionError(
        absl::StrCat("backup_dir: cannot create ", fs::path(dir).parent_path().string(), ": ", error.message()));
  }
  const absl::Time start = admin_.clock->Now();
  auto bytes = store.BackupMap(name, dir);
  if (!bytes.ok()) {
    // No half copy left to be mistaken for a backup.
    fs::remove_all(dir, error);
    if (existed) fs::create_directory(dir, error);
    return bytes.status();
  }
  const absl::Duration took = admin_.clock->Now() - start;
  response.set_path(dir);
  response.set_bytes(*bytes);
  response.set_duration_seconds(absl::ToDoubleSeconds(took));
  DaemonLog()->info("backup of map {} to {}: {} bytes in {}", name, dir, *bytes, absl::FormatDuration(took));
  return absl::OkStatus();
}

grpc::ServerUnaryReactor* AdminServiceImpl::RestoreMap(grpc::CallbackServerContext* context,
                                                       const v1::RestoreMapRequest* request,
                                                       v1::RestoreMapResponse* response) {
  return ServeUnary(deps_, context, kRestoreMap, [this, context, request, response] {
    return Restore(*request, *context, *response);
  });
}

absl::Status AdminServiceImpl::Restore(const v1::RestoreMapRequest& request, const grpc::CallbackServerContext& context,
                                       v1::RestoreMapResponse& response) const {
  auto name = OptionalMapName(context, request.map(), "map");
  if (!name.ok()) return name.status();
  auto dir = ResolveBackupPath(admin_.config->backup_dir, request.directory(), "directory");
  if (!dir.ok()) return dir.status();
  std::error_code error;
  if (!fs::is_directory(*dir, error)) {
    return absl::NotFoundError(absl::StrCat("directory: no backup at \"", request.directory(), "\" in the backup root"));
  }
  auto store = deps_.store->Get();
  if (!store.ok()) return store.status();
  auto info = (*store)->RestoreMap(*dir, *name, CallDeadline(context));
  if (absl::IsDataLoss(info.status()) || absl::IsDeadlineExceeded(info.status())) {
    DaemonLog()->warn("restore refused: {}", std::string(info.status().message()));
  }
  if (!info.ok()) return RenameNameField(info.status(), "map");
  MapInfoToProto(*info, *response.mutable_map());
  AddMoveState(**store, *response.mutable_map());
  DaemonLog()->info("map {} restored from {}", info->name, *dir);
  return absl::OkStatus();
}

grpc::ServerUnaryReactor* AdminServiceImpl::CheckMap(grpc::CallbackServerContext* context,
                                                     const v1::CheckMapRequest* request,
                                                     v1::CheckMapResponse* response) {
  return ServeUnary(deps_, context, kCheckMap, [this, context, request, response]() -> absl::Status {
    auto name = ResolveMapName(*context, request->map(), "map");
    if (!name.ok()) return name.status();
    auto store = deps_.store->Get();
    if (!store.ok()) return store.status();
    auto map = (*store)->Map(*name);
    if (!map.ok()) return map.status();
    const absl::Time start = admin_.clock->Now();
    const storage::VerifyReport report = (*map)->Verify(CallDeadline(*context));
    if (report.deadline_exceeded) {
      return absl::DeadlineExceededError(absl::StrCat("map ", *name, ": the check did not finish by the call's deadline (",
                                                      storage::FormatProblem(report.problems.back()), ")"));
    }
    VerifyReportToProto(report, *response);
    response->set_duration_seconds(absl::ToDoubleSeconds(admin_.clock->Now() - start));
    if (report.clean()) {
      DaemonLog()->info("check of map {}: clean", *name);
    } else {
      DaemonLog()->warn("check of map {}: {} problems, the first: {}", *name, report.problems.size(),
                  storage::FormatProblem(report.problems.front()));
    }
    return absl::OkStatus();
  });
}

grpc::ServerUnaryReactor* AdminServiceImpl::SalvageMap(grpc::CallbackServerContext* context,
                                                       const v1::SalvageMapRequest* request,
                                                       v1::SalvageMapResponse* response) {
  return ServeUnary(deps_, context, kSalvageMap, [this, context, request, response]() -> absl::Status {
    auto name = ResolveMapName(*context, request->map(), "map");
    if (!name.ok()) return name.status();
    auto store = deps_.store->Get();
    if (!store.ok()) return store.status();
    const absl::Time start = admin_.clock->Now();
    auto report = (*store)->SalvageMap(*name, request->new_map(), CallDeadline(*context));
    if (!report.ok()) {
      DaemonLog()->warn("salvage of map {} failed: {}", *name, std::string(report.status().message()));
      return RenameNameField(report.status(), "new_map");
    }
    SalvageReportToProto(*report, *response);
    response->set_duration_seconds(absl::ToDoubleSeconds(admin_.clock->Now() - start));
    DaemonLog()->warn("map {} salvaged as {}: {} records kept, {} lost; log: {} records kept, {} lost ({} bytes); {} losses",
                *name, report->map.name, report->records_kept(), report->records_lost(), report->log.records_kept,
                report->log.records_lost, report->log.bytes_lost, report->losses);
    for (const storage::VerifyProblem& p : report->lost) {
      DaemonLog()->warn("salvage of map {}: lost: {}", *name, storage::FormatProblem(p));
    }
    return absl::OkStatus();
  });
}

grpc::ServerWriteReactor<v1::MapChunk>* AdminServiceImpl::ExportMap(grpc::CallbackServerContext* context,
                                                                    const v1::ExportMapRequest* request) {
  return ServeServerStream<v1::MapChunk>(
      deps_, context, kExportMap, [this, context, request](StreamWriter<v1::MapChunk>& out) -> absl::Status {
        auto name = ResolveMapName(*context, request->map(), "map");
        if (!name.ok()) return name.status();
        auto store = deps_.store->Get();
        if (!store.ok()) return store.status();
        const absl::Time start = admin_.clock->Now();
        uint64_t bytes = 0;
        const auto send = [&](const v1::MapChunk& chunk) {
          bytes += chunk.data().data().size() + chunk.batch().batch().size();
          return out.Write(chunk);
        };
        const bool tail = request->kind() == v1::MAP_EXPORT_KIND_TAIL;
        const absl::Status status =
            tail ? ExportMapTail(**store, *name, request->tail_after_lsn(), send)
                 : server::ExportMap(**store, *name, admin_.config->data_dir, request->chunk_bytes(), request->kind(),
                                     send);
        if (status.ok()) {
          DaemonLog()->info("export of map {} ({}): {} bytes in {}", *name, v1::MapExportKind_Name(request->kind()),
                            bytes, absl::FormatDuration(admin_.clock->Now() - start));
        }
        return status;
      });
}

grpc::ServerReadReactor<v1::MapChunk>* AdminServiceImpl::ImportMap(grpc::CallbackServerContext* context,
                                                                   v1::ImportMapResponse* response) {
  return ServeClientStream<v1::MapChunk>(
      deps_, context, kImportMap, response,
      [this, context](StreamReader<v1::MapChunk>& in, v1::ImportMapResponse& out) {
        return Import(in, *context, out);
      });
}

absl::Status AdminServiceImpl::Import(StreamReader<v1::MapChunk>& in, const grpc::CallbackServerContext& context,
                                      v1::ImportMapResponse& response) const {
  const absl::Time start = admin_.clock->Now();
  auto store = deps_.store->Get();
  if (!store.ok()) return store.status();
  auto staging = NewTransferDir(admin_.config->data_dir, "import");
  if (!staging.ok()) return staging.status();
  MapImportWriter writer(*staging);
  MapTailReader tail;
  std::string name;
  const auto import = [&]() -> absl::StatusOr<storage::MapInfo> {
    v1::MapChunk chunk;
    if (!in.Read(chunk)) return writer.Finish();  // an empty stream
    if (chunk.has_header() && chunk.header().kind() == v1::MAP_EXPORT_KIND_TAIL) {
      // An online move's tail, for the incoming copy here (server/services/map_tail.h).
      auto resolved = ResolveMapName(context, chunk.header().map(), "header.map");
      if (!resolved.ok()) return resolved.status();
      name = *std::move(resolved);
      do {
        if (absl::Status added = tail.Add(chunk); !added.ok()) return added;
      } while (in.Read(chunk));
      if (context.IsCancelled()) return absl::CancelledError("ImportMap: the client cancelled the stream");
      if (absl::Status finished = tail.Finish(); !finished.ok()) return finished;
      return ApplyMapTail(**store, name, tail);
    }
    do {
      if (absl::Status added = writer.Add(chunk); !added.ok()) return added;
      if (chunk.has_header()) {
        // Refused before the data is sent: the name is known from the first message.
        auto resolved = ResolveMapName(context, chunk.header().map(), "header.map");
        if (!resolved.ok()) return resolved.status();
        name = *std::move(resolved);
        if (auto existing = (*store)->GetMap(name); existing.ok() || !absl::IsNotFound(existing.status())) {
          if (!existing.ok()) return existing.status();
          return absl::AlreadyExistsError(absl::StrCat("map \"", name, "\" already exists"));
        }
      }
    } while (in.Read(chunk));
    if (context.IsCancelled()) return absl::CancelledError("ImportMap: the client cancelled the stream");
    if (absl::Status finished = writer.Finish(); !finished.ok()) return finished;
    return (*store)->RestoreMap(writer.dir(), name, CallDeadline(context));
  };
  auto info = import();
  std::error_code error;
  fs::remove_all(*staging, error);
  if (!info.ok()) {
    if (tail.header()) DropIncomingCopy(**store, name);
    DaemonLog()->warn("import refused: {}", info.status().ToString());
    return RenameNameField(info.status(), "header.map");
  }
  MapInfoToProto(*info, *response.mutable_map());
  AddMoveState(**store, *response.mutable_map());
  if (tail.header()) {
    response.set_bytes(tail.bytes());
    response.set_tail_batches(tail.records().size());
    response.set_duration_seconds(absl::ToDoubleSeconds(admin_.clock->Now() - start));
    DaemonLog()->info("map {}: its tail of {} batches applied; it serves", info->name, tail.records().size());
    return absl::OkStatus();
  }
  if (writer.header()) response.set_snapshot_lsn(writer.header()->snapshot_lsn());
  response.set_bytes(writer.bytes());
  const absl::Duration took = admin_.clock->Now() - start;
  response.set_duration_seconds(absl::ToDoubleSeconds(took));
  DaemonLog()->info("map {} imported: {} bytes in {}", info->name, writer.bytes(), absl::FormatDuration(took));
  return absl::OkStatus();
}

grpc::ServerUnaryReactor* AdminServiceImpl::SetMapMove(grpc::CallbackServerContext* context,
                                                       const v1::SetMapMoveRequest* request,
                                                       v1::SetMapMoveResponse* response) {
  return ServeUnary(deps_, context, kSetMapMove, [this, context, request, response] {
    return Move(*request, *context, *response);
  });
}

absl::Status AdminServiceImpl::Move(const v1::SetMapMoveRequest& request, const grpc::CallbackServerContext& context,
                                    v1::SetMapMoveResponse& response) const {
  auto map = LookUpMap(*deps_.store, context, request.map());
  if (!map.ok()) return map.status();
  const std::string& name = (*map)->info().name;
  absl::Status status;
  switch (request.step()) {
    case v1::MAP_MOVE_STEP_STOP_WRITES:
      status = (*map)->StopWrites();
      if (status.ok()) DaemonLog()->info("map {}: writes stopped for a move", name);
      break;
    case v1::MAP_MOVE_STEP_MOVED:
      if (request.to().empty()) return absl::InvalidArgumentError("to: the daemon the map moved to is required");
      status = (*map)->MarkMoved(request.to());
      if (status.ok()) DaemonLog()->info("map {}: moved to {}; this copy refuses writes until deleted", name, request.to());
      break;
    case v1::MAP_MOVE_STEP_RESUME_WRITES:
      status = (*map)->ResumeWrites();
      if (status.ok()) DaemonLog()->info("map {}: writes resumed (no move)", name);
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("step: must be STOP_WRITES, MOVED or RESUME_WRITES, got ", v1::MapMoveStep_Name(request.step())));
  }
  if (!status.ok()) return status;
  const storage::MoveStatus move = (*map)->Move();
  response.set_state(MoveStateToProto(move.state));
  response.set_moved_to(move.moved_to);
  return absl::OkStatus();
}

grpc::ServerUnaryReactor* AdminServiceImpl::GetServerStatus(grpc::CallbackServerContext* context,
                                                            const v1::GetServerStatusRequest* /*request*/,
                                                            v1::GetServerStatusResponse* response) {
  return ServeUnary(deps_, context, kGetServerStatus, [this, response] { return FillStatus(*response); });
}

absl::Status AdminServiceImpl::FillStatus(v1::GetServerStatusResponse& response) const {
  const ServerConfig& config = *admin_.config;
  response.set_version(FREMEN_VERSION);
  TimeToProto(start_time_, *response.mutable_start_time());
  response.set_uptime_seconds(absl::ToDoubleSeconds(admin_.clock->Now() - start_time_));
  response.set_running_operations(static_cast<uint32_t>(admin_.operations->running()));
  if (admin_.scheduler != nullptr) {
    if (const absl::Time next = admin_.scheduler->NextRun(); next != absl::InfiniteFuture()) {
      TimeToProto(next, *response.mutable_next_update_time());
    }
  }
  response.set_update_schedule(config.update_schedule);
  response.set_update_time_zone(config.update_time_zone);
  response.set_tls(!config.tls_cert_pem.empty());
  response.set_tokens_required(deps_.auth->enabled());
  std::error_code error;
  if (const fs::space_info space = fs::space(config.data_dir, error); !error) {
    response.set_data_dir_free_bytes(space.available);
  }
  for (const OperationView& view : admin_.operations->LastUpdates()) OperationToProto(view, *response.add_last_updates());
  // While the maps are recovered the status still answers: that is when an operator asks.
  auto store = deps_.store->Get();
  if (!store.ok()) {
    response.set_store_state(v1::STORE_STATE_RECOVERING);
    return absl::OkStatus();
  }
  response.set_store_state(v1::STORE_STATE_OPEN);
  auto maps = ListAllMaps(**store);
  if (!maps.ok()) return maps.status();
  response.set_map_count(maps->size());
  // Maps that did not open (their calls answer the error), then maps whose writes stopped.
  for (const storage::FailedMap& failed_map : (*store)->FailedMaps()) {
    v1::MapFault& failed = *response.add_failed_maps();
    failed.set_map(failed_map.name);
    failed.set_error(failed_map.status.ToString());
  }
  for (const std::string& dir : (*store)->UnknownDirectories()) response.add_unknown_directories(dir);
  if (admin_.scrubber != nullptr) ScrubsToProto(*admin_.scrubber, response);
  for (const storage::MapInfo& info : *maps) {
    auto map = (*store)->Map(info.name);
    if (!map.ok()) continue;  // deleted meanwhile, or failed (listed above)
    if (const absl::Status fault = (*map)->WriteError(); !fault.ok()) {
      v1::MapFault& failed = *response.add_failed_maps();
      failed.set_map(info.name);
      failed.set_error(fault.ToString());
    }
    const storage::MapStats stats = (*map)->Stats();
    if (stats.last_update) {
      v1::MapLastUpdate& last = *response.add_map_updates();
      last.set_map(info.name);
      UpdateRecordToProto(*stats.last_update, *last.mutable_update());
    }
    response.set_state_count(response.state_count() + stats.totals.states);
    response.set_dynamic_state_count(response.dynamic_state_count() + stats.totals.dynamic_states);
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
