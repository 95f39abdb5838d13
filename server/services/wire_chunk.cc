#include "server/services/wire_chunk.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>
#include <grpc/slice.h>
#include <grpcpp/impl/codegen/proto_utils.h>
#include <grpcpp/support/slice.h>

#include <bit>
#include <cstdlib>
#include <new>

#include "absl/strings/str_cat.h"

namespace fremen::server {

namespace {

using google::protobuf::internal::WireFormatLite;
using CodedOutput = google::protobuf::io::CodedOutputStream;

static_assert(std::endian::native == std::endian::little, "a packed float on the wire is little-endian");

constexpr size_t kAlignment = 64;

size_t RoundUp(size_t n) { return (n + kAlignment - 1) / kAlignment * kAlignment; }

}  // namespace

absl::StatusOr<WireChunk> SerializedChunk(const google::protobuf::MessageLite& message, uint64_t values) {
  WireChunk chunk;
  chunk.values = values;
  bool own_buffer = false;
  const grpc::Status status = grpc::GenericSerialize<grpc::ProtoBufferWriter, google::protobuf::MessageLite>(
      message, &chunk.bytes, &own_buffer);
  if (!status.ok()) {
    return absl::InternalError(absl::StrCat("serializing a ", message.GetTypeName(), ": ", status.error_message()));
  }
  return chunk;
}

ValuesInPlace::ValuesInPlace(const google::protobuf::MessageLite& fields, int field_number, size_t value_bytes)
    : value_bytes_(value_bytes) {
  const size_t fields_bytes = fields.ByteSizeLong();
  const uint32_t tag = WireFormatLite::MakeTag(field_number, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);
  const size_t head_bytes =
      fields_bytes + CodedOutput::VarintSize32(tag) + CodedOutput::VarintSize32(static_cast<uint32_t>(value_bytes));
  // The head ends where the values start, on a 64-byte boundary (room_ is aligned, and so is the
  // head's rounded size), so that the prediction writes whole vectors.
  const size_t head_room = RoundUp(head_bytes);
  room_ = static_cast<uint8_t*>(std::aligned_alloc(kAlignment, head_room + RoundUp(value_bytes)));
  if (room_ == nullptr) throw std::bad_alloc();
  values_ = room_ + head_room;
  start_ = values_ - head_bytes;
  uint8_t* p = fields.SerializeWithCachedSizesToArray(start_);
  p = CodedOutput::WriteVarint32ToArray(tag, p);
  CodedOutput::WriteVarint32ToArray(static_cast<uint32_t>(value_bytes), p);
}

ValuesInPlace::~ValuesInPlace() { std::free(room_); }

std::span<float> ValuesInPlace::floats() const {
  return {reinterpret_cast<float*>(values_), value_bytes_ / sizeof(float)};
}

WireChunk ValuesInPlace::Finish(uint64_t values) && {
  // The slice owns the room from here, and frees it when gRPC has sent it.
  grpc_slice slice = grpc_slice_new_with_user_data(
      start_, static_cast<size_t>(values_ - start_) + value_bytes_, [](void* room) { std::free(room); }, room_);
  room_ = nullptr;
  grpc::Slice owned(slice, grpc::Slice::STEAL_REF);
  WireChunk chunk;
  chunk.bytes = grpc::ByteBuffer(&owned, 1);
  chunk.values = values;
  return chunk;
}

}  // namespace fremen::server
