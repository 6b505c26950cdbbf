#include "relight/formats/ptm_file.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "capture/io/load_photometric_set.h"
#include "core/atomic_file.h"
#include "core/colour.h"
#include "core/error.h"
#include "relight/formats/interchange.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

PtmFile ParseString(const std::string& bytes, const std::string& name = "t.ptm") {
  return ParsePtm({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, name);
}

// Relit values of `r` at every light of `set`, and the photographs' values, flattened.
struct Comparison {
  double rms_codes = 0.0;    // against the photographs, in 8-bit codes
  double correlation = 0.0;  // against `other`'s relighting
};

Comparison Compare(const Representation& r, const PhotometricSet& photos,
                   const Representation& other) {
  double squared = 0.0, n = 0.0, sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
  for (int i = 0; i < photos.size(); ++i) {
    const Image a = r.Relight(photos.light(i)), b = other.Relight(photos.light(i));
    for (std::size_t v = 0; v < a.values().size(); ++v) {
      const double x = a.values()[v], y = b.values()[v];
      squared += std::pow(x - photos.image(i).values()[v], 2);
      n += 1;
      sa += x, sb += y, saa += x * x, sbb += y * y, sab += x * y;
    }
  }
  const double cov = sab / n - sa * sb / (n * n);
  const double va = saa / n - sa * sa / (n * n), vb = sbb / n - sb * sb / (n * n);
  return {255.0 * std::sqrt(squared / n), cov / std::sqrt(va * vb)};
}

// The fixture's JPEGs as their codes / 255: the domain PTM coefficients describe.
PhotometricSet FixtureCodes(const std::filesystem::path& folder) {
  LoadOptions options;
  options.colour_space = ColourSpace::kLinear;
  return LoadPhotometricSet(folder / "reference_8x5.lp", options).set;
}

TEST(PtmFileTest, ReadsThePtmFitterReferenceWithRowsBottomToTop) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "ptmfitter");
  const PtmFile ptm = ReadPtmFile(folder / "reference_8x5.ptm");
  EXPECT_EQ(ptm.format, PtmFormat::kLrgb);
  EXPECT_EQ(ptm.width, 8);
  EXPECT_EQ(ptm.height, 5);
  EXPECT_EQ(ptm.scale, (std::array<double, 6>{0.5, 0.5, 0.25, 0.5, 0.25, 1.0}));
  EXPECT_EQ(ptm.bias, (std::array<int, 6>{167, 97, 0, 0, 0, 0}));
  // The first payload bytes are the bottom-left pixel's a0..a5 (file row 0 = image bottom row).
  const std::size_t bottom_left = 4 * 8;
  EXPECT_EQ(ptm.planes[0][bottom_left], 0x50);
  EXPECT_EQ(ptm.planes[5][bottom_left], 0xa1);
  const PhotometricSet photos = FixtureCodes(folder);
  const Representation read = RepresentationFromPtm(ptm);
  EXPECT_EQ(read.method(), "ptm-lrgb");
  // colour = RGB / 255 * L / 255 reproduces the photographs within a code or so...
  const double rms = Compare(read, photos, read).rms_codes;
  EXPECT_LT(rms, 1.0);
  // ...and the rows read top to bottom would not (pins the orientation).
  Image flipped_maps = read.maps();
  for (int y = 0; y < 5; ++y) {
    for (int x = 0; x < 8; ++x) {
      for (int c = 0; c < flipped_maps.channels(); ++c) {
        flipped_maps.at(x, y, c) = read.maps().at(x, 4 - y, c);
      }
    }
  }
  EXPECT_GT(Compare(read.WithMaps(flipped_maps), photos, read).rms_codes, 10 * rms);
  ::testing::Test::RecordProperty("reference_rms_codes", fmt::format("{:.4f}", rms));
}

