#include "represent/stack/stack_band_writer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "core/error.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// A stack written in two bands with a late detail reads back with the value given at Commit (in
// the description, beside the details known from the start) and the same maps.
TEST(StackBandWriterTest, LateDetailsAreInTheCommittedDescription) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(16);
  const Representation fitted = Fit(synthetic.set, Method::Parse("ptm"));
  const auto path = dir / "ptm.exr";
  nlohmann::json description = StackDescription(fitted);
  description["details"]["early"] = "known at the start";
  StackBandWriter writer(path, description, fitted.maps().channel_names(), 16, 16,
                         kDefaultExrCompression, {"late_summary"});
  writer.Write(fitted.maps().Rows(0, 9));
  writer.Write(fitted.maps().Rows(9, 7));
  const nlohmann::json late = {{"pixels", 256}, {"mean_final_cost", 0.125}};
  writer.Commit({{"late_summary", late}});
  const LoadedStack loaded = LoadRepresentation(path);
  EXPECT_EQ(loaded.representation.details().at("late_summary"), late);
  EXPECT_EQ(loaded.representation.details().at("early"), "known at the start");
  EXPECT_TRUE(testing::SameBits(loaded.representation.maps(), fitted.maps()));
}

TEST(StackBandWriterTest, MissingOrOverlongLateDetailsAreErrorsAndLeaveNoStack) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(8);
  const Representation fitted = Fit(synthetic.set, Method::Parse("ptm"));
  for (const bool overlong : {false, true}) {
    const auto path = dir / "ptm.exr";
    {
      StackBandWriter writer(path, StackDescription(fitted), fitted.maps().channel_names(), 8, 8,
                             kDefaultExrCompression, {"late_summary"});
      writer.Write(fitted.maps().View());
      const nlohmann::json values = overlong
                                        ? nlohmann::json{{"late_summary", std::string(2000, 'x')}}
                                        : nlohmann::json::object();
      EXPECT_THAT([&] { writer.Commit(values); },
                  ThrowsMessage<Error>(HasSubstr(overlong ? "longer than" : "no value")));
    }
    EXPECT_FALSE(std::filesystem::exists(path));
  }
}

}  // namespace
}  // namespace photomat
