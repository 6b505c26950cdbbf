#include "relight/formats/rti_file.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>

#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "relight/formats/interchange.h"
#include "represent/fitting/fit.h"
#include "represent/model/hsh.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

RtiFile ParseString(const std::string& bytes, const std::string& name = "t.rti") {
  return ParseRti({reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()}, name);
}

std::string Floats(std::initializer_list<float> values) {
  std::string out(values.size() * 4, '\0');
  std::memcpy(out.data(), std::data(values), out.size());
  return out;
}

// A shadowed, glossy sample under lights at five slants: enough for every HSH order.
PhotometricSet DomeSet() {
  SyntheticMaterialOptions material;
  material.width = material.height = 20;
  material.max_slope_degrees = 45;
  SyntheticRenderOptions render;
  render.shadows = true;
  render.specular = 0.3;
  std::vector<LightDirection> lights;
  for (int slant = 10; slant <= 70; slant += 15) {
    for (int tilt = 0; tilt < 360; tilt += 30) {
      lights.push_back(LightDirection::FromSlantTilt(slant, tilt));
    }
  }
  return RenderSyntheticCapture(MakeSyntheticMaterial(material), lights, render);
}

// Must show: write -> read is exact up to the quantisation, every coefficient within scale / 510.
TEST(RtiFileTest, RoundTripIsExactUpToQuantisation) {
  const PhotometricSet set = DomeSet();
  for (int terms : {4, 9, 16}) {
    const Representation hsh = Fit(set, Method::Parse(fmt::format("hsh{}", terms)));
    const RtiFile rti = RtiFromRepresentation(hsh);
    const RtiFile back = ParseString(SerializeRti(rti));
    EXPECT_EQ(back.planes, rti.planes);
    EXPECT_EQ(back.scale, rti.scale);
    EXPECT_EQ(back.bias, rti.bias);
    const Representation read = RepresentationFromRti(back);
    EXPECT_EQ(read.method(), hsh.method());
    ASSERT_EQ(read.maps().channel_names(), hsh.maps().channel_names());
    for (std::size_t p = 0; p < hsh.maps().pixel_count(); ++p) {
      for (int k = 0; k < terms * 3; ++k) {
        ASSERT_NEAR(read.maps().pixel(p)[k], hsh.maps().pixel(p)[k], rti.scale[k / 3] / 510 + 1e-6)
            << terms << " terms, plane " << k;
      }
    }
  }
}

TEST(RtiFileTest, HeaderUsesCrlfAndTheSizeOfRealFiles) {
  // A real 320 x 470, 9-term file: 30 bytes of text, 72 of floats, 320 * 470 * 27 of bytes.
  RtiFile rti;
  rti.width = 320;
  rti.height = 470;
  rti.terms = 9;
  rti.scale.assign(9, 1.0f);
  rti.bias.assign(9, 0.0f);
  rti.planes.assign(27, std::vector<std::uint8_t>(320 * 470));
  const std::string bytes = SerializeRti(rti);
  EXPECT_EQ(bytes.size(), 4060902u);
  EXPECT_EQ(bytes.substr(0, 30), "#HSH1.2\r\n3\r\n320 470 3\r\n9 2 1\r\n");
}

TEST(RtiFileTest, ReadsRowsBottomToTopAndCoefficientsAsScaleTimesBytePlusBias) {
  // 2 x 2, 4 terms, 3 colours; every byte is 10 * row + colour + term / 10 in file order.
  std::string bytes = "#HSH1.2\r\n# a comment\r\n3\r\n2 2 3\r\n4 2 1\r\n";
  bytes += Floats({255, 255, 510, 255}) + Floats({0, 0, -10, 1});
  for (int file_row = 0; file_row < 2; ++file_row) {
    for (int x = 0; x < 2; ++x) {
      for (int c = 0; c < 3; ++c) {
        for (int j = 0; j < 4; ++j)
          bytes.push_back(static_cast<char>(100 * file_row + 10 * c + j + x));
      }
    }
  }
  const RtiFile rti = ParseString(bytes);
  EXPECT_EQ(rti.comments, (std::vector<std::string>{"HSH1.2", " a comment"}));
  // Image row 1 (bottom) is file row 0.
  EXPECT_EQ(rti.planes[2 * 3 + 1][1 * 2 + 0], 12);   // term 2, green, bottom-left
  EXPECT_EQ(rti.planes[0 * 3 + 0][0 * 2 + 1], 101);  // term 0, red, top-right
  EXPECT_DOUBLE_EQ(rti.Coefficient(2 * 3 + 1, 2), 12 * 2.0 - 10);
  const Representation r = RepresentationFromRti(rti);
  EXPECT_EQ(r.method(), "hsh4");
  EXPECT_FLOAT_EQ(r.maps().at(0, 1, 2 * 3 + 1), 14.0f);
  // LF-only headers read too.
  std::string lf = bytes;
  for (std::size_t at; (at = lf.find("\r\n")) != std::string::npos;) lf.erase(at, 1);
  EXPECT_EQ(ParseString(lf).planes, rti.planes);
}

TEST(RtiFileTest, MalformedFilesAreRejectedWithTheirFault) {
  const std::string header = "#HSH1.2\r\n3\r\n1 1 3\r\n4 2 1\r\n";
  const std::string floats = Floats({1, 1, 1, 1}) + Floats({0, 0, 0, 0});
  const std::string good = header + floats + std::string(12, '\x10');
  EXPECT_NO_THROW(ParseString(good));
  const auto fails = [&](const std::string& bytes, const std::string& message) {
    EXPECT_THAT([&] { ParseString(bytes, "bad.rti"); },
                ThrowsMessage<Error>(::testing::AllOf(HasSubstr("bad.rti: "), HasSubstr(message))))
        << message;
  };
  fails("PTM_1.2\n", "not an RTI file");
  fails("#HSH1.2\r\n2\r\n", "line 2: RTI type 2 is not supported");
  fails("#HSH1.2\r\n3\r\n1 1 2\r\n", "line 3: 2 colours");
  fails("#HSH1.2\r\n3\r\n1 1 3\r\n7 2 1\r\n", "line 4: 7 terms");
  fails("#HSH1.2\r\n3\r\n1 1 3\r\n9 1 1\r\n", "line 4: basis type 1 is not supported");
  fails("#HSH1.2\r\n3\r\n1 1 3\r\n9 2 4\r\n", "line 4: element size 4 is not supported");
  fails("#HSH1.2\r\n3\r\n99999 1 3\r\n", "implausible size");
  fails(header + Floats({1, 1, NAN, 1}), "the scales: nan is not finite");
  fails(header + floats + std::string(11, '\x10'),
        "truncated: 12 bytes of the coefficients expected, 11 remain");
  for (std::size_t length = 0; length < good.size(); ++length) {
    EXPECT_THROW(ParseString(good.substr(0, length)), Error) << length;
  }
}

TEST(RtiFileTest, OnlyHshIsStoredAsItIs) {
  const PhotometricSet set = DomeSet();
  const Representation ptm = Fit(set, Method::Parse("ptm"));
  EXPECT_THAT([&] { RtiFromRepresentation(ptm); },
              ThrowsMessage<Error>(HasSubstr("a ptm representation cannot be stored as an HSH")));
}

}  // namespace
}  // namespace photomat
