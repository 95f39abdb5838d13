// Grid observation CSV files (client/formats/grid_csv.h ReadGridCsv), as fremenctl ingest --csv
// reads them. Every observation read has a finite time and a state in [0, 1]. Input: the file.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "client/formats/grid_csv.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  std::istringstream in(std::string(fuzz::AsView(data, size)));
  auto observations = formats::ReadGridCsv(in, "fuzz.csv");
  if (!observations.ok()) return 0;
  FUZZ_CHECK(!observations->empty(), "a file without observations is an error");
  for (const formats::CellObservation& o : *observations) {
    FUZZ_CHECK(std::isfinite(o.t), "a finite time");
    FUZZ_CHECK(o.s >= 0 && o.s <= 1, "a state in [0, 1]");
  }
  return 0;
}
