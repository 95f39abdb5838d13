#include "server/rpc/access_log.h"

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "server/rpc/status_convert.h"

namespace fremen::server {

void CallRecord::Finish(const grpc::Status& status, absl::string_view details) const {
  const absl::Duration took = absl::Now() - start_;
  if (observer_ != nullptr) observer_->CallFinished(method_, status.error_code(), took);
  static const std::shared_ptr<spdlog::logger> logger = spdlog::get(kAccessLogger);
  if (logger == nullptr) return;  // logging not set up (unit tests)
  const double ms = absl::ToDoubleMilliseconds(took);
  const fmt::string_view method(method_.data(), method_.size());
  const std::string extra = details.empty() ? "" : absl::StrCat(" ", details);
  if (status.ok()) {
    logger->info("{} {} OK {:.2f}ms{}", method, peer_, ms, extra);
  } else {
    logger->info("{} {} {} {:.2f}ms{} {}", method, peer_, StatusCodeName(status.error_code()), ms, extra,
                 status.error_message());
  }
}

}  // namespace fremen::server
