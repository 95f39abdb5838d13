// fremend's configuration: one table of settings (ConfigFields), each with its key, its help text,
// its default, and a parser that validates it. The same table reads the config file, defines the
// command-line flags (server/daemon/command_line.h) and documents both.
//
// The config file: one `key = value` per line; blank lines and lines starting with `#` are ignored
// (no comments after a value); a value may be wrapped in double quotes; a key may appear once.
// Precedence: embedded defaults < config file < flags. FinishConfig() then checks what spans
// several settings and reads the files the settings name (tokens, TLS).
//
// Every error is InvalidArgument with a message naming the setting:
//   config: listen: "abc" is not HOST:PORT (fremend.conf line 3)
// Value types and pure functions (apart from FinishConfig's file reads); thread-safe.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"

namespace fremen::server {

// What a caller may do: read (queries, get/list) or also write (ingest, create/delete, admin).
enum class Access { kRead, kWrite };

struct TokenGrant {
  std::string token;
  Access access = Access::kRead;
  bool operator==(const TokenGrant&) const = default;
};

// One map's own update schedule (update_map_schedules): a cron expression, or "" for none (the
// map is updated on demand only).
struct MapSchedule {
  std::string map;
  std::string schedule;
  bool operator==(const MapSchedule&) const = default;
};

struct ServerConfig {
  // HOST:PORT to serve gRPC on; IPv6 hosts in brackets ("[::1]:50051"); port 0 = any free port
  // (the chosen one is logged). Default: loopback only — exposing the daemon is a decision.
  std::string listen = "127.0.0.1:50051";
  // HOST:PORT of the HTTP port (server/http/): /metrics, /healthz and /readyz, the JSON API and the
  // dashboard, with the same TLS and tokens as gRPC; port 0 = any free port; "" = no HTTP port.
  std::string http_listen = "127.0.0.1:50052";
  // Where the catalog and every map's files live; created when missing.
  std::string data_dir = "./fremen-data";
  // Root of BackupMap/RestoreMap directories; "" = <data_dir>/backups.
  std::string backup_dir;
  // LMDB shards of a new map that asks for 0; 0 = one per core. Range [0, 256].
  uint32_t shards = 0;
  // A map checkpoints once its write-ahead log holds this many MiB: larger = fewer, longer
  // checkpoints and a longer recovery. Range [1, 1048576]. Default 256.
  uint64_t checkpoint_log_mb = 256;
  // Largest message received or sent, MiB; a larger request gets RESOURCE_EXHAUSTED. Bounds the
  // memory one call can make the daemon hold. Range [1, 2047]. Default 16.
  uint32_t max_message_mb = 16;
  // HTTP/2 keepalive, tuned for robots on Wi-Fi: ping an idle client every keepalive_time and drop
  // it when no answer comes within keepalive_timeout (a robot that left the network frees its
  // streams in ~30 s), even between calls (keepalive_permit_without_calls). Clients may ping as
  // often as keepalive_min_client_interval; more often and gRPC closes their connection.
  absl::Duration keepalive_time = absl::Seconds(20);
  absl::Duration keepalive_timeout = absl::Seconds(10);
  bool keepalive_permit_without_calls = true;
  absl::Duration keepalive_min_client_interval = absl::Seconds(10);
  // On SIGTERM: how long in-flight calls may take to finish before they are cancelled.
  absl::Duration shutdown_grace = absl::Seconds(10);
  // Threads that run RPC work which waits on disk (create/delete map, backups), so that gRPC's
  // threads never block. Range [1, 64]. Default 2.
  uint32_t blocking_threads = 2;
  // TLS: PEM certificate chain and private key; both or neither. With tls_client_ca_file, clients
  // must present a certificate signed by that CA (mutual TLS).
  std::string tls_cert_file;
  std::string tls_key_file;
  std::string tls_client_ca_file;
  // Bearer tokens, as ROLE:TOKEN with ROLE read or write, from `tokens` (inline, separated by
  // spaces or commas) and `tokens_file` (one per line, # comments). None = no authentication.
  std::vector<TokenGrant> tokens;
  std::string tokens_file;
  // When the update job runs (cron: minute hour day-of-month month day-of-week), in
  // update_time_zone ("local", "UTC" or an IANA name such as "Europe/Prague"). "" = never (for
  // deployments that trigger it from an external cron). Default: daily at midnight local time.
  std::string update_schedule = "0 0 * * *";
  std::string update_time_zone = "local";
  // Per-map overrides of update_schedule (same time zone), as "MAP=CRON; MAP=never; ...": those maps
  // follow their own schedule, or none. Default: none.
  std::vector<MapSchedule> update_map_schedules;
  // The background scrub (server/jobs/scrubber.h): every scrub_interval, every served map's files are
  // read and verified as CheckMap does, at the lowest CPU and I/O priority; the results are in
  // GetServerStatus. 0 = never (the default: a scrub of a large map reads all of it, and holds
  // back that map's checkpoints while it runs). Range [0, 366d]; e.g. "168h" for weekly.
  absl::Duration scrub_interval = absl::ZeroDuration();
  // The longest the scrub of one map may take: a shard still being read then is reported "not
  // verified" in its result and the scrub goes on with the next map. Range [1s, 366d]; default 1h.
  absl::Duration scrub_map_timeout = absl::Hours(1);
  // trace, debug, info, warn, error, critical or off.
  std::string log_level = "info";
  // Tests only: an update's publication waits before its first slice until a batch has been
  // applied and acknowledged, so that an end-to-end test sees, in order rather than by timing,
  // that ingest and queries are served while a job publishes. Default: false.
  bool test_publication_waits_for_a_batch = false;

  // Filled by FinishConfig from the files named above.
  std::string tls_cert_pem;
  std::string tls_key_pem;
  std::string tls_client_ca_pem;
};

// One setting of the table.
struct ConfigField {
  absl::string_view key;   // as in the file; the flag is --key with '_' as '-'
  absl::string_view help;  // one line
  absl::string_view value_name;  // what the value is, for --help: "HOST:PORT", "DURATION", ...
  // Parses and checks `value` into the config; the error says what is wrong with the value
  // (without the "config: key: " prefix, which the callers add).
  std::function<absl::Status(absl::string_view value, ServerConfig& config)> set;
  // The setting's value as the file would spell it.
  std::function<std::string(const ServerConfig& config)> get;
};

const std::vector<ConfigField>& ConfigFields();

// Sets one setting; `where` tells the error where the value came from ("fremend.conf line 3",
// "--listen"). InvalidArgument for an unknown key or a bad value.
absl::Status SetConfigValue(absl::string_view key, absl::string_view value, absl::string_view where,
                            ServerConfig& config);

// Applies the text of a config file; `source` names it in errors.
absl::Status ApplyConfigText(absl::string_view text, absl::string_view source, ServerConfig& config);
// Reads and applies a config file.
absl::Status ApplyConfigFile(const std::string& path, ServerConfig& config);

// Cross-setting checks and the files settings name: reads tokens_file into tokens and the TLS PEM
// files. Call once, after the file and the flags.
absl::Status FinishConfig(ServerConfig& config);

}  // namespace fremen::server
