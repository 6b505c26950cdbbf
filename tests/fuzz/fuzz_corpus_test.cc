// The fuzzers' seed corpora through the same entry points in the ordinary (GCC) build, so that
// every CI run re-checks them: seeds named "bad-*" must be rejected with a photomat::Error, all
// others must parse, and nothing may escape as another exception.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <vector>

#include "core/error.h"
#include "tests/fuzz/fuzz_targets.h"

namespace photomat::fuzz {
namespace {

namespace fs = std::filesystem;

struct Corpus {
  const char* folder;
  FuzzTarget target;
};

// gtest would otherwise print (and ctest name) the struct by its bytes, a function pointer among
// them, which differ between builds.
void PrintTo(const Corpus& corpus, std::ostream* out) { *out << corpus.folder; }

class FuzzCorpusTest : public ::testing::TestWithParam<Corpus> {};

TEST_P(FuzzCorpusTest, ValidSeedsParseAndBadOnesAreRejected) {
  const fs::path folder = fs::path(PHOTOMAT_FUZZ_CORPUS) / GetParam().folder;
  int valid = 0, bad = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    std::ifstream in(entry.path(), std::ios::binary);
    const std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
    const bool expect_error = entry.path().filename().string().starts_with("bad-");
    try {
      GetParam().target(data);
      EXPECT_FALSE(expect_error) << entry.path() << " was accepted";
      ++valid;
    } catch (const Error& error) {
      EXPECT_TRUE(expect_error) << entry.path() << ": " << error.what();
      EXPECT_NE(std::string(error.what()).find("fuzz"), std::string::npos)
          << "the error does not name the file: " << error.what();
      ++bad;
    }
  }
  EXPECT_GE(valid, 1) << folder;
  EXPECT_GE(bad, 1) << folder;
}

INSTANTIATE_TEST_SUITE_P(
    Parsers, FuzzCorpusTest,
    ::testing::Values(Corpus{"lp", FuzzLpFile}, Corpus{"manifest", FuzzCaptureManifest},
                      Corpus{"ptm", FuzzPtmFile}, Corpus{"rti", FuzzRtiFile},
                      Corpus{"stack", FuzzStackDescription}, Corpus{"jpeg", FuzzJpegStructure}),
    [](const auto& param_info) { return std::string(param_info.param.folder); });

}  // namespace
}  // namespace photomat::fuzz
