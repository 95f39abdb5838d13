// fremend's config file (server/daemon/config.h ApplyConfigText), then the cross-setting checks of
// FinishConfig (with the settings that name files cleared: the fuzzer must not read files). A
// config that applies spells every setting so that the spelling applies to the same spelling.
// Input: the file's text.
#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/strings/str_cat.h"
#include "fuzz/fuzz_util.h"
#include "server/daemon/config.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  server::ServerConfig config;
  const absl::Status applied =
      server::ApplyConfigText(absl::string_view(reinterpret_cast<const char*>(data), size), "fuzz.conf", config);
  if (!applied.ok()) {
    FUZZ_CHECK(absl::IsInvalidArgument(applied), applied.ToString());
    return 0;
  }
  for (const server::ConfigField& field : server::ConfigFields()) {
    if (field.key == "tokens") continue;  // spelled "(N tokens)": it never prints a secret
    const std::string spelled = field.get(config);
    server::ServerConfig again;
    const absl::Status set = server::SetConfigValue(field.key, spelled, "round trip", again);
    FUZZ_CHECK(set.ok(), absl::StrCat(field.key, " = ", spelled, ": ", set.ToString()));
    FUZZ_CHECK(field.get(again) == spelled,
               absl::StrCat(field.key, ": ", spelled, " reads back as ", field.get(again)));
  }
  config.tls_cert_file.clear();
  config.tls_key_file.clear();
  config.tls_client_ca_file.clear();
  config.tokens_file.clear();
  (void)server::FinishConfig(config);
  return 0;
}
