// Batches into a map, map creation and the update (see map_writer.h).
#include "client/fremenctl/map_writer.h"

#include <cstdio>
#include <mutex>

#include "absl/strings/str_cat.h"
#include "client/fremenctl/connection.h"
#include "client/fremenctl/exit_codes.h"

namespace fremen::client {

namespace {

const char* ReasonName(v1::RejectReason reason) {
  switch (reason) {
    case v1::REJECT_REASON_VALUE_OUT_OF_RANGE: return "value outside [0, 1]";
    case v1::REJECT_REASON_OUTSIDE_MAP: return "cell outside the map's grid";
    default: return "rejected";
  }
}

}  // namespace

void FailInput(const std::string& command, const absl::Status& status) {
  std::fprintf(stderr, "fremenctl %s: %s\n", command.c_str(), std::string(status.message()).c_str());
  throw CLI::RuntimeError(kExitFailure);
}

MapWriter::MapWriter(const Client& client, const std::string& map, const std::string& command)
    : map_(map), command_(command) {
  IngestOptions options;
  options.collect_acks = false;
  // The acks say which observations were rejected and why; the first few reach the summary.
  options.on_ack = [this](const IngestAck& ack) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ack.error.ok() && first_refusal_.ok()) {
      first_refusal_ = absl::Status(ack.error.code(), absl::StrCat("batch ", ack.sequence, ": ", ack.error.message()));
    }
    for (const Rejection& r : ack.rejections) {
      if (first_rejections_.size() > 200) break;
      absl::StrAppend(&first_rejections_, first_rejections_.empty() ? "" : "; ", "batch ", ack.sequence,
                      " observation ", r.index, ": ", ReasonName(r.reason));
    }
  };
  absl::StatusOr<std::unique_ptr<IngestSession>> session = client.OpenIngest(map, std::move(options));
  if (!session.ok()) FailCall(command, "cannot ingest", session.status(), map);
  session_ = *std::move(session);
}

void MapWriter::SendScan(absl::StatusOr<Scan> scan) {
  if (!scan.ok()) FailInput(command_, scan.status());
  absl::StatusOr<uint64_t> sent = session_->Send(*std::move(scan));
  if (!sent.ok()) FailCall(command_, "ingest failed", sent.status(), map_);
}

void MapWriter::Send(const formats::CellBatch& batch) {
  ScanBuilder builder(batch.time);
  for (size_t i = 0; i < batch.size(); ++i) builder.AddCell({batch.x[i], batch.y[i], batch.z[i]}, batch.values[i]);
  SendScan(builder.Build());
}

void MapWriter::Send(const formats::NamedStateBatch& batch) {
  ScanBuilder builder(batch.time);
  for (size_t i = 0; i < batch.names.size(); ++i) builder.AddNamedState(batch.names[i], batch.values[i]);
  SendScan(builder.Build());
}

void MapWriter::Flush() {
  if (absl::Status flushed = session_->Flush(); !flushed.ok()) FailCall(command_, "ingest failed", flushed, map_);
}

IngestTotals MapWriter::Finish() {
  if (absl::Status closed = session_->Close(); !closed.ok()) FailCall(command_, "ingest failed", closed, map_);
  const IngestTotals totals = session_->totals();
  session_.reset();  // the session's thread has ended: the fields below are ours again
  if (!first_refusal_.ok()) {
    FailCall(command_, absl::StrCat(totals.refused, " of ", totals.sent, " batches were refused"), first_refusal_,
             map_);
  }
  return totals;
}

std::string MapWriter::Summary(const IngestTotals& totals, const std::string& first_rejections) {
  std::string text = absl::StrCat(totals.sent, totals.sent == 1 ? " batch, " : " batches, ", totals.accepted, " observations accepted, ",
                                  totals.rejected, " rejected");
  if (totals.rejected > 0 && !first_rejections.empty()) absl::StrAppend(&text, " (", first_rejections, ")");
  return text;
}

v1::Map CreateMapIfMissing(const Client& client, const v1::Map& map, const std::string& command) {
  absl::StatusOr<v1::Map> existing = client.GetMap(map.name(), GlobalCall());
  if (existing.ok()) {
    if (existing->kind() != map.kind()) {
      FailInput(command,
                absl::FailedPreconditionError(absl::StrCat(
                    "map ", map.name(), " exists and is a ", existing->kind() == v1::MAP_KIND_GRID ? "grid" : "generic",
                    " map; this input needs a ", map.kind() == v1::MAP_KIND_GRID ? "grid" : "generic", " map")));
    }
    return *existing;
  }
  if (existing.status().code() != absl::StatusCode::kNotFound) {
    FailCall(command, "cannot read the map", existing.status(), map.name());
  }
  absl::StatusOr<v1::Map> created = client.CreateMap(map, GlobalCall());
  if (!created.ok()) FailCall(command, "cannot create the map", created.status(), map.name());
  std::printf("created %s map %s\n", map.kind() == v1::MAP_KIND_GRID ? "grid" : "generic", map.name().c_str());
  return *created;
}

uint64_t RunUpdateAndWait(const Client& client, const std::string& map, const std::string& command) {
  absl::StatusOr<v1::Operation> started = client.RunUpdate(map, GlobalCall());
  if (!started.ok()) FailCall(command, "cannot start the update", started.status(), map);
  absl::StatusOr<v1::Operation> done = client.WaitOperation(map, started->name(), {}, GlobalCall());
  if (!done.ok()) FailCall(command, "the update did not finish", done.status(), map);
  if (done->error().code() != 0) {
    FailCall(command, "the update failed",
             absl::Status(static_cast<absl::StatusCode>(done->error().code()), done->error().message()), map);
  }
  return done->update().states_published();
}

}  // namespace fremen::client
