#include "storage/env/fault_injection_env.h"

#include <algorithm>
#include <cerrno>

#include "absl/strings/str_cat.h"

namespace fremen::storage {

namespace {

// Marks the files Unlink moved aside; ListDir hides them.
constexpr char kAsideMark[] = ".fault-unlinked-";

}  // namespace

class FaultInjectionEnv::File : public WritableFile {
 public:
  File(FaultInjectionEnv* env, std::string path, std::unique_ptr<WritableFile> base)
      : env_(env), path_(std::move(path)), base_(std::move(base)) {}

  absl::Status Append(std::span<const uint8_t> data) override {
    base::MutexLock lock(&env_->mutex_);
    if (absl::Status s = env_->EnterLocked(); !s.ok()) return s;
    return env_->AppendLocked(path_, *base_, data);
  }

  absl::Status Sync() override {
    if (env_->before_sync_) {
      if (absl::Status s = env_->before_sync_(); !s.ok()) return s;
    }
    base::MutexLock lock(&env_->mutex_);
    if (absl::Status s = env_->EnterLocked(); !s.ok()) return s;
    return env_->SyncLocked(path_, *base_);
  }

  absl::Status Close() override { return base_->Close(); }

 private:
  FaultInjectionEnv* const env_;
  const std::string path_;
  std::unique_ptr<WritableFile> base_;
};

FaultInjectionEnv::FaultInjectionEnv(uint64_t seed, Env* base) : base_(base), rng_(seed) {}

FaultInjectionEnv::~FaultInjectionEnv() = default;

void FaultInjectionEnv::FailSyncs(int errno_value) {
  base::MutexLock lock(&mutex_);
  sync_errno_ = errno_value;
}

void FaultInjectionEnv::set_before_sync(std::function<absl::Status()> hook) { before_sync_ = std::move(hook); }

void FaultInjectionEnv::FailWrites(int errno_value) {
  base::MutexLock lock(&mutex_);
  write_errno_ = errno_value;
}

void FaultInjectionEnv::TearNextWrite() {
  base::MutexLock lock(&mutex_);
  tear_next_write_ = true;
}

void FaultInjectionEnv::CutPower() {
  base::MutexLock lock(&mutex_);
  if (!power_cut_) CutPowerLocked();
}

void FaultInjectionEnv::CutPowerAfter(uint64_t operations) {
  base::MutexLock lock(&mutex_);
  cut_at_ = operations == 0 ? 0 : operations_ + operations;
}

void FaultInjectionEnv::set_tear_at_cut(bool tear) {
  base::MutexLock lock(&mutex_);
  tear_at_cut_ = tear;
}

bool FaultInjectionEnv::power_cut() const {
  base::MutexLock lock(&mutex_);
  return power_cut_;
}

void FaultInjectionEnv::PowerOn() {
  base::MutexLock lock(&mutex_);
  power_cut_ = false;
  cut_at_ = 0;
}

uint64_t FaultInjectionEnv::operations() const {
  base::MutexLock lock(&mutex_);
  return operations_;
}

absl::Status FaultInjectionEnv::LiveLocked() const {
  if (power_cut_) return absl::UnavailableError("fault injection: the power is cut");
  return absl::OkStatus();
}

absl::Status FaultInjectionEnv::EnterLocked() {
  if (absl::Status s = LiveLocked(); !s.ok()) return s;
  ++operations_;
  if (cut_at_ != 0 && operations_ >= cut_at_) {
    CutPowerLocked();
    return LiveLocked();
  }
  return absl::OkStatus();
}

void FaultInjectionEnv::CutPowerLocked() {
  // 1. Directory changes not made durable, newest first. Errors are ignored: a test that cuts the
  // power checks what survives, and a file that cannot be restored shows up there.
  for (auto& [dir, ops] : pending_) {
    for (auto op = ops.rbegin(); op != ops.rend(); ++op) {
      switch (op->kind) {
        case DirOp::Kind::kCreate:
          (void)base_->Unlink(op->path);
          files_.erase(op->path);
          break;
        case DirOp::Kind::kUnlink:
          (void)base_->Rename(op->aside, op->path);
          MoveStateLocked(op->aside, op->path);
          break;
        case DirOp::Kind::kRename:
          (void)base_->Rename(op->path, op->from);
          MoveStateLocked(op->path, op->from);
          if (!op->aside.empty()) {
            (void)base_->Rename(op->aside, op->path);
            MoveStateLocked(op->aside, op->path);
          }
          break;
      }
    }
  }
  pending_.clear();
  // 2. Unsynced bytes.
  for (auto& [path, state] : files_) {
    if (state.size <= state.synced) continue;
    uint64_t keep = state.synced;
    if (tear_at_cut_) keep += rng_() % (state.size - state.synced + 1);
    (void)base_->Truncate(path, keep);
    state.size = state.synced = keep;
  }
  power_cut_ = true;
  cut_at_ = 0;
}

std::string FaultInjectionEnv::AsideNameLocked(const std::string& path) {
  return absl::StrCat(path, kAsideMark, ++aside_counter_);
}

void FaultInjectionEnv::MoveStateLocked(const std::string& from, const std::string& to) {
  auto it = files_.find(from);
  if (it == files_.end()) {
    files_.erase(to);
    return;
  }
  const FileState state = it->second;
  files_.erase(it);
  files_[to] = state;
}

absl::Status FaultInjectionEnv::AppendLocked(const std::string& path, WritableFile& base,
                                             std::span<const uint8_t> data) {
  if (write_errno_ != 0) return IoError(write_errno_, absl::StrCat("write ", path, " (injected)"));
  std::span<const uint8_t> written = data;
  const bool tear = tear_next_write_ && data.size() >= 2;
  if (tear) {
    tear_next_write_ = false;
    written = data.first(1 + rng_() % (data.size() - 1));
  }
  if (absl::Status s = base.Append(written); !s.ok()) return s;
  files_[path].size += written.size();
  if (tear) return IoError(EIO, absl::StrCat("write ", path, " (injected: torn after ", written.size(), " bytes)"));
  return absl::OkStatus();
}

absl::Status FaultInjectionEnv::SyncLocked(const std::string& path, WritableFile& base) {
  if (sync_errno_ != 0) return IoError(sync_errno_, absl::StrCat("fdatasync ", path, " (injected)"));
  if (absl::Status s = base.Sync(); !s.ok()) return s;
  FileState& state = files_[path];
  state.synced = state.size;
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<WritableFile>> FaultInjectionEnv::NewWritableFile(const std::string& path) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  auto file = base_->NewWritableFile(path);
  if (!file.ok()) return file.status();
  files_[path] = FileState{};
  pending_[DirName(path)].push_back({DirOp::Kind::kCreate, path, "", ""});
  return std::make_unique<File>(this, path, *std::move(file));
}

absl::StatusOr<std::unique_ptr<WritableFile>> FaultInjectionEnv::NewAppendableFile(const std::string& path) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  auto file = base_->NewAppendableFile(path);
  if (!file.ok()) return file.status();
  if (!files_.contains(path)) {
    // Not written through this env: what is there counts as durable.
    auto size = base_->FileSize(path);
    if (!size.ok()) return size.status();
    files_[path] = FileState{*size, *size};
  }
  return std::make_unique<File>(this, path, *std::move(file));
}

