#include "server/http/http_status.h"

#include <google/protobuf/util/json_util.h>

#include "fremen/v1/rpc_status.pb.h"

namespace fremen::server {

int HttpStatusOf(absl::StatusCode code) {
  switch (code) {
    case absl::StatusCode::kOk:
      return 200;
    case absl::StatusCode::kInvalidArgument:
    case absl::StatusCode::kFailedPrecondition:
    case absl::StatusCode::kOutOfRange:
      return 400;
    case absl::StatusCode::kUnauthenticated:
      return 401;
    case absl::StatusCode::kPermissionDenied:
      return 403;
    case absl::StatusCode::kNotFound:
      return 404;
    case absl::StatusCode::kAlreadyExists:
    case absl::StatusCode::kAborted:
      return 409;
    case absl::StatusCode::kResourceExhausted:
      return 429;
    case absl::StatusCode::kCancelled:
      return 499;  // nginx's "client closed request", as grpc-gateway
    case absl::StatusCode::kUnimplemented:
      return 501;
    case absl::StatusCode::kUnavailable:
      return 503;
    case absl::StatusCode::kDeadlineExceeded:
      return 504;
    default:
      return 500;
  }
}

std::string StatusBody(const absl::Status& status) {
  // google.rpc.Status's shape (proto/fremen/v1/rpc_status.proto), printed by protobuf's JSON
  // mapping: no hand-written JSON escaping.
  v1::RpcStatus body;
  body.set_code(static_cast<int>(status.code()));
  body.set_message(std::string(status.message()));
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;  // "details": [] too, as google.rpc.Status has it
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(body, &json, options);
  return json + "\n";
}

void SetErrorResponse(const absl::Status& status, httplib::Response& response) {
  response.status = HttpStatusOf(status.code());
  if (response.status == 401) response.set_header("WWW-Authenticate", "Bearer");
  response.set_content(StatusBody(status), "application/json");
}

}  // namespace fremen::server
