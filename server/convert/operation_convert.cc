#include "server/convert/operation_convert.h"

namespace fremen::server {

namespace {

v1::OperationStage StageToProto(OperationStage stage) {
  switch (stage) {
    case OperationStage::kQueued: return v1::OPERATION_STAGE_QUEUED;
    case OperationStage::kRunning: return v1::OPERATION_STAGE_RUNNING;
    case OperationStage::kPublishing: return v1::OPERATION_STAGE_PUBLISHING;
    case OperationStage::kDone: return v1::OPERATION_STAGE_DONE;
  }
  return v1::OPERATION_STAGE_UNSPECIFIED;
}

}  // namespace

void TimeToProto(absl::Time t, google::protobuf::Timestamp& out) {
  const absl::Duration since_epoch = t - absl::UnixEpoch();
  const int64_t seconds = absl::ToInt64Seconds(absl::Floor(since_epoch, absl::Seconds(1)));
  out.set_seconds(seconds);
  out.set_nanos(static_cast<int32_t>(absl::ToInt64Nanoseconds(since_epoch - absl::Seconds(seconds))));
}

void OperationToProto(const OperationView& view, v1::Operation& out) {
  out.Clear();
  out.set_name(view.name);
  out.set_map(view.map);
  TimeToProto(view.create_time, *out.mutable_create_time());
  if (view.done()) TimeToProto(view.end_time, *out.mutable_end_time());
  out.set_done(view.done());
  v1::Progress& progress = *out.mutable_progress();
  progress.set_states_done(view.states_done);
  progress.set_states_total(view.states_total);
  progress.set_rate(view.rate);
  progress.set_eta_seconds(view.eta_seconds);
  if (view.done()) {
    out.mutable_error()->set_code(static_cast<int32_t>(view.error.code()));
    out.mutable_error()->set_message(std::string(view.error.message()));
  }
  if (view.result) {
    v1::UpdateResult& result = *out.mutable_update();
    result.set_states_published(view.result->states_published);
    result.set_duration_seconds(absl::ToDoubleSeconds(view.result->duration));
    for (uint64_t n : view.result->order_histogram) result.add_order_histogram(n);
    result.set_prediction_error_before(view.result->prediction_error_before);
    result.set_prediction_error_after(view.result->prediction_error_after);
  }
  out.set_stage(StageToProto(view.stage));
  out.set_cancel_requested(view.cancel_requested);
  out.set_message(view.message);
  out.set_trigger(view.trigger);
}

}  // namespace fremen::server
