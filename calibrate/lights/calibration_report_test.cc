#include "calibrate/lights/calibration_report.h"

#include <gtest/gtest.h>

#include <limits>

#include "calibrate/lights/light_list.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

LightCalibrationReport TwoLights() {
  LightCalibrationReport report;
  report.title = "sphere <test>";
  report.names = {"a.png", "b.png"};
  report.recovered = {LightDirection::FromSlantTilt(30, 0), LightDirection::FromSlantTilt(45, 90)};
  report.reference = {LightDirection::FromSlantTilt(32, 0), LightDirection::FromSlantTilt(45, 90)};
  return report;
}

TEST(CalibrationReportTest, AngularDifferencesAndSummary) {
  const LightCalibrationReport report = TwoLights();
  const auto d = report.AngularDifferences();
  ASSERT_EQ(d.size(), 2u);
  EXPECT_NEAR(d[0], 2.0, 1e-9);
  EXPECT_NEAR(d[1], 0.0, 1e-6);
  EXPECT_NEAR(report.DifferenceSummary().mean, 1.0, 1e-6);
  EXPECT_NEAR(report.DifferenceSummary().max, 2.0, 1e-9);
  EXPECT_NE(report.ToTable().find("mean 1.00"), std::string::npos) << report.ToTable();
  EXPECT_NEAR(report.ToJson()["angle_deg"]["max"].get<double>(), 2.0, 1e-9);
}

TEST(CalibrationReportTest, SvgDrawsBothLightSetsWhereTheyBelong) {
  testing::TempDir dir;
  WriteLightCalibrationSvg(dir / "report.svg", TwoLights());
  const std::string svg = ReadTextFile(dir / "report.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("sphere &lt;test&gt;"), std::string::npos);  // escaped title
  // Recovered light 1 (slant 45, tilt 90) sits straight above the centre (300, 330) at half
  // the radius of slant 90 (250): y = 330 - 125.
  EXPECT_NE(svg.find("<circle cx=\"300.0\" cy=\"205.0\" r=\"3.5\""), std::string::npos);
  // The given light 0 (slant 32, tilt 0) is a ring to the right.
  EXPECT_NE(svg.find("<circle cx=\"388.9\" cy=\"330.0\" r=\"6\""), std::string::npos);
  EXPECT_NE(svg.find("2.00&#176;"), std::string::npos);
}

TEST(CalibrationReportTest, MismatchedReferenceIsAnError) {
  LightCalibrationReport report = TwoLights();
  report.reference.pop_back();
  EXPECT_THROW(report.AngularDifferences(), Error);
  testing::TempDir dir;
  EXPECT_THROW(WriteLightCalibrationSvg(dir / "r.svg", report), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "r.svg"));
}

TEST(CalibrationReportTest, UncertaintiesAndNotesInEveryForm) {
  LightCalibrationReport report = TwoLights();
  report.uncertainty_degrees = {0.25, std::numeric_limits<double>::quiet_NaN()};
  report.notes = {"refinement: converged"};
  const std::string table = report.ToTable();
  EXPECT_EQ(table.rfind("refinement: converged\n", 0), 0u) << table;
  EXPECT_NE(table.find("+-deg"), std::string::npos) << table;
  EXPECT_NE(table.find("0.25"), std::string::npos) << table;
  const nlohmann::json json = report.ToJson();
  EXPECT_DOUBLE_EQ(json["lights"][0]["uncertainty_deg"].get<double>(), 0.25);
  EXPECT_TRUE(json["lights"][1]["uncertainty_deg"].is_null());  // unknown, not a number
  EXPECT_EQ(json["notes"][0], "refinement: converged");
  const std::string svg = report.ToSvg();
  EXPECT_NE(svg.find("+-deg"), std::string::npos);
  EXPECT_NE(svg.find(" 0.25"), std::string::npos);
  EXPECT_NE(svg.find("refinement: converged"), std::string::npos);
  report.uncertainty_degrees.pop_back();
  EXPECT_THROW(report.ToTable(), Error);
}

TEST(LightListTest, ReadsPlainVectorListsWithAnOptionalCount) {
  testing::TempDir dir;
  testing::WriteFile(dir / "lights.txt", "2\n0 0 1\n0.5 0 0.5\n");
  const auto lights = ReadLightList(dir / "lights.txt");
  ASSERT_EQ(lights.size(), 2u);
  EXPECT_NEAR(lights[1].SlantDegrees(), 45.0, 1e-9);
  testing::WriteFile(dir / "count.txt", "3\n0 0 1\n");
  EXPECT_THROW(ReadLightList(dir / "count.txt"), Error);
  testing::WriteFile(dir / "bad.txt", "0 0 1\n0 x 1\n");
  try {
    ReadLightList(dir / "bad.txt");
    FAIL();
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("line 2"), std::string::npos);
  }
  testing::WriteFile(dir / "set.lp", "a.png 0 0 1\nb.png 0.5 0 0.5\n");
  EXPECT_EQ(ReadLightList(dir / "set.lp").size(), 2u);
}

}  // namespace
}  // namespace photomat
