#include "server/metrics/call_metrics.h"

#include <string>

#include "server/metrics/buckets.h"
#include "server/rpc/status_convert.h"

namespace fremen::server {

CallMetrics::CallMetrics(prometheus::Registry& registry)
    : calls_(prometheus::BuildCounter()
                 .Name("fremen_grpc_calls_total")
                 .Help("gRPC calls ended, by method and status code (streams included)")
                 .Register(registry)),
      durations_(prometheus::BuildHistogram()
                     .Name("fremen_grpc_call_duration_seconds")
                     .Help("gRPC calls' durations from arrival to their status, by method")
                     .Register(registry)),
      ingest_bytes_(prometheus::BuildCounter()
                        .Name("fremen_ingest_received_bytes_total")
                        .Help("Bytes of the ingest messages read, by map")
                        .Register(registry)),
      ingest_waits_(prometheus::BuildCounter()
                        .Name("fremen_ingest_backpressure_wait_seconds_total")
                        .Help("Time ingest streams waited for room in a map's full queue, by map")
                        .Register(registry)) {}

void CallMetrics::CallFinished(absl::string_view method, grpc::StatusCode code, absl::Duration took) {
  const std::string name(method);
  calls_.Add({{"method", name}, {"code", std::string(StatusCodeName(code))}}).Increment();
  durations_.Add({{"method", name}}, LatencyBuckets()).Observe(absl::ToDoubleSeconds(took));
}

void CallMetrics::MapOpened(const std::string& map) {
  ingest_bytes_.Add({{"map", map}});
  ingest_waits_.Add({{"map", map}});
}

void CallMetrics::IngestReceived(const std::string& map, uint64_t bytes) {
  ingest_bytes_.Add({{"map", map}}).Increment(static_cast<double>(bytes));
}

void CallMetrics::IngestWaited(const std::string& map, absl::Duration took) {
  ingest_waits_.Add({{"map", map}}).Increment(absl::ToDoubleSeconds(took));
}

}  // namespace fremen::server
