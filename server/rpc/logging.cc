#include "server/rpc/logging.h"

#include <grpc/support/log.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include <string>

#include "server/rpc/access_log.h"

namespace fremen::server {

namespace {

void LogGrpcMessage(gpr_log_func_args* args) {
  static const std::shared_ptr<spdlog::logger> logger = spdlog::get(kGrpcLogger);
  const spdlog::level::level_enum level = args->severity == GPR_LOG_SEVERITY_ERROR  ? spdlog::level::err
                                          : args->severity == GPR_LOG_SEVERITY_INFO ? spdlog::level::info
                                                                                    : spdlog::level::debug;
  logger->log(level, "{} ({}:{})", args->message, args->file, args->line);
}

}  // namespace

void SetUpLogging(absl::string_view level) {
  auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  sink->set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%-5l%$ [%n] %v");
  for (const char* name : {kDaemonLogger, kAccessLogger, kStoreLogger, kGrpcLogger}) {
    auto logger = std::make_shared<spdlog::logger>(name, sink);
    logger->set_level(spdlog::level::from_str(std::string(level)));
    spdlog::register_logger(logger);
  }
  spdlog::set_default_logger(spdlog::get(kDaemonLogger));
  gpr_set_log_function(LogGrpcMessage);
}

std::shared_ptr<spdlog::logger> NamedLogger(const char* name) {
  auto logger = spdlog::get(name);
  return logger != nullptr ? logger : spdlog::default_logger();
}

}  // namespace fremen::server
