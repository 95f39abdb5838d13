// The fremen C++ client: typed calls of fremend's four services over one Connection.
//
//   auto client = fremen::client::Client::Connect({.address = "robot-hub:50051", .token = "..."});
//   auto map = client->GetMap("office");
//   auto session = client->OpenIngest("office");              // see ingest_session.h
//   auto p = client->Predict("office", StateSet::Cells({{3, 4}}), {t});
//
// Every call returns absl::Status / StatusOr carrying the gRPC code and the daemon's message
// (which names the field at fault). Calls that are safe to repeat (reads, RunUpdate,
// CancelOperation) are retried with exponential backoff on UNAVAILABLE until their deadline
// (CallOptions::timeout, else ConnectionOptions::default_timeout); CreateMap, DeleteMap,
// BackupMap and RestoreMap are tried once, since a retry after a lost answer would report
// ALREADY_EXISTS or NOT_FOUND for work that was done.
//
// Messages with many fields (v1::Map, v1::StateModel, v1::MapStats, v1::Operation, the server
// status) are returned as the API's own messages, documented in proto/fremen/v1/*.proto.
// Thread-safety: thread-safe; share one Client between threads.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "client/lib/connection.h"
#include "client/lib/ingest_session.h"
#include "client/lib/options.h"
#include "client/lib/region_assembler.h"
#include "client/lib/region_series_assembler.h"
#include "client/lib/state_set.h"
#include "fremen/v1/admin.pb.h"
#include "fremen/v1/maps.pb.h"
#include "fremen/v1/query.pb.h"

namespace fremen::client {

// How the published model is evaluated (docs/model.md, "Published model P" and "Persistence").
struct ModelOptions {
  // Blend in the last observation with the persistence model (maps created with persistence).
  bool persistence = false;
  // Evaluate at this order instead of each state's selected one (≤ the map's max_order).
  std::optional<uint32_t> order;
};

struct PredictOptions {
  ModelOptions model;
  // Also answer the binary states p(t) ≥ confidence. REQUIRES: in [0, 1].
  std::optional<float> confidence;
  // Only the states, not the probabilities (REQUIRES: confidence).
  bool states_only = false;
};

// p of states × times, time-major.
struct Predictions {
  uint32_t state_count = 0;
  uint32_t time_count = 0;
  std::vector<float> probabilities;  // [time · state_count + state]; empty with states_only
  std::vector<bool> states;          // same layout; with a confidence
  std::vector<uint32_t> unobserved;  // indices of states the map never observed (they predict 0.5)

  float probability(size_t time, size_t state) const { return probabilities[time * state_count + state]; }
};

// A box [lo, hi) of a grid at one time.
struct RegionQuery {
  Cell lo;
  // REQUIRES: lo < hi ≤ the grid's size on every axis; on a 2-D grid hi.z = 1 (or lo.z = hi.z = 0).
  Cell hi;
  double time = 0;
  ModelOptions model;
  v1::RegionOutput output = v1::REGION_OUTPUT_FLOAT;
  // For REGION_OUTPUT_STATES.
  float confidence = 0.5f;
  // Cells per chunk; 0 = the daemon's choice (just under 1 MiB of values).
  uint32_t chunk_cells = 0;
};

// A box [lo, hi) of a grid at many times (PredictRegionSeries).
struct RegionSeriesQuery {
  // As RegionQuery's: the box, the model options, the output.
  Cell lo;
  Cell hi;
  // REQUIRES: 1 to 1000 times.
  std::vector<double> times;
  ModelOptions model;
  v1::RegionOutput output = v1::REGION_OUTPUT_FLOAT;
  float confidence = 0.5f;
  uint32_t chunk_cells = 0;
};

struct MapPage {
  std::vector<v1::Map> maps;
  std::string next_page_token;  // empty on the last page
};

struct OperationPage {
  std::vector<v1::Operation> operations;
  std::string next_page_token;
};

struct Anomaly {
  float probability = 0;
  bool anomalous = false;
};

struct WaitOptions {
  // Between GetOperation polls. Default: 500 ms.
  absl::Duration poll_interval = absl::Milliseconds(500);
  // Give up (DEADLINE_EXCEEDED) after this. Default: never.
  absl::Duration timeout = absl::InfiniteDuration();
  // Called with each polled state of the operation, the last one done.
  std::function<void(const v1::Operation&)> on_progress;
};

class Client {
 public:
  // Opens a Connection with `options` (INVALID_ARGUMENT naming a bad option). Does not wait for
  // the daemon.
  static absl::StatusOr<Client> Connect(ConnectionOptions options);
  explicit Client(std::shared_ptr<Connection> connection) : connection_(std::move(connection)) {}

