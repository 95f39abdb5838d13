#include "server/gateway/json_api.h"

#include <google/protobuf/util/json_util.h>

#include <map>
#include <set>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_replace.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "server/gateway/grpc_forward.h"
#include "server/gateway/region_png.h"
#include "server/gateway/request_fields.h"
#include "server/http/http_status.h"

namespace fremen::server {

namespace {

using MapStub = v1::MapService::Stub;
using QueryStub = v1::QueryService::Stub;
using IngestStub = v1::IngestService::Stub;
using AdminStub = v1::AdminService::Stub;
using Handler = JsonRoute::Handler;

// Where a route's request message comes from, besides the path's variables.
enum class Source { kQuery, kBody };

absl::Status FromGrpc(const grpc::Status& status) {
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()), status.error_message());
}

// The parameters of the URL's query string only: httplib's `params` also holds a form-encoded
// body's fields (what `curl -d` sends by default), which here is JSON, not parameters.
std::multimap<std::string, std::string> QueryParams(const httplib::Request& http) {
  httplib::Params params;
  if (const size_t question = http.target.find('?'); question != std::string::npos) {
    httplib::detail::parse_query_text(http.target.substr(question + 1), params);
  }
  return params;
}

// The request message of `http` for a route of `source`.
absl::Status ParseRequest(const httplib::Request& http, Source source, const PathVariables& variables,
                          google::protobuf::Message& request) {
  if (source == Source::kBody && !http.body.empty()) {
    const auto parsed = google::protobuf::util::JsonStringToMessage(http.body, &request);
    if (!parsed.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("request body: ", std::string(parsed.message())));
    }
  }
  if (absl::Status s = SetFieldsFromQuery(QueryParams(http), request); !s.ok()) return s;
  for (const auto& [name, value] : variables) {
    if (absl::Status s = SetField(name, value, request); !s.ok()) {
      // "query parameter writer_id: not an integer: x" → "path variable writer_id: ...".
      return absl::InvalidArgumentError(absl::StrReplaceAll(s.message(), {{"query parameter ", "path variable "}}));
    }
  }
  return absl::OkStatus();
}

void SetJsonResponse(const google::protobuf::Message& message, httplib::Response& response) {
  google::protobuf::util::JsonPrintOptions options;
  options.always_print_primitive_fields = true;  // a client sees `done: false`, not a missing field
  std::string json;
  const auto printed = google::protobuf::util::MessageToJsonString(message, &json, options);
  if (!printed.ok()) {
    SetErrorResponse(absl::InternalError(absl::StrCat("answer not printable as JSON: ", std::string(printed.message()))),
                     response);
    return;
  }
  response.status = 200;
  response.set_content(json + "\n", "application/json");
}

// The route that calls `forward` with the request parsed from `source` and answers its response as JSON.
template <typename Request, typename Response>
Handler Forward(Forwarder<Request, Response> forward, Source source) {
  return [forward = std::move(forward), source](const std::shared_ptr<grpc::Channel>& channel,
                                                const httplib::Request& http, const PathVariables& variables,
                                                httplib::Response& response) {
    Request request;
    if (absl::Status s = ParseRequest(http, source, variables, request); !s.ok()) {
      SetErrorResponse(s, response);
      return;
    }
    Response answer;
    auto context = ForwardedContext(http);
    if (const grpc::Status status = forward(channel, *context, request, answer); !status.ok()) {
      SetErrorResponse(FromGrpc(status), response);
      return;
    }
    SetJsonResponse(answer, response);
  };
}

// GET /v1/maps/{map}/region.png (region_png.h).
void RegionPngRoute(const std::shared_ptr<grpc::Channel>& channel, const httplib::Request& http,
                    const PathVariables& variables, httplib::Response& response) {
  auto request = RegionPngRequest(QueryParams(http));
  if (!request.ok()) return SetErrorResponse(request.status(), response);
  for (const auto& [name, value] : variables) (void)SetField(name, value, *request);  // {map}: a string
  v1::PredictRegionResponse region;
  auto context = ForwardedContext(http);
  if (const grpc::Status status = WholeRegion(channel, *context, *request, region); !status.ok()) {
    return SetErrorResponse(FromGrpc(status), response);
  }
  auto png = RegionPng(*request, region);
  if (!png.ok()) return SetErrorResponse(png.status(), response);
  response.status = 200;
  response.set_content(*std::move(png), "image/png");
}

void Dispatch(const ChannelSource& channel_source, const httplib::Request& http, httplib::Response& response) {
  const std::string raw_path = http.target.substr(0, http.target.find('?'));
  std::set<std::string> allowed;
  for (const JsonRoute& route : JsonApiRoutes()) {
    std::optional<PathVariables> variables = route.pattern.Match(raw_path);
    if (!variables) continue;
    if (route.method != http.method) {
      allowed.insert(route.method);
      continue;
    }
    const std::shared_ptr<grpc::Channel> channel = channel_source();
    if (channel == nullptr) {
      return SetErrorResponse(absl::UnavailableError("fremend's gRPC services are not up yet; retry"), response);
    }
    return route.handler(channel, http, *variables, response);
  }
  if (allowed.empty()) {
    return SetErrorResponse(
        absl::NotFoundError(absl::StrCat("no route ", http.path, " in fremend's JSON API (docs/http.md lists them)")),
        response);
  }
  const std::string methods = absl::StrJoin(allowed, ", ");
  SetErrorResponse(absl::UnimplementedError(absl::StrCat(http.method, " is not a method of ", http.path,
                                                         "; it allows ", methods)),
                   response);
  response.status = 405;
  response.set_header("Allow", methods);
}

}  // namespace

