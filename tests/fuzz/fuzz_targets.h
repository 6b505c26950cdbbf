#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace photomat::fuzz {

// One entry point per parser that reads files from outside: each parses `data` as that file
// would be parsed and must return normally or throw photomat::Error; anything else (a crash, an
// out-of-bounds read under AddressSanitizer, another exception type) is a bug. Shared by the
// libFuzzer targets (tests/fuzz/*_fuzzer.cc) and the corpus regression test that runs in the
// ordinary build (fuzz_corpus_test.cc).
void FuzzLpFile(std::span<const std::uint8_t> data);
void FuzzCaptureManifest(std::span<const std::uint8_t> data);
void FuzzPtmFile(std::span<const std::uint8_t> data);
void FuzzRtiFile(std::span<const std::uint8_t> data);
void FuzzStackDescription(std::span<const std::uint8_t> data);
void FuzzJpegStructure(std::span<const std::uint8_t> data);

// Runs `target` on `data`, swallowing photomat::Error (the expected outcome for bad input).
using FuzzTarget = void (*)(std::span<const std::uint8_t>);
void RunExpectingOnlyPhotomatErrors(FuzzTarget target, const std::uint8_t* data, std::size_t size);

}  // namespace photomat::fuzz