// Must show: fit the 12 images with the .lp; the file photomat writes relights the 12 lights with
// correlation >= 0.99 against the reference's relighting and RMSE against the photographs no
// worse than the reference's (both in the encoded domain PTMfitter fits in).
TEST(PtmFileTest, PhotomatsFileMatchesPtmFitterOnTheFixture) {
  PHOTOMAT_TEST_DATA_OR_SKIP(folder, "ptmfitter");
  testing::TempDir dir;
  const Representation reference = RepresentationFromPtm(ReadPtmFile(folder / "reference_8x5.ptm"));
  const PhotometricSet photos = FixtureCodes(folder);
  const double reference_rms = Compare(reference, photos, reference).rms_codes;
  // photomat's route: the images as loaded (linear), fitted in the encoded domain, quantised.
  const PhotometricSet linear = LoadPhotometricSet(folder / "reference_8x5.lp").set;
  for (const char* method : {"ptm-lrgb", "ptm"}) {
    const auto path = dir / (std::string(method) + ".ptm");
    WritePtmFile(path, PtmFromRepresentation(FitEncoded(linear, Method::Parse(method))));
    const Representation mine = RepresentationFromPtm(ReadPtmFile(path));
    const Comparison comparison = Compare(mine, photos, reference);
    EXPECT_GE(comparison.correlation, 0.99) << method;
    EXPECT_LE(comparison.rms_codes, reference_rms) << method;
    ::testing::Test::RecordProperty(
        std::string(method) + "_rms_codes",
        fmt::format("{:.4f} (reference {:.4f})", comparison.rms_codes, reference_rms));
    ::testing::Test::RecordProperty(std::string(method) + "_correlation",
                                    fmt::format("{:.6f}", comparison.correlation));
  }
}

// Must show: write -> read is exact up to the quantisation: every coefficient within half a step
// (scale / 2 in file units, i.e. scale / 510 of photomat's values), bytes identical.
TEST(PtmFileTest, RoundTripIsExactUpToQuantisation) {
  const auto synthetic = testing::ShadowedSpecularSet(24);
  for (const char* method : {"ptm", "ptm-lrgb"}) {
    const Representation fitted = FitEncoded(synthetic.set, Method::Parse(method));
    const PtmFile ptm = PtmFromRepresentation(fitted);
    const PtmFile back = ParseString(SerializePtm(ptm));
    EXPECT_EQ(back.planes, ptm.planes);
    EXPECT_EQ(back.scale, ptm.scale);
    EXPECT_EQ(back.bias, ptm.bias);
    const Representation read = RepresentationFromPtm(back);
    ASSERT_EQ(read.maps().channel_names(), fitted.maps().channel_names());
    if (std::string(method) == "ptm") {
      for (std::size_t p = 0; p < fitted.maps().pixel_count(); ++p) {
        for (int k = 0; k < 18; ++k) {
          const double bound = ptm.scale[k / 3] / 2 / 255 + 1e-7;
          ASSERT_NEAR(read.maps().pixel(p)[k], fitted.maps().pixel(p)[k], bound) << k;
        }
      }
      continue;
    }
    // LRGB: the split between luminance and chroma is renormalised; the products must agree
    // within the luminance steps times the chroma plus half a chroma step times the luminance.
    for (const auto& light :
         {LightDirection::FromSlantTilt(40, 10), LightDirection::FromSlantTilt(70, 250)}) {
      const Image a = fitted.Relight(light), b = read.Relight(light);
      const Eigen::VectorXd t = PtmLightBasis().Coefficients(light);
      double step = 0.0;
      for (int j = 0; j < 6; ++j) step += std::abs(t[j]) * ptm.scale[j] / 2 / 255;
      for (std::size_t p = 0; p < a.pixel_count(); ++p) {
        const auto bytes = read.maps().pixel(p);
        double luminance = 0.0;
        for (int j = 0; j < 6; ++j) luminance += t[j] * bytes[j];
        for (int c = 0; c < 3; ++c) {
          const double bound = step * bytes[6 + c] + std::abs(luminance) * 0.5 / 255 + 1e-6;
          ASSERT_NEAR(a.pixel(p)[c], b.pixel(p)[c], bound);
        }
      }
    }
  }
}

