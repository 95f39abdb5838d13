#include "server/services/state_page.h"

#include <algorithm>
#include <tuple>

#include "absl/strings/escaping.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "storage/map_page.h"

namespace fremen::server {

namespace {

// The token's plain text: the id in 16 hex digits, then the name.
constexpr size_t kKeyDigits = 16;

std::string TokenAfter(const storage::StateLabel& last) {
  return absl::WebSafeBase64Escape(absl::StrCat(absl::Hex(last.key, absl::kZeroPad16), last.name));
}

absl::StatusOr<storage::StateLabel> LabelOfToken(const std::string& token) {
  std::string plain;
  uint64_t key = 0;
  if (!absl::WebSafeBase64Unescape(token, &plain) || plain.size() < kKeyDigits ||
      !absl::SimpleHexAtoi(plain.substr(0, kKeyDigits), &key)) {
    return absl::InvalidArgumentError(
        absl::StrCat("page_token: \"", token, "\" is not a next_page_token of ListStates"));
  }
  return storage::StateLabel{key, plain.substr(kKeyDigits), ""};
}

}  // namespace

absl::StatusOr<StatePage> PageOfStates(std::span<const storage::StateLabel> sorted, int32_t page_size,
                                       const std::string& page_token) {
  if (page_size < 0) return absl::InvalidArgumentError(absl::StrCat("page_size must be ≥ 0, got ", page_size));
  const size_t size = page_size == 0 ? storage::kDefaultPageSize
                                     : std::min<size_t>(static_cast<size_t>(page_size), storage::kMaxPageSize);
  auto begin = sorted.begin();
  if (!page_token.empty()) {
    auto after = LabelOfToken(page_token);
    if (!after.ok()) return after.status();
    begin = std::upper_bound(sorted.begin(), sorted.end(), *after, [](const auto& a, const auto& b) {
      return std::tie(a.name, a.key) < std::tie(b.name, b.key);
    });
  }
  StatePage page;
  const auto end = begin + static_cast<std::ptrdiff_t>(std::min<size_t>(size, sorted.end() - begin));
  page.states.assign(begin, end);
  if (end != sorted.end() && !page.states.empty()) page.next_page_token = TokenAfter(page.states.back());
  return page;
}

}  // namespace fremen::server
