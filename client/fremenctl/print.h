// How fremenctl prints the API's messages: as JSON (--json, for scripts; protobuf's JSON mapping)
// or as short `key: value` lines for people. Thread-safety: pure functions writing to stdout.
#pragma once

#include <string>

#include "fremen/v1/admin.pb.h"
#include "google/protobuf/message.h"
#include "google/protobuf/timestamp.pb.h"

namespace fremen::client {

// The message as one JSON object (fields with default values included), and a newline.
void PrintJson(const google::protobuf::Message& message);
// The same object as a string, without the newline (to nest it: {"daemon": ..., "map": ...}).
std::string JsonOf(const google::protobuf::Message& message);
// "2026-11-22T03:04:05Z"; "-" when unset.
std::string FormatTimestamp(const google::protobuf::Timestamp& timestamp);
// 1536 → "1.5 KiB".
std::string FormatBytes(uint64_t bytes);
// A problem found by a check or a scrub: "shard-2/data.mdb: dynamic record of state 7: checksum mismatch".
std::string FormatCheckProblem(const v1::CheckProblem& problem);

}  // namespace fremen::client
