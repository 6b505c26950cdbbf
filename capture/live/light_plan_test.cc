#include "capture/live/light_plan.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "capture/io/lp_file.h"
#include "core/error.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;

TEST(LightPlanTest, ThesisGridListAndFiles) {
  const LightPlan thesis = ReadLightPlan("thesis");
  EXPECT_TRUE(SameLights(thesis.lights, ThesisLightGrid()));

  const LightPlan list = ReadLightPlan("30,0; 45,90 ;60,180");
  ASSERT_EQ(list.lights.size(), 3u);
  EXPECT_NEAR(list.lights[1].SlantDegrees(), 45.0, 1e-9);
  EXPECT_NEAR(list.lights[1].TiltDegrees(), 90.0, 1e-9);
  EXPECT_FALSE(SameLights(list.lights, thesis.lights));

  testing::TempDir dir;
  const std::vector<LightDirection> lights = {LightDirection::FromVector(0, 0, 1),
                                              LightDirection::FromVector(0.5, 0, 0.8)};
  WriteLpFile(dir / "dome.lp", {"a.png", "b.png"}, lights);
  const LightPlan dome = ReadLightPlan((dir / "dome.lp").string());
  EXPECT_TRUE(SameLights(dome.lights, lights));
}

TEST(LightPlanTest, BadPlansAreErrors) {
  try {
    ReadLightPlan("30,0;45");
    FAIL();
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("light list entry 2 \"45\": expected SLANT,TILT"));
  }
  EXPECT_THROW(ReadLightPlan("120,0"), Error);
  try {
    ReadLightPlan("/no/such/plan.lp");
    FAIL();
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("/no/such/plan.lp: no such light plan"));
  }
}

}  // namespace
}  // namespace photomat