absl::StatusOr<std::string> FaultInjectionEnv::ReadFile(const std::string& path) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = LiveLocked(); !s.ok()) return s;
  return base_->ReadFile(path);
}

absl::StatusOr<uint64_t> FaultInjectionEnv::FileSize(const std::string& path) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = LiveLocked(); !s.ok()) return s;
  return base_->FileSize(path);
}

absl::StatusOr<std::vector<std::string>> FaultInjectionEnv::ListDir(const std::string& dir) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = LiveLocked(); !s.ok()) return s;
  auto names = base_->ListDir(dir);
  if (names.ok()) {
    std::erase_if(*names, [](const std::string& n) { return n.find(kAsideMark) != std::string::npos; });
  }
  return names;
}

absl::Status FaultInjectionEnv::CreateDir(const std::string& dir) {
  // Directories are taken as durable at once: the store creates them before it writes anything that
  // matters, and syncs the files in them.
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  return base_->CreateDir(dir);
}

absl::Status FaultInjectionEnv::Truncate(const std::string& path, uint64_t size) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  if (absl::Status s = base_->Truncate(path, size); !s.ok()) return s;
  files_[path] = FileState{size, size};  // Truncate is durable (env.h)
  return absl::OkStatus();
}

absl::Status FaultInjectionEnv::Unlink(const std::string& path) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  if (auto size = base_->FileSize(path); !size.ok()) return size.status();
  const std::string aside = AsideNameLocked(path);
  if (absl::Status s = base_->Rename(path, aside); !s.ok()) return s;
  MoveStateLocked(path, aside);
  pending_[DirName(path)].push_back({DirOp::Kind::kUnlink, path, "", aside});
  return absl::OkStatus();
}

absl::Status FaultInjectionEnv::Rename(const std::string& from, const std::string& to) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  std::string aside;
  if (base_->FileSize(to).ok()) {
    aside = AsideNameLocked(to);
    if (absl::Status s = base_->Rename(to, aside); !s.ok()) return s;
    MoveStateLocked(to, aside);
  }
  if (absl::Status s = base_->Rename(from, to); !s.ok()) return s;
  MoveStateLocked(from, to);
  pending_[DirName(to)].push_back({DirOp::Kind::kRename, to, from, aside});
  return absl::OkStatus();
}

absl::Status FaultInjectionEnv::SyncDir(const std::string& dir) {
  base::MutexLock lock(&mutex_);
  if (absl::Status s = EnterLocked(); !s.ok()) return s;
  if (sync_errno_ != 0) return IoError(sync_errno_, absl::StrCat("fsync ", dir, " (injected)"));
  if (absl::Status s = base_->SyncDir(dir); !s.ok()) return s;
  // The changes are durable now: files moved aside are gone for good.
  if (auto it = pending_.find(dir); it != pending_.end()) {
    for (const DirOp& op : it->second) {
      if (!op.aside.empty()) {
        (void)base_->Unlink(op.aside);
        files_.erase(op.aside);
      }
    }
    pending_.erase(it);
  }
  return absl::OkStatus();
}

}  // namespace fremen::storage