const std::vector<JsonRoute>& JsonApiRoutes() {
  static const auto* const routes = new std::vector<JsonRoute>{
      {"GET", RoutePattern("/v1/maps"), Forward(Unary(&MapStub::ListMaps), Source::kQuery)},
      {"POST", RoutePattern("/v1/maps"), Forward(Unary(&MapStub::CreateMap), Source::kBody)},
      {"GET", RoutePattern("/v1/maps/{map}"), Forward(Unary(&MapStub::GetMap), Source::kQuery)},
      {"DELETE", RoutePattern("/v1/maps/{map}"), Forward(Unary(&MapStub::DeleteMap), Source::kQuery)},
      {"GET", RoutePattern("/v1/maps/{map}/stats"), Forward(Unary(&QueryStub::GetMapStats), Source::kQuery)},
      {"GET", RoutePattern("/v1/maps/{map}/states"), Forward(Unary(&QueryStub::ListStates), Source::kQuery)},
      {"POST", RoutePattern("/v1/maps/{map}:predict"), Forward(Unary(&QueryStub::Predict), Source::kBody)},
      {"GET", RoutePattern("/v1/maps/{map}/region"),
       Forward(Forwarder<v1::PredictRegionRequest, v1::PredictRegionResponse>(WholeRegion), Source::kQuery)},
      {"GET", RoutePattern("/v1/maps/{map}/region.png"), RegionPngRoute},
      {"POST", RoutePattern("/v1/maps/{map}:topStates"), Forward(Unary(&QueryStub::TopStates), Source::kBody)},
      {"POST", RoutePattern("/v1/maps/{map}:checkAnomalies"), Forward(Unary(&QueryStub::CheckAnomalies), Source::kBody)},
      {"GET", RoutePattern("/v1/maps/{map}/model"), Forward(Unary(&QueryStub::GetStateModel), Source::kQuery)},
      {"POST", RoutePattern("/v1/maps/{map}:reconstruct"), Forward(Unary(&QueryStub::Reconstruct), Source::kBody)},
      {"POST", RoutePattern("/v1/maps/{map}:ingest"),
       Forward(Forwarder<v1::IngestRequest, v1::IngestResponse>(IngestOne), Source::kBody)},
      {"GET", RoutePattern("/v1/maps/{map}/writers/{writer_id}/lastSequence"),
       Forward(Unary(&IngestStub::LastSequence), Source::kQuery)},
      {"POST", RoutePattern("/v1/maps/{map}:runUpdate"), Forward(Unary(&AdminStub::RunUpdate), Source::kBody)},
      {"GET", RoutePattern("/v1/operations"), Forward(Unary(&AdminStub::ListOperations), Source::kQuery)},
      {"GET", RoutePattern("/v1/maps/{map}/operations"), Forward(Unary(&AdminStub::ListOperations), Source::kQuery)},
      {"GET", RoutePattern("/v1/maps/{map}/{name=operations/*}"),
       Forward(Unary(&AdminStub::GetOperation), Source::kQuery)},
      {"POST", RoutePattern("/v1/maps/{map}/{name=operations/*}:cancel"),
       Forward(Unary(&AdminStub::CancelOperation), Source::kBody)},
      {"GET", RoutePattern("/v1/status"), Forward(Unary(&AdminStub::GetServerStatus), Source::kQuery)},
      {"POST", RoutePattern("/v1/maps/{map}:check"), Forward(Unary(&AdminStub::CheckMap), Source::kBody)},
      {"POST", RoutePattern("/v1/maps/{map}:backup"), Forward(Unary(&AdminStub::BackupMap), Source::kBody)},
      {"POST", RoutePattern("/v1/maps/{map}:restore"), Forward(Unary(&AdminStub::RestoreMap), Source::kBody)},
      {"POST", RoutePattern("/v1/maps/{map}:salvage"), Forward(Unary(&AdminStub::SalvageMap), Source::kBody)},
  };
  return *routes;
}

void AddJsonApi(httplib::Server& server, ChannelSource channel) {
  const std::string pattern = R"(/v1(/.*)?)";
  auto dispatch = [channel = std::move(channel)](const httplib::Request& http, httplib::Response& response) {
    Dispatch(channel, http, response);
  };
  server.Get(pattern, dispatch);
  server.Post(pattern, dispatch);
  server.Delete(pattern, dispatch);
  // No route takes them, but their answer is a Status body too rather than httplib's empty 400.
  server.Put(pattern, dispatch);
  server.Patch(pattern, dispatch);
  // httplib would wait its read timeout (30 s) for the body of a POST with neither a body length
  // nor chunks (`curl -X POST URL` without -d), then answer an empty 400: refuse it at once,
  // before the body is read, with a Status body (411 Length Required).
  server.set_pre_routing_handler([](const httplib::Request& http, httplib::Response& response) {
    const bool has_body_method = http.method == "POST" || http.method == "PUT" || http.method == "PATCH";
    if (!has_body_method || http.has_header("Content-Length") || http.has_header("Transfer-Encoding") ||
        (http.path != "/v1" && http.path.rfind("/v1/", 0) != 0)) {
      return httplib::Server::HandlerResponse::Unhandled;
    }
    SetErrorResponse(absl::InvalidArgumentError(absl::StrCat("a ", http.method, " needs a body (at least {}) or ",
                                                             "Content-Length: 0")),
                     response);
    response.status = 411;
    return httplib::Server::HandlerResponse::Handled;
  });
}

}  // namespace fremen::server
