// ParallelForShards: f(shard) for every shard at once, on fresh threads (the caller's thread takes
// shard 0), returning when all are done. For the work of callers other than the map's writer —
// a large box query, the checkpoint's shard writes — which may run concurrently with the writer and
// with each other; the writer's own per-shard work runs on the shards' owner threads instead
// (ShardWorkers), which keeps every shard's tables written by one thread.
// Thread-safety: reentrant; f must be safe to run on different shards at once.
#pragma once

#include <cstddef>
#include <functional>

namespace fremen::storage {

// With `parallel` false (work too small to pay for threads) or a single shard, runs f(0), f(1), ...
// on the caller's thread.
void ParallelForShards(size_t shards, const std::function<void(size_t)>& f, bool parallel = true);

}  // namespace fremen::storage
