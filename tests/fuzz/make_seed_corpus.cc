// Writes the binary seed files of tests/fuzz/corpus (ptm/, rti/): small valid files of every
// variant the readers take, and a few broken ones. The text seeds (lp/, manifest/, stack/) are
// written by hand. Usage: make_seed_corpus tests/fuzz/corpus
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "relight/formats/ptm_file.h"
#include "relight/formats/rti_file.h"

namespace fs = std::filesystem;
using namespace photomat;

namespace {

void Write(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<long>(bytes.size()));
  std::printf("%s (%zu bytes)\n", path.c_str(), bytes.size());
}

PtmFile Ptm(PtmFormat format, int width, int height) {
  PtmFile ptm;
  ptm.format = format;
  ptm.width = width;
  ptm.height = height;
  ptm.scale = {0.5, 0.5, 0.25, 0.5, 0.25, 1.0};
  ptm.bias = {167, 97, 0, 0, 0, 0};
  ptm.planes.assign(ptm.PlaneCount(), std::vector<std::uint8_t>(width * height));
  for (int k = 0; k < ptm.PlaneCount(); ++k) {
    for (int p = 0; p < width * height; ++p)
      ptm.planes[k][p] = static_cast<std::uint8_t>(37 * k + 11 * p);
  }
  return ptm;
}

std::string Jpeg(const std::vector<std::uint8_t>& plane, int width, int height) {
  std::vector<unsigned char> buffer;
  OIIO::Filesystem::IOVecOutput memory(buffer);
  auto output = OIIO::ImageOutput::create("plane.jpg");
  output->set_ioproxy(&memory);
  OIIO::ImageSpec spec(width, height, 1, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:90");
  output->open("plane.jpg", spec);
  output->write_image(OIIO::TypeDesc::UINT8, plane.data());
  output->close();
  return std::string(buffer.begin(), buffer.end());
}

// The documented JPEG layout (ptm_file.cc): plane 1 refers to plane 0, plane 2 has one side
// record.
std::string JpegPtm(PtmFormat format, int width, int height) {
  const PtmFile ptm = Ptm(format, width, height);
  const int n = ptm.PlaneCount();
  std::vector<std::string> streams;
  for (int s = 0; s < n; ++s) streams.push_back(Jpeg(ptm.planes[s], width, height));
  const std::string side = std::string("\0\0\0\1", 4) + "\x7f";
  std::string out = fmt::format("PTM_1.2\n{}\n{}\n{}\n", ToString(format), width, height);
  out += "0.500000 0.500000 0.250000 0.500000 0.250000 1.000000 \n167 97 0 0 0 0 \n90\n";
  const auto line = [&](auto value) {
    std::string text;
    for (int s = 0; s < n; ++s) text += fmt::format("{}{}", s ? " " : "", value(s));
    out += text + "\n";
  };
  for (int k = 0; k < 3; ++k) line([](int) { return 0; });
  line([](int s) { return s; });
  line([](int s) { return s == 1 ? 0 : -1; });
  line([&](int s) { return streams[s].size(); });
  line([&](int s) { return s == 2 ? 5 : 0; });
  for (int s = 0; s < n; ++s) out += streams[s] + (s == 2 ? side : "");
  return out;
}

RtiFile Rti(int terms, int width, int height) {
  RtiFile rti;
  rti.width = width;
  rti.height = height;
  rti.terms = terms;
  for (int j = 0; j < terms; ++j) {
    rti.scale.push_back(0.5f + 0.1f * j);
    rti.bias.push_back(-0.25f + 0.02f * j);
  }
  rti.planes.assign(terms * 3, std::vector<std::uint8_t>(width * height));
  for (int k = 0; k < terms * 3; ++k) {
    for (int p = 0; p < width * height; ++p)
      rti.planes[k][p] = static_cast<std::uint8_t>(29 * k + 7 * p);
  }
  return rti;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_seed_corpus CORPUS_FOLDER\n");
    return 2;
  }
  const fs::path root = argv[1];
  fs::create_directories(root / "ptm");
  fs::create_directories(root / "rti");
  Write(root / "ptm" / "rgb-3x2.ptm", SerializePtm(Ptm(PtmFormat::kRgb, 3, 2)));
  Write(root / "ptm" / "lrgb-4x2.ptm", SerializePtm(Ptm(PtmFormat::kLrgb, 4, 2)));
  Write(root / "ptm" / "lum-2x2.ptm", SerializePtm(Ptm(PtmFormat::kLum, 2, 2)));
  std::string v11 = SerializePtm(Ptm(PtmFormat::kLrgb, 2, 1));
  v11.replace(0, 7, "PTM_1.1");
  Write(root / "ptm" / "lrgb-v1.1-2x1.ptm", v11);
  Write(root / "ptm" / "jpeg-lrgb-8x8.ptm", JpegPtm(PtmFormat::kJpegLrgb, 8, 8));
  Write(root / "ptm" / "jpeg-rgb-8x4.ptm", JpegPtm(PtmFormat::kJpegRgb, 8, 4));
  const std::string rgb = SerializePtm(Ptm(PtmFormat::kRgb, 3, 2));
  Write(root / "ptm" / "bad-truncated.ptm", rgb.substr(0, rgb.size() - 5));
  Write(root / "rti" / "hsh4-3x2.rti", SerializeRti(Rti(4, 3, 2)));
  Write(root / "rti" / "hsh9-2x2.rti", SerializeRti(Rti(9, 2, 2)));
  RtiFile commented = Rti(16, 1, 2);
  commented.comments = {" made by photomat's seed generator"};
  Write(root / "rti" / "hsh16-1x2.rti", SerializeRti(commented));
  const std::string hsh9 = SerializeRti(Rti(9, 2, 2));
  Write(root / "rti" / "bad-truncated.rti", hsh9.substr(0, hsh9.size() - 1));
  return 0;
}
