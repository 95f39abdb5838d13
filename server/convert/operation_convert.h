// server::OperationView → fremen.v1.Operation, and the absl::Time → Timestamp conversion the admin
// service's answers share.
// Pure functions; thread-safe.
#pragma once

#include <google/protobuf/timestamp.pb.h>

#include "absl/time/time.h"
#include "fremen/v1/admin.pb.h"
#include "server/jobs/operations.h"

namespace fremen::server {

void TimeToProto(absl::Time t, google::protobuf::Timestamp& out);
void OperationToProto(const OperationView& view, v1::Operation& out);

}  // namespace fremen::server
