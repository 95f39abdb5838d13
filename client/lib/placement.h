// Which daemon of a fleet holds a map: the consistent hash ("ketama") that nginx computes for
// `upstream { hash $http_x_fremen_map consistent; server A; server B; ... }`, reimplemented so
// that fremenctl, the tests and any tool name the same owner as the proxy without asking it.
//
// Why a consistent hash rather than a placement table (docs/fleet.md, "Placement"):
// - Adding a daemon moves only the maps whose owner becomes the new daemon, about 1/N of them,
//   and removing one moves only its own maps; a modulo hash would move nearly all of them.
// - Nothing is shared: the proxy's configuration (its list of servers) is the whole placement.
//   A table would have to be generated, distributed to every proxy replica and kept in step with
//   the maps that clients create at any time; the ring needs no update when a map is created.
// - The cost: placement is not chosen, so a large map cannot be put on an emptier daemon by
//   hand, and balance is statistical (160 points per daemon: within about ±10% of the mean).
//
// The ring, as nginx builds it (ngx_http_upstream_hash_module.c, nginx 1.22 to 1.27): each server
// string (exactly as written in the `server` directive, e.g. "fremend-0.fremend:50051") is split
// at its last ':' when what follows is all digits into HOST and PORT ("unix:PATH": HOST = PATH, no
// PORT; no port: HOST alone). Its 160 points (per unit of weight; all weights are 1 here) are
// crc32(HOST "\0" PORT PREV), where PREV is the previous point's hash as 4 little-endian bytes,
// 0 for the first. A key's hash is crc32(KEY); its owner is the server of the first point ≥ it,
// wrapping to the first point. nginx sorts points with an unstable qsort; equal hashes of two
// servers (odds ~1e-5 for 3 daemons) would make its choice there unspecified, we take the earlier
// server in the list.
//
// What nginx does beyond the ring, which this does not model: an empty key goes round-robin (map
// names are never empty); a server marked failed is skipped for the next point's — which is why
// deploy/nginx/fremen.conf turns failure accounting off (max_fails=0, no next upstream), so that a
// stopped daemon's maps answer UNAVAILABLE rather than NOT_FOUND from a daemon that does not hold
// them. A server name that resolves to several addresses shares one set of points among them:
// name daemons by names that resolve to one address each (a StatefulSet's pod names do).
//
// Thread-safety: immutable after Create; thread-safe.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace fremen::client {

class Placement {
 public:
  // Points per daemon, as nginx (and Cache::Memcached::Fast) give each unit of weight.
  static constexpr int kPointsPerDaemon = 160;

  // The ring of `daemons`, nginx server strings ("HOST:PORT"). INVALID_ARGUMENT for an empty list,
  // an empty name or a name listed twice. Their order does not matter.
  static absl::StatusOr<Placement> Create(std::vector<std::string> daemons);
  // The same from a comma-separated list ("a:50051,b:50051"; blanks around names ignored).
  static absl::StatusOr<Placement> Parse(absl::string_view comma_separated);

  const std::vector<std::string>& daemons() const { return daemons_; }

  // The daemon that holds `map` (an index into daemons()). REQUIRES: map is not empty.
  size_t OwnerIndex(absl::string_view map) const;
  const std::string& Owner(absl::string_view map) const { return daemons_[OwnerIndex(map)]; }

  // crc32 (zlib's: the IEEE polynomial, reflected, as nginx's ngx_crc32_long) of `bytes`.
  static uint32_t Crc32(absl::string_view bytes);

 private:
  struct Point {
    uint32_t hash;
    uint32_t daemon;
  };
  Placement(std::vector<std::string> daemons, std::vector<Point> ring)
      : daemons_(std::move(daemons)), ring_(std::move(ring)) {}

  std::vector<std::string> daemons_;
  std::vector<Point> ring_;  // sorted by hash, then by daemon index
};

}  // namespace fremen::client
