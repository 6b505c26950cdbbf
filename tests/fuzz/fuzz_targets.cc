#include "tests/fuzz/fuzz_targets.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "capture/io/capture_manifest.h"
#include "capture/io/lp_file.h"
#include "core/error.h"
#include "core/image.h"
#include "core/jpeg_structure.h"
#include "relight/formats/ptm_file.h"
#include "relight/formats/rti_file.h"
#include "represent/stack/map_stack.h"

namespace photomat::fuzz {
namespace {

std::string Text(std::span<const std::uint8_t> data) {
  return std::string(reinterpret_cast<const char*>(data.data()), data.size());
}

// Relights every pixel once: exercises the light basis and the layout a file described.
void RelightOnce(const Representation& representation) {
  const Image relit = representation.Relight(LightDirection::FromSlantTilt(35, 120));
  volatile float sink = relit.values().empty() ? 0.0f : relit.values().front();
  (void)sink;
}

// Manifests are read from a path (image names resolve against its folder): one scratch file per
// process, removed at exit.
class ScratchFile {
 public:
  ScratchFile() {
    char name[] = "/tmp/photomat-fuzz-XXXXXX";
    const int fd = mkstemp(name);
    if (fd < 0) std::abort();
    close(fd);
    path_ = name;
  }
  ~ScratchFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  const std::filesystem::path& Write(std::span<const std::uint8_t> data) {
    std::ofstream out(path_, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data.data()),
              static_cast<std::streamsize>(data.size()));
    return path_;
  }

 private:
  std::filesystem::path path_;
};

}  // namespace

void FuzzLpFile(std::span<const std::uint8_t> data) { ParseLpText(Text(data), "fuzz.lp"); }

void FuzzCaptureManifest(std::span<const std::uint8_t> data) {
  static ScratchFile scratch;
  ReadCaptureManifest(scratch.Write(data));
}

void FuzzPtmFile(std::span<const std::uint8_t> data) {
  RelightOnce(RepresentationFromPtm(ParsePtm(data, "fuzz.ptm")));
}

void FuzzRtiFile(std::span<const std::uint8_t> data) {
  RelightOnce(RepresentationFromRti(ParseRti(data, "fuzz.rti")));
}

// The input is the "photomat:stack" JSON of an EXR map stack. The EXR's channels are made up
// from the names the description asks for (so that the fuzzer reaches the layout, basis and
// provenance checks), leaving out the first one for inputs of odd length (a missing map).
void FuzzStackDescription(std::span<const std::uint8_t> data) {
  const std::string text = Text(data);
  std::vector<std::string> names;
  std::set<std::string> seen;
  const nlohmann::json json = nlohmann::json::parse(text, nullptr, false);
  if (json.is_object()) {
    for (const char* key : {"channels", "extra_layers"}) {
      const auto it = json.find(key);
      if (it == json.end() || !it->is_array()) continue;
      for (const auto& name : *it) {
        if (name.is_string() && names.size() < 256 && seen.insert(name.get<std::string>()).second) {
          names.push_back(name.get<std::string>());
        }
      }
    }
  }
  if (data.size() % 2 == 1 && !names.empty()) names.erase(names.begin());
  if (names.empty()) names.push_back("Y");
  const Image stored(3, 2, names);
  const LoadedStack stack = StackFromDescription(text, stored, "fuzz.exr");
  RelightOnce(stack.representation);
}

// The marker walk that checks every JPEG photomat opens for truncation, through a scratch file.
void FuzzJpegStructure(std::span<const std::uint8_t> data) {
  static ScratchFile scratch;
  CheckJpegIsWhole(scratch.Write(data));
}

void RunExpectingOnlyPhotomatErrors(FuzzTarget target, const std::uint8_t* data, std::size_t size) {
  try {
    target({data, size});
  } catch (const Error&) {
    // Bad input, reported as it should be.
  }
}

}  // namespace photomat::fuzz