TEST(PtmFileTest, HeaderAndSizeFollowRealFiles) {
  // A one-channel PTM writes as PTM_FORMAT_LUM; LRGB as 6 + 3 bytes per pixel.
  Image maps(8, 5, 9);
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    for (int k = 0; k < 9; ++k) maps.pixel(p)[k] = 0.1f * k - 0.2f + 0.01f * static_cast<float>(p);
  }
  std::vector<std::string> names;
  for (int j = 0; j < 6; ++j) names.push_back(fmt::format("ptm.a{}", j));
  for (const char* c : {"rgb.R", "rgb.G", "rgb.B"}) names.push_back(c);
  maps.set_channel_names(names);
  const Representation lrgb("ptm-lrgb", maps, {6, false, true, 3},
                            std::make_shared<PtmLightBasis>());
  const std::string bytes = SerializePtm(PtmFromRepresentation(lrgb));
  EXPECT_TRUE(bytes.starts_with("PTM_1.2\nPTM_FORMAT_LRGB\n8\n5\n"));
  const std::size_t header = bytes.size() - 8 * 5 * 9;
  const std::string text = bytes.substr(0, header);
  EXPECT_THAT(text,
              ::testing::MatchesRegex(
                  "PTM_1\\.2\nPTM_FORMAT_LRGB\n8\n5\n([0-9]+\\.[0-9]{6} ){6}\n(-?[0-9]+ ){6}\n"));
  Image lum_maps(3, 2, 6);
  lum_maps.set_channel_names(
      {"ptm.a0.Y", "ptm.a1.Y", "ptm.a2.Y", "ptm.a3.Y", "ptm.a4.Y", "ptm.a5.Y"});
  const Representation lum("ptm", lum_maps, {6, true, false, 1}, std::make_shared<PtmLightBasis>());
  EXPECT_EQ(ParseString(SerializePtm(PtmFromRepresentation(lum))).format, PtmFormat::kLum);
}

TEST(PtmFileTest, OlderLrgbInterleavesNineBytesPerPixel) {
  PtmFile ptm;
  ptm.format = PtmFormat::kLrgb;
  ptm.width = 2;
  ptm.height = 2;
  ptm.scale = {1, 1, 1, 1, 1, 1};
  ptm.planes.assign(9, std::vector<std::uint8_t>(4));
  for (int k = 0; k < 9; ++k) {
    for (int p = 0; p < 4; ++p) ptm.planes[k][p] = static_cast<std::uint8_t>(10 * k + p);
  }
  std::string v12 = SerializePtm(ptm);
  // The same pixels as PTM_1.1: 9 interleaved bytes per pixel, rows bottom to top.
  std::string v11 = v12.substr(0, v12.size() - 36);
  v11.replace(0, 7, "PTM_1.1");
  for (int row : {1, 0}) {
    for (int x = 0; x < 2; ++x) {
      for (int k = 0; k < 9; ++k) v11.push_back(static_cast<char>(ptm.planes[k][row * 2 + x]));
    }
  }
  EXPECT_EQ(ParseString(v11).planes, ptm.planes);
  EXPECT_EQ(ParseString(v12).planes, ptm.planes);
}

