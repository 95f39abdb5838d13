#include "server/daemon/config.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/time.h"
#include "server/jobs/cron.h"

namespace fremen::server {

namespace {

absl::Status Invalid(absl::string_view message) { return absl::InvalidArgumentError(message); }

std::string Quoted(absl::string_view value) { return absl::StrCat("\"", value, "\""); }

// --- value parsers: each says what is wrong with the value ---

absl::Status CheckHostPort(absl::string_view value) {
  const size_t colon = value.rfind(':');
  const absl::string_view host = colon == absl::string_view::npos ? value : value.substr(0, colon);
  const absl::string_view port = colon == absl::string_view::npos ? "" : value.substr(colon + 1);
  const bool bracketed = absl::StartsWith(host, "[") && absl::EndsWith(host, "]") && host.size() > 2;
  uint32_t port_number = 0;
  if (host.empty() || (!bracketed && absl::StrContains(host, ':')) || port.empty() ||
      !absl::SimpleAtoi(port, &port_number) || !absl::ascii_isdigit(port[0])) {
    return Invalid(absl::StrCat(Quoted(value), " is not HOST:PORT (e.g. 127.0.0.1:50051, [::1]:50051)"));
  }
  if (port_number > 65535) return Invalid(absl::StrCat(Quoted(value), ": port must be in [0, 65535]"));
  return absl::OkStatus();
}

absl::StatusOr<bool> ParseBool(absl::string_view value) {
  const std::string lower = absl::AsciiStrToLower(value);
  if (lower == "true" || lower == "yes" || lower == "on" || lower == "1") return true;
  if (lower == "false" || lower == "no" || lower == "off" || lower == "0") return false;
  return Invalid(absl::StrCat(Quoted(value), " is not true or false"));
}

absl::StatusOr<TokenGrant> ParseTokenGrant(absl::string_view text) {
  const size_t colon = text.find(':');
  if (colon == absl::string_view::npos) {
    return Invalid(absl::StrCat("\"", text.substr(0, 5), "...\" is not ROLE:TOKEN (ROLE read or write)"));
  }
  TokenGrant grant;
  const absl::string_view role = text.substr(0, colon);
  if (role == "read") {
    grant.access = Access::kRead;
  } else if (role == "write") {
    grant.access = Access::kWrite;
  } else {
    return Invalid(absl::StrCat("role ", Quoted(role), " is neither read nor write"));
  }
  grant.token = std::string(text.substr(colon + 1));
  // RFC 6750 b64token: what may follow "Bearer " in the authorization header.
  const bool valid = !grant.token.empty() && std::all_of(grant.token.begin(), grant.token.end(), [](char c) {
    return absl::ascii_isalnum(c) || absl::StrContains("-._~+/=", c);
  });
  if (!valid) {
    return Invalid(absl::StrCat("a ", role, " token must be 1 or more of A-Z a-z 0-9 - . _ ~ + / ="));
  }
  return grant;
}

absl::StatusOr<std::vector<TokenGrant>> ParseTokenList(absl::string_view text) {
  std::vector<TokenGrant> grants;
  for (absl::string_view item : absl::StrSplit(text, absl::ByAnyChar(" ,\t"), absl::SkipEmpty())) {
    auto grant = ParseTokenGrant(item);
    if (!grant.ok()) return grant.status();
    grants.push_back(*std::move(grant));
  }
  return grants;
}

constexpr const char* kLogLevels[] = {"trace", "debug", "info", "warn", "error", "critical", "off"};

// --- field makers: one per kind of setting, so the table below is one line of intent per field ---

ConfigField StringField(absl::string_view key, absl::string_view value_name, absl::string_view help,
                        std::string ServerConfig::*member, std::function<absl::Status(absl::string_view)> check = nullptr) {
  return {key, help, value_name,
          [member, check](absl::string_view value, ServerConfig& config) -> absl::Status {
            if (check) {
              if (absl::Status s = check(value); !s.ok()) return s;
            }
            config.*member = std::string(value);
            return absl::OkStatus();
          },
          [member](const ServerConfig& config) { return config.*member; }};
}

template <typename T>
ConfigField UintField(absl::string_view key, absl::string_view help, T ServerConfig::*member, T min, T max) {
  return {key, help, "N",
          [member, min, max](absl::string_view value, ServerConfig& config) -> absl::Status {
            uint64_t parsed = 0;
            if (!absl::SimpleAtoi(value, &parsed) || parsed < min || parsed > max) {
              return Invalid(absl::StrCat(Quoted(value), " is not a whole number in [", min, ", ", max, "]"));
            }
            config.*member = static_cast<T>(parsed);
            return absl::OkStatus();
          },
          [member](const ServerConfig& config) { return absl::StrCat(config.*member); }};
}

ConfigField DurationField(absl::string_view key, absl::string_view help, absl::Duration ServerConfig::*member,
                          absl::Duration min, absl::Duration max) {
  return {key, help, "DURATION",
          [member, min, max](absl::string_view value, ServerConfig& config) -> absl::Status {
            absl::Duration parsed;
            if (!absl::ParseDuration(value, &parsed)) {
              return Invalid(absl::StrCat(Quoted(value), " is not a duration (e.g. 20s, 1m30s, 500ms)"));
            }
            if (parsed < min || parsed > max) {
              return Invalid(absl::StrCat(Quoted(value), " is outside [", absl::FormatDuration(min), ", ",
                                          absl::FormatDuration(max), "]"));
            }
            config.*member = parsed;
            return absl::OkStatus();
          },
          [member](const ServerConfig& config) { return absl::FormatDuration(config.*member); }};
}

ConfigField BoolField(absl::string_view key, absl::string_view help, bool ServerConfig::*member) {
  return {key, help, "BOOL",
          [member](absl::string_view value, ServerConfig& config) -> absl::Status {
            auto parsed = ParseBool(value);
            if (!parsed.ok()) return parsed.status();
            config.*member = *parsed;
            return absl::OkStatus();
          },
          [member](const ServerConfig& config) { return std::string(config.*member ? "true" : "false"); }};
}

// update_map_schedules: "MAP=CRON; MAP=never; ..." (blank entries ignored). Each map once; a
// schedule that does not parse is named by its map.
absl::Status SetMapSchedules(absl::string_view value, ServerConfig& config) {
  std::vector<MapSchedule> schedules;
  for (absl::string_view entry : absl::StrSplit(value, ';')) {
    entry = absl::StripAsciiWhitespace(entry);
    if (entry.empty()) continue;
    const size_t equals = entry.find('=');
    if (equals == absl::string_view::npos) {
      return Invalid(absl::StrCat(Quoted(entry), " is not MAP=CRON or MAP=never"));
    }
    MapSchedule schedule{std::string(absl::StripAsciiWhitespace(entry.substr(0, equals))),
                         std::string(absl::StripAsciiWhitespace(entry.substr(equals + 1)))};
    if (schedule.map.empty()) return Invalid(absl::StrCat(Quoted(entry), " names no map before '='"));
    if (schedule.schedule == "never") schedule.schedule.clear();
    if (!schedule.schedule.empty()) {
      if (auto parsed = CronSchedule::Parse(schedule.schedule); !parsed.ok()) {
        return Invalid(absl::StrCat("map ", Quoted(schedule.map), ": ", parsed.status().message()));
      }
    }
    for (const MapSchedule& earlier : schedules) {
      if (earlier.map == schedule.map) {
        return Invalid(absl::StrCat("map ", Quoted(schedule.map), " is given twice; give each map one schedule"));
      }
    }
    schedules.push_back(std::move(schedule));
  }
  config.update_map_schedules = std::move(schedules);
  return absl::OkStatus();
}

std::string MapSchedulesValue(const ServerConfig& config) {
  std::vector<std::string> entries;
  for (const MapSchedule& s : config.update_map_schedules) {
    entries.push_back(absl::StrCat(s.map, "=", s.schedule.empty() ? "never" : s.schedule));
  }
  return absl::StrJoin(entries, "; ");
}

std::vector<ConfigField> MakeConfigFields() {
  using C = ServerConfig;
  const auto non_empty = [](absl::string_view value) {
    return value.empty() ? Invalid("must not be empty") : absl::OkStatus();
  };
  return {
      StringField("listen", "HOST:PORT", "HOST:PORT to serve gRPC on (port 0: any free port)", &C::listen, CheckHostPort),
      StringField("http_listen", "HOST:PORT",
                  "HOST:PORT of the HTTP port: metrics, health, JSON API, dashboard (empty: none)", &C::http_listen,
                  [](absl::string_view value) { return value.empty() ? absl::OkStatus() : CheckHostPort(value); }),
      StringField("data_dir", "DIR", "directory of the catalog and the maps' files (created when missing)", &C::data_dir,
                  non_empty),
      StringField("backup_dir", "DIR", "root of BackupMap/RestoreMap directories (empty: DATA_DIR/backups)",
                  &C::backup_dir),
      UintField<uint32_t>("shards", "LMDB shards of a new map that asks for 0 (0: one per core)", &C::shards, 0, 256),
      UintField<uint64_t>("checkpoint_log_mb", "a map checkpoints once its log holds this many MiB",
                          &C::checkpoint_log_mb, 1, 1 << 20),
      UintField<uint32_t>("max_message_mb", "largest gRPC message received or sent, MiB", &C::max_message_mb, 1,
                          2047),
      DurationField("keepalive_time", "ping an idle client this often", &C::keepalive_time, absl::Seconds(1),
                    absl::Hours(2)),
      DurationField("keepalive_timeout", "drop a client whose ping answer takes longer", &C::keepalive_timeout,
                    absl::Seconds(1), absl::Minutes(10)),
      BoolField("keepalive_permit_without_calls", "keep pinging between calls (robots idle between scans)",
                &C::keepalive_permit_without_calls),
      DurationField("keepalive_min_client_interval", "shortest ping interval allowed to clients",
                    &C::keepalive_min_client_interval, absl::Seconds(1), absl::Hours(1)),
      DurationField("shutdown_grace", "on SIGTERM, time in-flight calls get before they are cancelled",
                    &C::shutdown_grace, absl::ZeroDuration(), absl::Minutes(10)),
      UintField<uint32_t>("blocking_threads", "threads for RPC work that waits on disk", &C::blocking_threads, 1, 64),
      StringField("tls_cert_file", "FILE", "PEM certificate chain; with tls_key_file, serve TLS", &C::tls_cert_file),
      StringField("tls_key_file", "FILE", "PEM private key of tls_cert_file", &C::tls_key_file),
      StringField("tls_client_ca_file", "FILE", "PEM CA; clients must present a certificate it signed",
                  &C::tls_client_ca_file),
      {"tokens", "bearer tokens as ROLE:TOKEN (ROLE read or write), space-separated; none: no auth", "TOKENS",
       [](absl::string_view value, C& config) -> absl::Status {
         auto grants = ParseTokenList(value);
         if (!grants.ok()) return grants.status();
         config.tokens = *std::move(grants);
         return absl::OkStatus();
       },
       // Never prints a secret: only how many there are.
       [](const C& config) { return config.tokens.empty() ? "" : absl::StrCat("(", config.tokens.size(), " tokens)"); }},
      StringField("tokens_file", "FILE", "file of ROLE:TOKEN lines (# comments), added to tokens", &C::tokens_file),
      StringField("update_schedule", "CRON", "cron schedule of the update job (empty: never)", &C::update_schedule,
                  [](absl::string_view value) {
                    return value.empty() ? absl::OkStatus() : CronSchedule::Parse(value).status();
                  }),
      StringField("update_time_zone", "ZONE", "time zone of update_schedule: local, UTC or an IANA name",
                  &C::update_time_zone,
                  [](absl::string_view value) -> absl::Status {
                    absl::TimeZone zone;
                    if (value == "local" || absl::LoadTimeZone(std::string(value), &zone)) return absl::OkStatus();
                    return Invalid(absl::StrCat("unknown time zone ", Quoted(value)));
                  }),
      {"update_map_schedules", "per-map update schedules overriding update_schedule: MAP=CRON; MAP=never",
       "SCHEDULES", SetMapSchedules, MapSchedulesValue},
      DurationField("scrub_interval", "verify every map's files in the background this often (0: never)",
                    &C::scrub_interval, absl::ZeroDuration(), absl::Hours(24 * 366)),
      DurationField("scrub_map_timeout", "the longest the background scrub of one map may take",
                    &C::scrub_map_timeout, absl::Seconds(1), absl::Hours(24 * 366)),
      StringField("log_level", "LEVEL", "trace, debug, info, warn, error, critical or off", &C::log_level,
                  [](absl::string_view value) -> absl::Status {
                    for (const char* level : kLogLevels) {
                      if (value == level) return absl::OkStatus();
                    }
                    return Invalid(absl::StrCat(Quoted(value), " is not one of ", absl::StrJoin(kLogLevels, ", ")));
                  }),
      BoolField("test_publication_waits_for_a_batch",
                "tests only: an update's publication waits for a batch before its first slice",
                &C::test_publication_waits_for_a_batch),
  };
}

absl::StatusOr<std::string> ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Invalid(absl::StrCat("cannot read ", Quoted(path), ": ", std::strerror(errno)));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// "config: key: message" for a setting's file.
absl::StatusOr<std::string> ReadSettingFile(absl::string_view key, const std::string& path) {
  auto text = ReadFile(path);
  if (!text.ok()) return Invalid(absl::StrCat("config: ", key, ": ", text.status().message()));
  return text;
}

absl::Status ReadTokensFile(ServerConfig& config) {
  auto text = ReadSettingFile("tokens_file", config.tokens_file);
  if (!text.ok()) return text.status();
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(*text, '\n')) {
    ++line_number;
    line = absl::StripAsciiWhitespace(line);
    if (line.empty() || line[0] == '#') continue;
    auto grant = ParseTokenGrant(line);
    if (!grant.ok()) {
      return Invalid(absl::StrCat("config: tokens_file: ", config.tokens_file, " line ", line_number, ": ",
                                  grant.status().message()));
    }
    config.tokens.push_back(*std::move(grant));
  }
  return absl::OkStatus();
}

}  // namespace

