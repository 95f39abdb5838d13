// The RPC layer's metrics (server/rpc/call_observer.h) as Prometheus families:
//   fremen_grpc_calls_total{method,code}              every call's end, unary and streaming
//   fremen_grpc_call_duration_seconds{method}         histogram of the same calls' durations
//   fremen_ingest_received_bytes_total{map}           bytes of the ingest messages read
//   fremen_ingest_backpressure_wait_seconds_total{map} time ingest streams waited for room
// Cost: a labelled series is looked up (one lock of its family) per call or message; the series
// stay bounded by the method table, the status codes and the maps.
// Thread-safety: every method may be called from any thread.
#pragma once

#include <prometheus/counter.h>
#include <prometheus/family.h>
#include <prometheus/histogram.h>
#include <prometheus/registry.h>

#include "server/rpc/call_observer.h"

namespace fremen::server {

class CallMetrics final : public CallObserver {
 public:
  // The families are added to `registry`, which must outlive this.
  explicit CallMetrics(prometheus::Registry& registry);

  void CallFinished(absl::string_view method, grpc::StatusCode code, absl::Duration took) override;
  void IngestReceived(const std::string& map, uint64_t bytes) override;
  void IngestWaited(const std::string& map, absl::Duration took) override;
  // Exports the map's ingest series from 0 on, before its first message (a rate needs a start).
  void MapOpened(const std::string& map);

 private:
  prometheus::Family<prometheus::Counter>& calls_;
  prometheus::Family<prometheus::Histogram>& durations_;
  prometheus::Family<prometheus::Counter>& ingest_bytes_;
  prometheus::Family<prometheus::Counter>& ingest_waits_;
};

}  // namespace fremen::server
