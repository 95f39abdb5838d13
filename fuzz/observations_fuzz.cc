// The `time state` observation files of fremenctl eval (client/fremenctl/offline_eval.h
// ReadObservations). Input: the file.
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "client/fremenctl/offline_eval.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  std::istringstream in(std::string(fuzz::AsView(data, size)));
  (void)client::ReadObservations(in, "fuzz.txt");
  return 0;
}