// A greyscale JPEG of `plane` (width x height, rows as given) through OpenImageIO.
std::string EncodeJpeg(const std::vector<std::uint8_t>& plane, int width, int height) {
  std::vector<unsigned char> buffer;
  OIIO::Filesystem::IOVecOutput memory(buffer);
  auto output = OIIO::ImageOutput::create("plane.jpg");
  EXPECT_TRUE(output);
  output->set_ioproxy(&memory);
  OIIO::ImageSpec spec(width, height, 1, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:100");
  EXPECT_TRUE(output->open("plane.jpg", spec)) << output->geterror();
  EXPECT_TRUE(output->write_image(OIIO::TypeDesc::UINT8, plane.data()));
  output->close();
  return std::string(buffer.begin(), buffer.end());
}

// A JPEG-variant file built from the documented layout (file-formats.md, relight's reader): no
// real JPEG_RGB / JPEG_LRGB file is available to the tests. Plane `diff` is stored as its
// difference to plane `ref` plus 128, and `patched` carries one side-information record.
std::string JpegVariant(const PtmFile& ptm, const std::vector<int>& order, int diff, int ref,
                        int patched, std::size_t patched_pixel, std::uint8_t patched_value) {
  const int n = ptm.PlaneCount();
  const std::size_t pixels = static_cast<std::size_t>(ptm.width) * ptm.height;
  std::vector<std::string> streams, sides;
  for (int s = 0; s < n; ++s) {
    // The file's row order: bottom row first.
    std::vector<std::uint8_t> stored(pixels);
    for (int y = 0; y < ptm.height; ++y) {
      for (int x = 0; x < ptm.width; ++x) {
        const std::size_t image = static_cast<std::size_t>(ptm.height - 1 - y) * ptm.width + x;
        std::uint8_t value = ptm.planes[s][image];
        if (s == diff) value = static_cast<std::uint8_t>(value + 128 - ptm.planes[ref][image]);
        stored[static_cast<std::size_t>(y) * ptm.width + x] = value;
      }
    }
    streams.push_back(EncodeJpeg(stored, ptm.width, ptm.height));
    std::string side;
    if (s == patched) {
      // Big-endian index of the stored (bottom-up) pixel, then the byte.
      const std::size_t row = patched_pixel / ptm.width, col = patched_pixel % ptm.width;
      const std::size_t index = (ptm.height - 1 - row) * ptm.width + col;
      for (int shift : {24, 16, 8, 0}) side.push_back(static_cast<char>((index >> shift) & 0xff));
      side.push_back(static_cast<char>(patched_value));
    }
    sides.push_back(side);
  }
  const auto line = [&](const auto& value_of) {
    std::string text;
    for (int s = 0; s < n; ++s) text += fmt::format("{}{}", s ? " " : "", value_of(s));
    return text + "\n";
  };
  std::string out =
      fmt::format("PTM_1.2\n{}\n{} {}\n", ToString(ptm.format), ptm.width, ptm.height);
  out += "1.000000 1.000000 1.000000 1.000000 1.000000 1.000000\n0 0 0 0 0 0\n100\n";
  for (int k = 0; k < 3; ++k) out += line([](int) { return 0; });
  out += line([&](int s) { return order[s]; });
  out += line([&](int s) { return s == diff ? ref : -1; });
  out += line([&](int s) { return streams[s].size(); });
  out += line([&](int s) { return sides[s].size(); });
  for (int s = 0; s < n; ++s) out += streams[s] + sides[s];
  return out;
}

TEST(PtmFileTest, JpegVariantsDecodeWithReferencesAndSideInformation) {
  for (PtmFormat format : {PtmFormat::kJpegLrgb, PtmFormat::kJpegRgb}) {
    PtmFile ptm;
    ptm.format = format;
    ptm.width = 24;
    ptm.height = 16;
    const int n = ptm.PlaneCount();
    ptm.planes.assign(n, std::vector<std::uint8_t>(24 * 16));
    for (int s = 0; s < n; ++s) {
      for (int y = 0; y < 16; ++y) {
        for (int x = 0; x < 24; ++x) {
          // Smooth content (JPEG at quality 100 keeps it within a code or two), different
          // per plane and not symmetric in y, so that a row flip would show.
          ptm.planes[s][y * 24 + x] = static_cast<std::uint8_t>(40 + 4 * s + 3 * x + 5 * y);
        }
      }
    }
    std::vector<int> order(n);
    for (int s = 0; s < n; ++s) order[s] = n - 1 - s;  // decode the last plane first
    // Plane 2 is stored relative to plane 7 (decoded before it); plane 4 gets a side record.
    const std::string bytes = JpegVariant(ptm, order, 2, 7, 4, 5 * 24 + 3, 250);
    const PtmFile read = ParseString(bytes);
    EXPECT_EQ(read.format, format);
    ASSERT_EQ(read.PlaneCount(), n);
    int worst = 0;
    for (int s = 0; s < n; ++s) {
      for (std::size_t p = 0; p < read.planes[s].size(); ++p) {
        if (s == 4 && p == 5 * 24 + 3) continue;
        worst = std::max(worst, std::abs(read.planes[s][p] - ptm.planes[s][p]));
      }
    }
    EXPECT_LE(worst, 2) << ToString(format);
    EXPECT_EQ(read.planes[4][5 * 24 + 3], 250);
    // A reference decoded after the plane that needs it is an error.
    std::vector<int> bad_order(n);
    for (int s = 0; s < n; ++s) bad_order[s] = s;
    EXPECT_THAT([&] { ParseString(JpegVariant(ptm, bad_order, 2, 7, 4, 0, 0)); },
                ThrowsMessage<Error>(HasSubstr("refers to plane 7, which is decoded after it")));
  }
}

TEST(PtmFileTest, MalformedFilesAreRejectedWithTheirFault) {
  const std::string header = "PTM_1.2\nPTM_FORMAT_RGB\n2 1\n1 1 1 1 1 1\n0 0 0 0 0 0\n";
  const std::string good = header + std::string(2 * 18, '\x40');
  EXPECT_NO_THROW(ParseString(good));
  const auto fails = [&](const std::string& bytes, const std::string& message) {
    EXPECT_THAT([&] { ParseString(bytes, "bad.ptm"); },
                ThrowsMessage<Error>(::testing::AllOf(HasSubstr("bad.ptm: "), HasSubstr(message))))
        << message;
  };
  fails("GIF89a", "not a PTM file");
  fails("PTM_1.9\nPTM_FORMAT_RGB\n", "line 1: unknown PTM version \"PTM_1.9\"");
  fails("PTM_1.2\nPTM_FORMAT_XYZ\n", "line 2: unknown PTM format \"PTM_FORMAT_XYZ\"");
  fails("PTM_1.2\nPTM_FORMAT_JPEGLS_RGB\n", "PTM_FORMAT_JPEGLS_RGB is not supported");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n2 x\n", "line 3: expected the width and height: \"x\" is not");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n2 1 7\n", "line 3: expected the width and height (2 numbers)");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n0 5\n", "implausible size 0 x 5");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n65536 65536\n1 1 1 1 1 1\n0 0 0 0 0 0\n", "implausible size");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n16000 16000\n1 1 1 1 1 1\n0 0 0 0 0 0\n",
        "truncated: a 16000 x 16000 PTM_FORMAT_RGB needs 4608000000 bytes of coefficients, 0 "
        "remain");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n2 1\n1 1 1 nan 1 1\n", "the 6 scale values: nan is not finite");
  fails("PTM_1.2\nPTM_FORMAT_RGB\n2 1\n1 1 1 0 1 1\n0 0 0 0 0 0\n", "implausible scale 0");
  fails(header + std::string(35, '\x40'), "truncated");
  fails("PTM_1.2\nPTM_FORMAT_RGB" + std::string(2000, ' ') + "x\n", "no line end in 1024 bytes");
  // Every truncation of a valid file is an error, never a crash or a short read.
  for (std::size_t length = 0; length < good.size(); ++length) {
    EXPECT_THROW(ParseString(good.substr(0, length)), Error) << length;
  }
}

