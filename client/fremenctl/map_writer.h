// Writing many observation batches into one map for fremenctl's ingest and demo: an IngestSession
// (client/lib) fed with CellBatch / NamedStateBatch / built scans and histories, whose acks are tallied
// so that the command can report accepted, rejected and refused, and the first reasons. Also the
// map creation and the update that ingest --create / --update and demo share.
// Thread-compatible: one command drives one writer.
#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "absl/status/status.h"
#include "client/formats/observation_batches.h"
#include "client/lib/client.h"

namespace fremen::client {

class MapWriter {
 public:
  // Opens an ingest session on `map`; on failure reports it as `command` and exits (kExitFailure).
  MapWriter(const Client& client, const std::string& map, const std::string& command);
  // The session's callback holds `this`.
  MapWriter(const MapWriter&) = delete;
  MapWriter& operator=(const MapWriter&) = delete;

  // Queue one batch; a batch the session refuses to take ends the command.
  void Send(const formats::CellBatch& batch);
  void Send(const formats::NamedStateBatch& batch);
  // A built batch (a scan or a history); a builder's error ends the command as bad input.
  void SendScan(absl::StatusOr<Scan> scan);

  // Waits until every batch sent so far is acknowledged (applied), e.g. before an update that must
  // see them; a failed session ends the command.
  void Flush();
  // Waits for every ack and closes the session; ends the command when the session failed or a
  // batch was refused as a whole (the daemon's message names the field). Prints nothing.
  IngestTotals Finish();
  // "N batches, A observations accepted, R rejected" and the first rejection reasons.
  static std::string Summary(const IngestTotals& totals, const std::string& first_rejections);
  const std::string& first_rejections() const { return first_rejections_; }

 private:
  std::string map_;
  std::string command_;
  std::unique_ptr<IngestSession> session_;
  std::string first_rejections_;  // written on the session's thread until Finish
  absl::Status first_refusal_;    // likewise
  std::mutex mutex_;              // guards the two fields above while the session runs
};

// Creates `map` unless a map of that name exists (then returns it, checking its kind). Ends the
// command on errors.
v1::Map CreateMapIfMissing(const Client& client, const v1::Map& map, const std::string& command);

// Runs the update job on `map` and waits for it; returns the number of states it published. Ends
// the command when it fails.
uint64_t RunUpdateAndWait(const Client& client, const std::string& map, const std::string& command);

// Reports a bad input file (its message names file:line) as "fremenctl COMMAND: MESSAGE" and ends
// the command with kExitFailure.
[[noreturn]] void FailInput(const std::string& command, const absl::Status& status);

}  // namespace fremen::client
