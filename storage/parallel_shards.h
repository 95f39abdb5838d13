// ParallelForShards: f(shard) for every shard, spread over the caller's thread (which takes shard 0)
// and a process-wide pool of helper threads, returning when all are done. For the work of callers
// other than the map's writer — a large box query, a batched Predict, the checkpoint's shard
// writes — which may run concurrently with the writer and with each other; the writer's own
// per-shard work runs on the shards' owner threads instead (ShardWorkers), which keeps every
// shard's tables written by one thread. Shards run at once when helpers are free; a shard no
// helper has taken when the caller is done with its own runs on the caller, so a call never waits
// on a busy helper.
// Thread-safety: reentrant; f must be safe to run on different shards at once.
#pragma once

#include <cstddef>
#include <functional>

namespace fremen::storage {

// With `parallel` false (work too small to pay for threads) or a single shard, runs f(0), f(1), ...
// on the caller's thread.
void ParallelForShards(size_t shards, const std::function<void(size_t)>& f, bool parallel = true);

}  // namespace fremen::storage
