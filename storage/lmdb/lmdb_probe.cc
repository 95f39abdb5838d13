#include "storage/lmdb/lmdb_probe.h"

#include <lmdb.h>
#include <signal.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "storage/isolated_child.h"
#include "storage/lmdb/lmdb_env.h"

namespace fremen::storage {

namespace {

// What the child writes to the parent, one line each: "F <index>" before it opens the index-th environment, "E <rc>"
// for an LMDB error, "A <text>" for a failed LMDB assertion (then it aborts).
constexpr char kFileTag = 'F';
constexpr char kErrorTag = 'E';
constexpr char kAssertTag = 'A';
// Of the child's output, no more than this is kept (an assertion line is under 400 bytes).
constexpr size_t kMaxOutput = 64 << 10;

// --- the child: LMDB's C API, write() and _exit() only ---

int probe_fd = -1;  // OnAssert has no other way to it

void WriteLine(char tag, long number) {
  char line[32];
  size_t at = sizeof(line);
  line[--at] = '\n';
  const bool negative = number < 0;
  unsigned long magnitude = negative ? 0ul - static_cast<unsigned long>(number) : static_cast<unsigned long>(number);
  do {
    line[--at] = static_cast<char>('0' + magnitude % 10);
    magnitude /= 10;
  } while (magnitude > 0);
  if (negative) line[--at] = '-';
  line[--at] = ' ';
  line[--at] = tag;
  (void)WriteAll(probe_fd, std::string_view(line + at, sizeof(line) - at));
}

// LMDB calls this instead of printing to stderr (whose lock a thread of the parent may have held at fork) before it
// aborts.
void OnAssert(MDB_env*, const char* message) {
  const char tag[2] = {kAssertTag, ' '};
  (void)WriteAll(probe_fd, std::string_view(tag, 2));
  (void)WriteAll(probe_fd, message);
  (void)WriteAll(probe_fd, "\n");
  signal(SIGABRT, SIG_DFL);
  raise(SIGABRT);
  _exit(3);
}

// Reads every record of `dbi`, touching each page of its value (overflow pages are reached only so).
int WalkDatabase(MDB_txn* txn, MDB_dbi dbi, bool open_named) {
  MDB_cursor* cursor;
  int rc = mdb_cursor_open(txn, dbi, &cursor);
  if (rc != MDB_SUCCESS) return rc;
  MDB_val key, value;
  volatile uint8_t sink = 0;
  while ((rc = mdb_cursor_get(cursor, &key, &value, MDB_NEXT)) == MDB_SUCCESS) {
    const auto* bytes = static_cast<const uint8_t*>(value.mv_data);
    for (size_t i = 0; i < value.mv_size; i += 4096) sink = sink ^ bytes[i];
    if (value.mv_size > 0) sink = sink ^ bytes[value.mv_size - 1];
    if (!open_named) continue;
    // A key of the main database names a database, or is a plain record (MDB_INCOMPATIBLE).
    char name[512];
    if (key.mv_size >= sizeof(name)) continue;
    std::memcpy(name, key.mv_data, key.mv_size);
    name[key.mv_size] = '\0';
    MDB_dbi named;
    const int opened = mdb_dbi_open(txn, name, 0, &named);
    if (opened == MDB_INCOMPATIBLE || opened == MDB_NOTFOUND) continue;
    if (opened != MDB_SUCCESS) {
      rc = opened;
      break;
    }
    if (const int walked = WalkDatabase(txn, named, false); walked != MDB_SUCCESS) {
      rc = walked;
      break;
    }
  }
  mdb_cursor_close(cursor);
  return rc == MDB_NOTFOUND ? MDB_SUCCESS : rc;
}

int WalkEnvironment(const char* dir) {
  MDB_env* env;
  int rc = mdb_env_create(&env);
  if (rc != MDB_SUCCESS) return rc;
  mdb_env_set_assert(env, OnAssert);
  mdb_env_set_maxdbs(env, 256);
  // Read-only and without the lock file: the child must change nothing, and the parent has not opened the environment
  // yet.
  rc = mdb_env_open(env, dir, MDB_RDONLY | MDB_NOLOCK | MDB_NORDAHEAD | MDB_NOTLS, 0);
  MDB_txn* txn = nullptr;
  if (rc == MDB_SUCCESS) rc = mdb_txn_begin(env, nullptr, MDB_RDONLY, &txn);
  if (rc == MDB_SUCCESS) rc = WalkDatabase(txn, /*FREE_DBI*/ 0,
                                           false);  // as a writer's page allocation reads it
  if (rc == MDB_SUCCESS) rc = WalkDatabase(txn, /*MAIN_DBI*/ 1, true);
  if (txn != nullptr) mdb_txn_abort(txn);
  mdb_env_close(env);
  return rc;
}

// The child's work: false after an LMDB error (reported on the pipe).
bool WalkAll(const std::vector<const char*>& dirs, int fd) {
  probe_fd = fd;
  for (int s : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) signal(s, SIG_DFL);
  for (size_t i = 0; i < dirs.size(); ++i) {
    WriteLine(kFileTag, static_cast<long>(i));
    if (const int rc = WalkEnvironment(dirs[i]); rc != MDB_SUCCESS) {
      WriteLine(kErrorTag, rc);
      return false;
    }
  }
  return true;
}

// --- the parent ---

// `output` is what the child wrote; `timed_out` that it was killed at the deadline, else `exit` how it ended.
absl::Status Interpret(const std::string& output, bool timed_out, const ChildExit& exit,
                       const std::vector<std::string>& dirs, absl::Duration timeout) {
  if (!timed_out && exit.ok()) return absl::OkStatus();
  size_t index = 0;
  int lmdb_error = 0;
  std::string assertion;
  for (absl::string_view line : absl::StrSplit(output, '\n', absl::SkipEmpty())) {
    if (line.size() < 2) continue;
    const absl::string_view rest = line.substr(2);
    if (line[0] == kFileTag) {
      (void)absl::SimpleAtoi(rest, &index);
    } else if (line[0] == kErrorTag) {
      (void)absl::SimpleAtoi(rest, &lmdb_error);
    } else if (line[0] == kAssertTag) {
      assertion = std::string(rest);
    }
  }
  const std::string file = absl::StrCat(dirs[std::min(index, dirs.size() - 1)], "/data.mdb");
  if (timed_out) {
    return absl::DataLossError(
        absl::StrCat(file, " is damaged: LMDB did not finish reading it within ", absl::FormatDuration(timeout)));
  }
  if (exit.signal != 0) {
    const int signal_number = exit.signal;
    return absl::DataLossError(absl::StrCat(file, " is damaged: LMDB aborted reading it (signal ", signal_number, ", ",
                                            strsignal(signal_number), ")",
                                            assertion.empty() ? "" : absl::StrCat(": ", assertion)));
  }
  if (lmdb_error != 0) {
    // An error LMDB returns gracefully: a damaged file is DataLoss, anything else (EACCES, ENOMEM) is the open's own
    // error, which the real open will report the same way.
    const absl::Status status = LmdbStatus(lmdb_error, absl::StrCat(file, ": LMDB reports"));
    if (absl::IsDataLoss(status)) {
      return absl::DataLossError(absl::StrCat(file, " is damaged: ", mdb_strerror(lmdb_error)));
    }
    return status;
  }
  return absl::InternalError(
      absl::StrCat("the probe of ", file, " ended with exit status ", exit.exit_code));
}

}  // namespace

absl::Status ProbeEnvironments(const std::vector<std::string>& dirs, const ProbeOptions& options) {
  std::vector<std::string> present;
  for (const std::string& dir : dirs) {
    struct stat st;
    if (stat(absl::StrCat(dir, "/data.mdb").c_str(), &st) == 0) present.push_back(dir);
  }
  if (present.empty()) return absl::OkStatus();
  // Everything the child needs is prepared before the fork.
  std::vector<const char*> paths;
  for (const std::string& dir : present) paths.push_back(dir.c_str());
  std::string output;
  auto exit = RunIsolated([&](int fd) { return WalkAll(paths, fd); },
                          [&](std::string_view chunk) {
                            if (output.size() < kMaxOutput) output.append(chunk);
                          },
                          absl::Now() + options.timeout);
  const bool timed_out = absl::IsDeadlineExceeded(exit.status());
  if (!exit.ok() && !timed_out) {
    return absl::UnavailableError(absl::StrCat("cannot probe LMDB files: ", exit.status().message()));
  }
  return Interpret(output, timed_out, exit.value_or(ChildExit{}), present, options.timeout);
}

}  // namespace fremen::storage
