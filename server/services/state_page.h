// ListStates' paging: a page of a map's labelled states in (name, id) order, and the token that
// continues after it. The token is the last state's (name, id), web-safe base64: opaque to
// clients, and still valid when states are added between pages (the next page starts after that
// name, wherever it now is), as Google's API guidelines ask of page tokens.
// Pure; thread-compatible.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/batch.h"

namespace fremen::server {

struct StatePage {
  std::vector<storage::StateLabel> states;
  std::string next_page_token;  // empty on the last page
};

// `sorted` in (name, key) order (MapStore::Labels). page_size 0 = 100, above 1000 = 1000; negative
// or a token no page returned is INVALID_ARGUMENT naming the field.
absl::StatusOr<StatePage> PageOfStates(std::span<const storage::StateLabel> sorted, int32_t page_size,
                                       const std::string& page_token);

}  // namespace fremen::server