const std::vector<ConfigField>& ConfigFields() {
  static const std::vector<ConfigField> fields = MakeConfigFields();
  return fields;
}

absl::Status SetConfigValue(absl::string_view key, absl::string_view value, absl::string_view where,
                            ServerConfig& config) {
  for (const ConfigField& field : ConfigFields()) {
    if (field.key != key) continue;
    if (absl::Status s = field.set(value, config); !s.ok()) {
      return Invalid(absl::StrCat("config: ", key, ": ", s.message(), " (", where, ")"));
    }
    return absl::OkStatus();
  }
  return Invalid(absl::StrCat("config: unknown setting ", Quoted(key), " (", where, ")"));
}

absl::Status ApplyConfigText(absl::string_view text, absl::string_view source, ServerConfig& config) {
  absl::flat_hash_map<std::string, int> first_line;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    line = absl::StripAsciiWhitespace(line);
    if (line.empty() || line[0] == '#') continue;
    const std::string where = absl::StrCat(source, " line ", line_number);
    const size_t equals = line.find('=');
    if (equals == absl::string_view::npos) {
      return Invalid(absl::StrCat("config: expected key = value, got ", Quoted(line), " (", where, ")"));
    }
    const std::string key(absl::StripAsciiWhitespace(line.substr(0, equals)));
    absl::string_view value = absl::StripAsciiWhitespace(line.substr(equals + 1));
    if (value.size() >= 2 && value.front() == '"' && value.back() == '"') value = value.substr(1, value.size() - 2);
    if (auto [it, inserted] = first_line.emplace(key, line_number); !inserted) {
      return Invalid(absl::StrCat("config: ", key, ": set twice, on lines ", it->second, " and ", line_number, " (",
                                  source, ")"));
    }
    if (absl::Status s = SetConfigValue(key, value, where, config); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status ApplyConfigFile(const std::string& path, ServerConfig& config) {
  auto text = ReadFile(path);
  if (!text.ok()) return Invalid(absl::StrCat("config: ", text.status().message()));
  return ApplyConfigText(*text, path, config);
}

absl::Status FinishConfig(ServerConfig& config) {
  if (config.tls_cert_file.empty() != config.tls_key_file.empty()) {
    return Invalid(config.tls_cert_file.empty() ? "config: tls_cert_file: required with tls_key_file"
                                                : "config: tls_key_file: required with tls_cert_file");
  }
  if (!config.tls_client_ca_file.empty() && config.tls_cert_file.empty()) {
    return Invalid("config: tls_client_ca_file: needs tls_cert_file and tls_key_file (mutual TLS is TLS first)");
  }
  const std::pair<absl::string_view, std::pair<const std::string*, std::string*>> pem_files[] = {
      {"tls_cert_file", {&config.tls_cert_file, &config.tls_cert_pem}},
      {"tls_key_file", {&config.tls_key_file, &config.tls_key_pem}},
      {"tls_client_ca_file", {&config.tls_client_ca_file, &config.tls_client_ca_pem}},
  };
  for (const auto& [key, paths] : pem_files) {
    if (paths.first->empty()) continue;
    auto pem = ReadSettingFile(key, *paths.first);
    if (!pem.ok()) return pem.status();
    *paths.second = *std::move(pem);
  }
  if (!config.tokens_file.empty()) {
    if (absl::Status s = ReadTokensFile(config); !s.ok()) return s;
  }
  absl::flat_hash_map<absl::string_view, Access> seen;
  for (const TokenGrant& grant : config.tokens) {
    if (!seen.emplace(grant.token, grant.access).second) {
      return Invalid("config: tokens: a token is given twice (in tokens or tokens_file); each token has one role");
    }
  }
  return absl::OkStatus();
}

}  // namespace fremen::server
