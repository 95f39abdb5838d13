#include "client/lib/placement.h"

#include <zlib.h>

#include <algorithm>
#include <set>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace fremen::client {

namespace {

// HOST and PORT of a server string, split as nginx splits it before hashing.
struct HostPort {
  absl::string_view host, port;
};

HostPort Split(absl::string_view server) {
  if (server.size() >= 5 && absl::EqualsIgnoreCase(server.substr(0, 5), "unix:")) return {server.substr(5), ""};
  for (size_t j = 0; j < server.size(); ++j) {
    const char c = server[server.size() - j - 1];
    if (c == ':') return {server.substr(0, server.size() - j - 1), server.substr(server.size() - j)};
    if (!absl::ascii_isdigit(static_cast<unsigned char>(c))) break;
  }
  return {server, ""};
}

uLong Update(uLong crc, absl::string_view bytes) {
  return crc32(crc, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size()));
}

}  // namespace

uint32_t Placement::Crc32(absl::string_view bytes) {
  return static_cast<uint32_t>(Update(crc32(0, nullptr, 0), bytes));
}

absl::StatusOr<Placement> Placement::Create(std::vector<std::string> daemons) {
  if (daemons.empty()) return absl::InvalidArgumentError("a fleet needs at least one daemon");
  std::set<absl::string_view> seen;
  for (const std::string& daemon : daemons) {
    if (daemon.empty()) return absl::InvalidArgumentError("a daemon's name is empty");
    if (!seen.insert(daemon).second) {
      return absl::InvalidArgumentError(absl::StrCat("daemon \"", daemon, "\" is listed twice"));
    }
  }
  std::vector<Point> ring;
  ring.reserve(daemons.size() * kPointsPerDaemon);
  for (uint32_t d = 0; d < daemons.size(); ++d) {
    const HostPort hp = Split(daemons[d]);
    // zlib's crc32 carries its state between calls, pre- and post-conditioned, so that
    // crc32(crc32(0, A), B) == crc32(0, A B): nginx's running crc of HOST "\0" PORT, then PREV.
    uLong base = Update(crc32(0, nullptr, 0), hp.host);
    base = Update(base, absl::string_view("\0", 1));
    base = Update(base, hp.port);
    uint32_t prev = 0;
    for (int j = 0; j < kPointsPerDaemon; ++j) {
      const unsigned char le[4] = {static_cast<unsigned char>(prev), static_cast<unsigned char>(prev >> 8),
                                   static_cast<unsigned char>(prev >> 16), static_cast<unsigned char>(prev >> 24)};
      prev = static_cast<uint32_t>(crc32(base, le, 4));
      ring.push_back({prev, d});
    }
  }
  std::sort(ring.begin(), ring.end(),
            [](const Point& a, const Point& b) { return a.hash != b.hash ? a.hash < b.hash : a.daemon < b.daemon; });
  return Placement(std::move(daemons), std::move(ring));
}

absl::StatusOr<Placement> Placement::Parse(absl::string_view comma_separated) {
  std::vector<std::string> daemons;
  for (absl::string_view name : absl::StrSplit(comma_separated, ',')) {
    daemons.emplace_back(absl::StripAsciiWhitespace(name));
  }
  return Create(std::move(daemons));
}

size_t Placement::OwnerIndex(absl::string_view map) const {
  const uint32_t hash = Crc32(map);
  // The first point ≥ the key's hash, past the last point the first (nginx: index % points).
  auto it = std::lower_bound(ring_.begin(), ring_.end(), hash, [](const Point& p, uint32_t h) { return p.hash < h; });
  if (it == ring_.end()) it = ring_.begin();
  return it->daemon;
}

}  // namespace fremen::client
