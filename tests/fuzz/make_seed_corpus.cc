// Writes the binary seed files of tests/fuzz/corpus (ptm/, rti/): small valid files of every
// variant the readers take, and a few broken ones. The text seeds (lp/, manifest/, stack/) are
// written by hand. Usage: make_seed_corpus tests/fuzz/corpus

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

// A JPEG variant through photomat's writer: plane 1 predicted from plane 0, side information
// for the pixels the JPEG misses by more than 3 codes.
std::string JpegPtm(PtmFormat format, int width, int height) {
  PtmFile ptm = Ptm(format, width, height);
  ptm.jpeg = PtmJpegCoding::Unpredicted(ptm.PlaneCount(), 90);
  ptm.jpeg.planes[1].reference = 0;
  ptm.jpeg.side_information_tolerance = 3;
  return SerializePtm(ptm);
}

// The prediction of HP's JPEG_LRGB files (order 8 4 3 2 1 7 5 0 6, references
// 5 -1 -1 -1 -1 1 7 -1 7, a0 and a5 from inverted references), R also motion compensated.
std::string PredictedJpegLrgb(int width, int height) {
  PtmFile ptm = Ptm(PtmFormat::kJpegLrgb, width, height);
  const int order[9] = {8, 4, 3, 2, 1, 7, 5, 0, 6};
  const int references[9] = {5, -1, -1, -1, -1, 1, 7, -1, 7};
  ptm.jpeg.quality = 75;
  ptm.jpeg.planes.resize(9);
  for (int s = 0; s < 9; ++s) {
    ptm.jpeg.planes[s].order = order[s];
    ptm.jpeg.planes[s].reference = references[s];
    ptm.jpeg.planes[s].inverted = s == 0 || s == 5;
  }
  ptm.jpeg.planes[6] = {true, true, 2, -1, order[6], references[6]};
  ptm.jpeg.side_information_tolerance = 8;
  return SerializePtm(ptm);
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
  const std::string predicted = PredictedJpegLrgb(16, 8);
  Write(root / "ptm" / "jpeg-lrgb-predicted-16x8.ptm", predicted);
  std::string cycle = predicted;
  const std::string references = "5 -1 -1 -1 -1 1 7 -1 7";
  cycle.replace(cycle.find(references), references.size(), "5 0 -1 -1 -1 1 7 -1 7");
  Write(root / "ptm" / "bad-jpeg-reference-cycle.ptm", cycle);
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
