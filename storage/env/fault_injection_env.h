// An Env for tests that does what disks do wrong, after LevelDB's FaultInjectionTestEnv: it passes
// every operation to a base Env (the real file system) and remembers what is durable, so that it
// can fail fsync, run out of space, fail with EIO, tear a write, and cut the power.
//
// Durability model: a file's bytes are durable up to the length of its last successful Sync (a
// failed Sync makes nothing more durable; files that existed before the env saw them count as
// durable). A creation, unlink or rename is durable once its directory is synced. A power cut
// (CutPower, or CutPowerAfter a number of operations) then, under one lock:
//   1. undoes, newest first, every creation, unlink and rename whose directory was not synced
//      since: created files disappear, unlinked ones reappear (Unlink only moves a file aside,
//      under a name ListDir hides, until SyncDir), renames go back;
//   2. cuts every file to its durable length — or, with tear_at_cut, keeps a random prefix of its
//      unsynced bytes too (a write the disk finished only in part);
//   3. refuses every later operation (Unavailable), as a dead machine would, until PowerOn().
// Renames are modelled within one directory only (the store renames a temporary beside its target);
// directories count as durable once created. LMDB does its own I/O, outside any Env:
// wal_fault_test.cc says how a power cut under a MapStore keeps LMDB from writing after the cut.
//
// Thread-safety: every method may be called from any thread; operations are serialised.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "base/mutex.h"
#include "storage/env/env.h"

namespace fremen::storage {

class FaultInjectionEnv : public Env {
 public:
  explicit FaultInjectionEnv(uint64_t seed = 1, Env* base = Env::Default());
  ~FaultInjectionEnv() override;

  // Faults on demand, each until changed; errno 0 turns one off.

  // Sync and SyncDir fail with this errno (e.g. EIO: an fsync failure), making nothing durable.
  void FailSyncs(int errno_value);
  // Append fails with this errno (ENOSPC, EIO) and writes nothing.
  void FailWrites(int errno_value);
  // The next Append writes only a random part of its bytes (at least one, not all) and fails with
  // EIO.
  void TearNextWrite();

  // Called before every file Sync, outside the env's lock (it may block, to hold a sync in
  // progress); a non-OK status fails that Sync with it and makes nothing more durable. Default:
  // none.
  void set_before_sync(std::function<absl::Status()> hook);

  // Cuts the power now (see above).
  void CutPower();
  // Cuts the power just before the n-th operation from now that changes a file or directory
  // (creation, Append, Sync, SyncDir, Truncate, Unlink, Rename), which is refused. 0: never.
  void CutPowerAfter(uint64_t operations);
  // At a cut, files keep a random prefix of their unsynced bytes instead of none. Default: false.
  void set_tear_at_cut(bool tear);
  bool power_cut() const;
  // The machine starts again: operations go through; files are as the cut left them, all durable.
  void PowerOn();
  // Operations that changed a file or directory so far (to place a CutPowerAfter).
  uint64_t operations() const;

  absl::StatusOr<std::unique_ptr<WritableFile>> NewWritableFile(const std::string& path) override;
  absl::StatusOr<std::unique_ptr<WritableFile>> NewAppendableFile(const std::string& path) override;
  absl::StatusOr<std::string> ReadFile(const std::string& path) override;
  absl::StatusOr<uint64_t> FileSize(const std::string& path) override;
  absl::StatusOr<std::vector<std::string>> ListDir(const std::string& dir) override;
  absl::Status CreateDir(const std::string& dir) override;
  absl::Status Truncate(const std::string& path, uint64_t size) override;
  absl::Status Unlink(const std::string& path) override;
  absl::Status Rename(const std::string& from, const std::string& to) override;
  absl::Status SyncDir(const std::string& dir) override;

 private:
  class File;
  struct FileState {
    uint64_t size = 0;    // bytes written through the env
    uint64_t synced = 0;  // the durable prefix
  };
  // A directory change not yet made durable by SyncDir, with what undoes it.
  struct DirOp {
    enum class Kind { kCreate, kUnlink, kRename } kind;
    std::string path;   // created, unlinked or renamed-to
    std::string from;   // kRename: the old name
    std::string aside;  // kUnlink, and kRename over a file: where the old file was moved
  };

  // Counts a changing operation; cuts the power when due. An error: refuse the operation.
  absl::Status EnterLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  absl::Status LiveLocked() const ABSL_SHARED_LOCKS_REQUIRED(mutex_);
  void CutPowerLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  std::string AsideNameLocked(const std::string& path) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  void MoveStateLocked(const std::string& from, const std::string& to) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  absl::Status AppendLocked(const std::string& path, WritableFile& base, std::span<const uint8_t> data)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);
  absl::Status SyncLocked(const std::string& path, WritableFile& base) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_);

  Env* const base_;
  mutable base::Mutex mutex_;
  std::mt19937_64 rng_ ABSL_GUARDED_BY(mutex_);
  int sync_errno_ ABSL_GUARDED_BY(mutex_) = 0;
  int write_errno_ ABSL_GUARDED_BY(mutex_) = 0;
  bool tear_next_write_ ABSL_GUARDED_BY(mutex_) = false;
  std::function<absl::Status()> before_sync_;  // set before the env is used
  bool tear_at_cut_ ABSL_GUARDED_BY(mutex_) = false;
  bool power_cut_ ABSL_GUARDED_BY(mutex_) = false;
  uint64_t operations_ ABSL_GUARDED_BY(mutex_) = 0;
  uint64_t cut_at_ ABSL_GUARDED_BY(mutex_) = 0;  // operations_ value at which to cut; 0: none
  uint64_t aside_counter_ ABSL_GUARDED_BY(mutex_) = 0;
  absl::flat_hash_map<std::string, FileState> files_ ABSL_GUARDED_BY(mutex_);
  // By directory, oldest first.
  absl::flat_hash_map<std::string, std::vector<DirOp>> pending_ ABSL_GUARDED_BY(mutex_);
};

}  // namespace fremen::storage
