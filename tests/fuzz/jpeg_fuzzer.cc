// libFuzzer target: see fuzz_targets.h.
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  photomat::fuzz::RunExpectingOnlyPhotomatErrors(photomat::fuzz::FuzzJpegStructure, data, size);
  return 0;
}