  const std::shared_ptr<Connection>& connection() const { return connection_; }

  // --- maps ---
  // The map as created, every default filled in. INVALID_ARGUMENT names the bad field;
  // ALREADY_EXISTS when the name is taken.
  absl::StatusOr<v1::Map> CreateMap(const v1::Map& map, const CallOptions& call = {}) const;
  absl::StatusOr<v1::Map> GetMap(absl::string_view map, const CallOptions& call = {}) const;
  // One page in name order; page_size 0 = the daemon's default (100).
  absl::StatusOr<MapPage> ListMaps(int page_size = 0, const std::string& page_token = "",
                                   const CallOptions& call = {}) const;
  // Every map, page after page (each page a call with its own deadline).
  absl::StatusOr<std::vector<v1::Map>> ListAllMaps(const CallOptions& call = {}) const;
  absl::Status DeleteMap(absl::string_view map, const CallOptions& call = {}) const;

  // --- ingest ---
  absl::StatusOr<std::unique_ptr<IngestSession>> OpenIngest(const std::string& map, IngestOptions options = {}) const {
    return IngestSession::Open(connection_, map, std::move(options));
  }

  // --- queries ---
  absl::StatusOr<Predictions> Predict(absl::string_view map, const StateSet& states, const std::vector<double>& times,
                                      const PredictOptions& options = {}, const CallOptions& call = {}) const;
  // The box as one dense array of its shape (hi − lo), assembled from the streamed chunks.
  absl::StatusOr<RegionArray> PredictRegion(absl::string_view map, const RegionQuery& query,
                                            const CallOptions& call = {}) const;
  // The box at each time, one dense array per time, assembled from the stream that sends the cells
  // whose prediction cannot change with time once (a box of at most 2^22 cells; the frames take
  // times × cells values of memory here).
  absl::StatusOr<RegionSeries> PredictRegionSeries(absl::string_view map, const RegionSeriesQuery& query,
                                                   const CallOptions& call = {}) const;
  // The n states of `group` most likely 1 at `time`, most likely first (generic maps).
  absl::StatusOr<std::vector<v1::ScoredState>> TopStates(absl::string_view map, absl::string_view group, double time,
                                                         uint32_t n, const ModelOptions& model = {},
                                                         const CallOptions& call = {}) const;
  // Every named state of a generic map (or of one `group`), in name order: all pages of ListStates.
  absl::StatusOr<std::vector<v1::NamedState>> ListAllStates(absl::string_view map, absl::string_view group = "",
                                                            const CallOptions& call = {}) const;
  // Which observations (value of each state at its time, or all at times[0]) are anomalous at
  // `confidence` (in [0.5, 1]).
  absl::StatusOr<std::vector<Anomaly>> CheckAnomalies(absl::string_view map, const StateSet& states,
                                                      const std::vector<float>& values,
                                                      const std::vector<double>& times, float confidence,
                                                      const ModelOptions& model = {},
                                                      const CallOptions& call = {}) const;
  // A state's model; nullopt when the state was never observed.
  absl::StatusOr<std::optional<v1::StateModel>> GetStateModel(absl::string_view map, const v1::StateRef& state,
                                                              bool include_spectrum = false,
                                                              const CallOptions& call = {}) const;
  absl::StatusOr<v1::MapStats> GetMapStats(absl::string_view map, const CallOptions& call = {}) const;

