// Env::Default(): the POSIX file system.
#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "absl/strings/str_cat.h"
#include "storage/env/env.h"

namespace fremen::storage {

namespace {

absl::Status Errno(const std::string& what, const std::string& path) {
  return IoError(errno, absl::StrCat(what, " ", path));
}

class PosixWritableFile : public WritableFile {
 public:
  PosixWritableFile(std::string path, int fd) : path_(std::move(path)), fd_(fd) {}
  ~PosixWritableFile() override { (void)Close(); }

  absl::Status Append(std::span<const uint8_t> data) override {
    size_t written = 0;
    while (written < data.size()) {
      const ssize_t n = ::write(fd_, data.data() + written, data.size() - written);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return Errno("write", path_);
      written += static_cast<size_t>(n);
    }
    return absl::OkStatus();
  }

  absl::Status Sync() override { return ::fdatasync(fd_) == 0 ? absl::OkStatus() : Errno("fdatasync", path_); }

  absl::Status Close() override {
    if (fd_ < 0) return absl::OkStatus();
    const int rc = ::close(fd_);
    fd_ = -1;
    return rc == 0 ? absl::OkStatus() : Errno("close", path_);
  }

 private:
  const std::string path_;
  int fd_;
};

class PosixEnv : public Env {
 public:
  absl::StatusOr<std::unique_ptr<WritableFile>> NewWritableFile(const std::string& path) override {
    return Open(path, O_WRONLY | O_APPEND | O_CREAT | O_EXCL | O_CLOEXEC, "create");
  }

  absl::StatusOr<std::unique_ptr<WritableFile>> NewAppendableFile(const std::string& path) override {
    return Open(path, O_WRONLY | O_APPEND | O_CLOEXEC, "open");
  }

  absl::StatusOr<std::string> ReadFile(const std::string& path) override {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return Errno("open", path);
    const auto fail = [&](const char* what) {
      absl::Status s = Errno(what, path);
      ::close(fd);
      return s;
    };
    // Straight into a string of the file's size (a log segment is tens of MB): growing one by
    // appends copied it over and over (a tenth of a recovery's profile, docs/storage.md).
    struct stat st;
    if (::fstat(fd, &st) != 0) return fail("fstat");
    std::string data(static_cast<size_t>(st.st_size), '\0');
    size_t got = 0;
    while (got < data.size()) {
      const ssize_t n = ::read(fd, data.data() + got, data.size() - got);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return fail("read");
      if (n == 0) break;  // it shrank
      got += static_cast<size_t>(n);
    }
    data.resize(got);
    // Whatever was appended since fstat.
    char chunk[1 << 16];
    for (;;) {
      const ssize_t n = ::read(fd, chunk, sizeof chunk);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return fail("read");
      if (n == 0) break;
      data.append(chunk, static_cast<size_t>(n));
    }
    ::close(fd);
    return data;
  }

  absl::StatusOr<uint64_t> FileSize(const std::string& path) override {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) return Errno("stat", path);
    return static_cast<uint64_t>(st.st_size);
  }

  absl::StatusOr<std::vector<std::string>> ListDir(const std::string& dir) override {
    DIR* d = ::opendir(dir.c_str());
    if (!d) return Errno("opendir", dir);
    std::vector<std::string> names;
    while (const dirent* e = ::readdir(d)) {
      const std::string_view name = e->d_name;
      if (name != "." && name != "..") names.emplace_back(name);
    }
    ::closedir(d);
    return names;
  }

  absl::Status CreateDir(const std::string& dir) override {
    if (::mkdir(dir.c_str(), 0750) != 0 && errno != EEXIST) return Errno("mkdir", dir);
    return absl::OkStatus();
  }

  absl::Status Truncate(const std::string& path, uint64_t size) override {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) return Errno("open", path);
    absl::Status s;
    if (::ftruncate(fd, static_cast<off_t>(size)) != 0) {
      s = Errno("truncate", path);
    } else if (::fdatasync(fd) != 0) {
      s = Errno("fdatasync", path);
    }
    ::close(fd);
    return s;
  }

  absl::Status Unlink(const std::string& path) override {
    return ::unlink(path.c_str()) == 0 ? absl::OkStatus() : Errno("unlink", path);
  }

  absl::Status Rename(const std::string& from, const std::string& to) override {
    return std::rename(from.c_str(), to.c_str()) == 0 ? absl::OkStatus()
                                                      : Errno(absl::StrCat("rename ", from, " to"), to);
  }

  absl::Status SyncDir(const std::string& dir) override {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return Errno("open", dir);
    const int rc = ::fsync(fd);
    absl::Status s = rc == 0 ? absl::OkStatus() : Errno("fsync", dir);
    ::close(fd);
    return s;
  }

 private:
  absl::StatusOr<std::unique_ptr<WritableFile>> Open(const std::string& path, int flags, const char* what) {
    const int fd = ::open(path.c_str(), flags, 0640);
    if (fd < 0) return Errno(what, path);
    return std::make_unique<PosixWritableFile>(path, fd);
  }
};

}  // namespace

Env* Env::Default() {
  static PosixEnv* env = new PosixEnv;
  return env;
}

}  // namespace fremen::storage
