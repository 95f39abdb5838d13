// The store the services serve, published once it is open. The daemon starts serving (health
// NOT_SERVING) before it recovers the maps, so calls that arrive meanwhile get UNAVAILABLE — the
// status clients retry — instead of waiting or failing for good.
// Thread-safety: Publish once from the daemon; Get from any thread. The store outlives the server.
#pragma once

#include <atomic>

#include "absl/status/statusor.h"
#include "storage/store.h"

namespace fremen::server {

class StoreHandle {
 public:
  void Publish(storage::Store* store) { store_.store(store, std::memory_order_release); }

  absl::StatusOr<storage::Store*> Get() const {
    storage::Store* store = store_.load(std::memory_order_acquire);
    if (store == nullptr) return absl::UnavailableError("fremend is starting (recovering its maps); retry shortly");
    return store;
  }

 private:
  std::atomic<storage::Store*> store_{nullptr};
};

}  // namespace fremen::server
