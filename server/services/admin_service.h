// fremen.v1.AdminService: the update job as a long-running operation (server/jobs/operations.h),
// backups and restores of maps, and the server's status.
//
// RunUpdate, GetOperation, ListOperations and CancelOperation only touch the operation registry and
// the catalog, and run inline; BackupMap and RestoreMap copy files, CheckMap reads a whole map
// (storage/verify.h), SalvageMap reads a damaged one and writes a new one (storage/salvage.h) and
// GetServerStatus reads every map's statistics, so they run on the blocking pool; so do ExportMap and
// ImportMap, streams of a map's backup (server/services/map_transfer.h) served as loops on a pool
// thread (server/rpc/blocking_stream.h), and SetMapMove, whose stop of writes waits for the queued
// batches. Write methods (RunUpdate, CancelOperation, BackupMap, RestoreMap, SalvageMap, ExportMap,
// ImportMap, SetMapMove) need a write token when tokens are configured.
// Thread-safety: gRPC calls the handlers from any thread; the registry is thread-safe and the
// service's one mutable member, the backups in progress, has its own mutex.
#pragma once

#include <string>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_set.h"
#include "base/mutex.h"
#include "absl/time/time.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "server/jobs/clock.h"
#include "server/daemon/config.h"
#include "server/jobs/operations.h"
#include "server/jobs/scrubber.h"
#include "server/rpc/blocking_stream.h"
#include "server/services/map_transfer.h"
#include "server/rpc/unary_call.h"
#include "server/jobs/update_scheduler.h"

namespace fremen::server {

// What the admin service needs beyond ServiceDeps; owned by the daemon, outliving the server.
struct AdminDeps {
  OperationRegistry* operations = nullptr;
  const UpdateScheduler* scheduler = nullptr;  // null: no schedule
  const Scrubber* scrubber = nullptr;          // null: no background scrub
  // The daemon's settings; backup_dir is absolute (resolved before the server starts).
  const ServerConfig* config = nullptr;
  const Clock* clock = nullptr;
};

class AdminServiceImpl final : public v1::AdminService::CallbackService {
 public:
  AdminServiceImpl(const ServiceDeps& deps, const AdminDeps& admin)
      : deps_(deps), admin_(admin), start_time_(admin.clock->Now()) {
    ClearTransfers(admin.config->data_dir);  // what a killed daemon left staged
  }

  grpc::ServerUnaryReactor* RunUpdate(grpc::CallbackServerContext* context, const v1::RunUpdateRequest* request,
                                      v1::Operation* response) override;
  grpc::ServerUnaryReactor* GetOperation(grpc::CallbackServerContext* context,
                                         const v1::GetOperationRequest* request, v1::Operation* response) override;
  grpc::ServerUnaryReactor* ListOperations(grpc::CallbackServerContext* context,
                                           const v1::ListOperationsRequest* request,
                                           v1::ListOperationsResponse* response) override;
  grpc::ServerUnaryReactor* CancelOperation(grpc::CallbackServerContext* context,
                                            const v1::CancelOperationRequest* request,
                                            v1::Operation* response) override;
  grpc::ServerUnaryReactor* BackupMap(grpc::CallbackServerContext* context, const v1::BackupMapRequest* request,
                                      v1::BackupMapResponse* response) override;
  grpc::ServerUnaryReactor* RestoreMap(grpc::CallbackServerContext* context, const v1::RestoreMapRequest* request,
                                       v1::RestoreMapResponse* response) override;
  grpc::ServerUnaryReactor* GetServerStatus(grpc::CallbackServerContext* context,
                                            const v1::GetServerStatusRequest* request,
                                            v1::GetServerStatusResponse* response) override;
  grpc::ServerUnaryReactor* CheckMap(grpc::CallbackServerContext* context, const v1::CheckMapRequest* request,
                                     v1::CheckMapResponse* response) override;
  grpc::ServerUnaryReactor* SalvageMap(grpc::CallbackServerContext* context, const v1::SalvageMapRequest* request,
                                       v1::SalvageMapResponse* response) override;
  grpc::ServerWriteReactor<v1::MapChunk>* ExportMap(grpc::CallbackServerContext* context,
                                                    const v1::ExportMapRequest* request) override;
  grpc::ServerReadReactor<v1::MapChunk>* ImportMap(grpc::CallbackServerContext* context,
                                                   v1::ImportMapResponse* response) override;
  grpc::ServerUnaryReactor* SetMapMove(grpc::CallbackServerContext* context, const v1::SetMapMoveRequest* request,
                                       v1::SetMapMoveResponse* response) override;

 private:
  // The operation `name` (field "name"), checked against the map the call names, if any.
  absl::StatusOr<OperationView> FindOperation(const grpc::CallbackServerContext& context,
                                              const std::string& request_map, const std::string& name) const;
  absl::Status Backup(const v1::BackupMapRequest& request, const grpc::CallbackServerContext& context,
                      v1::BackupMapResponse& response) const;
  // The copy itself, once the directory is claimed.
  absl::Status BackupInto(const std::string& name, const std::string& dir, const std::string& requested_dir,
                          storage::Store& store, v1::BackupMapResponse& response) const;
  absl::Status Restore(const v1::RestoreMapRequest& request, const grpc::CallbackServerContext& context,
                       v1::RestoreMapResponse& response) const;
  absl::Status FillStatus(v1::GetServerStatusResponse& response) const;
  absl::Status Import(StreamReader<v1::MapChunk>& in, const grpc::CallbackServerContext& context,
                      v1::ImportMapResponse& response) const;
  absl::Status Move(const v1::SetMapMoveRequest& request, const grpc::CallbackServerContext& context,
                    v1::SetMapMoveResponse& response) const;

  // Claims a backup directory for one call (false: another backup is writing there), so that two
  // concurrent backups never interleave in one directory.
  bool ClaimBackupDir(const std::string& dir) const ABSL_LOCKS_EXCLUDED(backups_mutex_);
  void ReleaseBackupDir(const std::string& dir) const ABSL_LOCKS_EXCLUDED(backups_mutex_);

  const ServiceDeps deps_;
  const AdminDeps admin_;
  const absl::Time start_time_;
  mutable base::Mutex backups_mutex_;
  mutable absl::flat_hash_set<std::string> backups_in_progress_ ABSL_GUARDED_BY(backups_mutex_);
};

}  // namespace fremen::server