  // --- admin ---
  // Starts the update job on a map (or answers the one running) and returns its operation at once.
  absl::StatusOr<v1::Operation> RunUpdate(absl::string_view map, const CallOptions& call = {}) const;
  absl::StatusOr<v1::Operation> GetOperation(absl::string_view map, absl::string_view name,
                                             const CallOptions& call = {}) const;
  absl::StatusOr<OperationPage> ListOperations(absl::string_view map = "", bool running_only = false, int page_size = 0,
                                               const std::string& page_token = "", const CallOptions& call = {}) const;
  absl::StatusOr<v1::Operation> CancelOperation(absl::string_view map, absl::string_view name,
                                                const CallOptions& call = {}) const;
  // Polls the operation until it is done and returns it (done, with its result or its error:
  // the caller checks op.error().code()). Each poll is a call with `call`'s deadline.
  absl::StatusOr<v1::Operation> WaitOperation(absl::string_view map, absl::string_view name,
                                              const WaitOptions& wait = {}, const CallOptions& call = {}) const;
  // A consistent copy of the map into `directory` under the daemon's backup root.
  absl::StatusOr<v1::BackupMapResponse> BackupMap(absl::string_view map, absl::string_view directory,
                                                  const CallOptions& call = {}) const;
  // A backup as a new map, named `map` (empty: the backed-up map's name).
  absl::StatusOr<v1::Map> RestoreMap(absl::string_view directory, absl::string_view map = "",
                                     const CallOptions& call = {}) const;
  absl::StatusOr<v1::GetServerStatusResponse> GetServerStatus(const CallOptions& call = {}) const;
  // Verifies the map's files while it serves (like fsck); problems are in the answer (clean is
  // false), not in the status. Reads every record: give it a deadline to match the map's size.
  absl::StatusOr<v1::CheckMapResponse> CheckMap(absl::string_view map, const CallOptions& call = {}) const;
  // Salvages a damaged (failed) map into a new map `new_map` (empty: "<map>-salvaged"): everything that verifies is
  // kept, what was lost is in the answer. Not retried (it creates a map). Reads the whole map: give it a deadline to
  // match the map's size.
  absl::StatusOr<v1::SalvageMapResponse> SalvageMap(absl::string_view map, absl::string_view new_map = "",
                                                    const CallOptions& call = {}) const;

  // --- a map's copy as a stream, and moves (docs/fleet.md, "Moving a map") ---
  // The map's export (header, data chunks, trailer): `receive` is called with each message in
  // order; a non-OK answer cancels the stream and is returned. Tried once. chunk_bytes 0: 1 MiB.
  // `kind` and `tail_after_lsn`: ExportMapRequest's (an online move's snapshot, then its tail).
  absl::Status ExportMap(absl::string_view map, const std::function<absl::Status(const v1::MapChunk&)>& receive,
                         const CallOptions& call = {}, uint32_t chunk_bytes = 0,
                         v1::MapExportKind kind = v1::MAP_EXPORT_KIND_SNAPSHOT, uint64_t tail_after_lsn = 0) const;
  // An export as a new map: `next` fills the next message and answers true, or false once the
  // trailer has been given; an error cancels the stream and is returned. `map` is the header's
  // map (sent as x-fremen-map, so that a proxy routes the call to its owner). Tried once.
  absl::StatusOr<v1::ImportMapResponse> ImportMap(absl::string_view map,
                                                  const std::function<absl::StatusOr<bool>(v1::MapChunk&)>& next,
                                                  const CallOptions& call = {}) const;
  // ExportMap of `map` here streamed straight into ImportMap on `target`, as `new_name` (empty:
  // the same name). An online move copies kind ONLINE_SNAPSHOT, then (writes stopped) kind TAIL
  // after the snapshot's LSN (the first answer's snapshot_lsn) into the same name.
  absl::StatusOr<v1::ImportMapResponse> CopyMapTo(const Client& target, absl::string_view map,
                                                  absl::string_view new_name = "", const CallOptions& call = {},
                                                  v1::MapExportKind kind = v1::MAP_EXPORT_KIND_SNAPSHOT,
                                                  uint64_t tail_after_lsn = 0) const;
  // A step of a move on the daemon that holds the map (AdminService.SetMapMove). Each step is
  // idempotent, so it is retried.
  absl::StatusOr<v1::SetMapMoveResponse> SetMapMove(absl::string_view map, v1::MapMoveStep step,
                                                    absl::string_view to = "", const CallOptions& call = {}) const;

 private:
  std::shared_ptr<Connection> connection_;
};

// The API's PredictionOptions for `model`.
v1::PredictionOptions ToProto(const ModelOptions& model);

}  // namespace fremen::client
