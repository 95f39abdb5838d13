// A streamed response as it goes on the wire — a serialized message in a grpc::ByteBuffer — with
// the number of values it carries (the stream's progress), and ValuesInPlace, which builds one
// whose values are written straight into the buffer gRPC sends.
//
// Why: a region's values are nearly all of its answer (a 1M-cell box is 1 MB as bytes, 4 MB as
// floats). Predicted into a message, they were copied once more when gRPC serialized it; the region
// streams write them where they go out instead (their methods are raw: they write ByteBuffers).
//
// Thread-safety: value types; a ValuesInPlace is filled by one thread at a time.
#pragma once

#include <google/protobuf/message_lite.h>
#include <grpcpp/support/byte_buffer.h>

#include <cstddef>
#include <cstdint>
#include <span>

#include "absl/status/statusor.h"

namespace fremen::server {

struct WireChunk {
  grpc::ByteBuffer bytes;
  uint64_t values = 0;
};

// `message` serialized as gRPC would, carrying `values` values (INTERNAL if it cannot be: 2 GiB or more).
absl::StatusOr<WireChunk> SerializedChunk(const google::protobuf::MessageLite& message, uint64_t values);

// A message made of `fields` (any fields but one) and then field `field_number` — a bytes field or
// a packed repeated float — of `value_bytes` bytes, which the caller writes in place before Finish.
// Wire-compatible with the message parsed the usual way (protobuf accepts fields in any order).
// The values start 64-byte aligned. REQUIRES: `fields` does not set field `field_number`; the
// message is under 2 GiB.
class ValuesInPlace {
 public:
  ValuesInPlace(const google::protobuf::MessageLite& fields, int field_number, size_t value_bytes);
  ValuesInPlace(const ValuesInPlace&) = delete;
  ValuesInPlace& operator=(const ValuesInPlace&) = delete;
  ~ValuesInPlace();

  std::span<uint8_t> bytes() const { return {values_, value_bytes_}; }
  // REQUIRES: value_bytes is a multiple of 4. Little-endian floats are the wire's floats.
  std::span<float> floats() const;

  // The message; this object is spent.
  WireChunk Finish(uint64_t values) &&;

 private:
  uint8_t* room_;    // what was allocated: freed by the slice that takes it, or by the destructor
  uint8_t* start_;   // the message's first byte
  uint8_t* values_;  // the field's first value
  size_t value_bytes_;
};

}  // namespace fremen::server