TEST(PtmFileTest, OtherRepresentationsAreRefittedNotStoredAsTheyAre) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Representation gradient = Fit(synthetic.set, Method::Parse("gradient"));
  EXPECT_THAT(
      [&] { PtmFromRepresentation(gradient); },
      ThrowsMessage<Error>(HasSubstr("a gradient representation cannot be stored as a PTM")));
  // Through the interchange conversion: refitted at the capture lights in encoded values.
  const LoadedStack stack{gradient, {synthetic.set.lights(), "linear", "synthetic"}};
  const Representation ptm = ConvertToEncoded(stack, Method::Parse("ptm"));
  EXPECT_EQ(ptm.method(), "ptm");
  const PtmFile file = PtmFromRepresentation(ptm);
  EXPECT_EQ(file.format, PtmFormat::kRgb);
  // The file relights close to the (encoded) Lambertian images it was refitted to.
  const Image relit = RepresentationFromPtm(file).Relight(synthetic.set.light(20));
  double worst = 0.0;
  for (std::size_t v = 0; v < relit.values().size(); ++v) {
    worst = std::max(
        worst, std::abs(relit.values()[v] - LinearToSrgb(synthetic.set.image(20).values()[v])));
  }
  EXPECT_LT(worst, 0.05);
}

}  // namespace
}  // namespace photomat
