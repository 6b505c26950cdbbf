// Degenerate light sets read through every loader: the fit names the light file and the fault.
#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"
#include "represent/fitting/fit.h"
#include "tests/support/layouts.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

class FitInputTest : public ::testing::TestWithParam<int> {
 protected:
  std::string FitError(const std::vector<std::string>& lights, const char* method) {
    const testing::LayoutWriter layout = testing::Layouts()[GetParam()];
    std::vector<std::string> names;
    for (std::size_t i = 0; i < lights.size(); ++i) names.push_back(fmt::format("{}.png", i));
    testing::WriteImages(dir_.path(), names);
    layout.write_lights(dir_.path(), names, lights, static_cast<int>(lights.size()));
    try {
      Fit(LoadPhotometricSet(dir_.path()).set, Method::Parse(method));
    } catch (const Error& e) {
      EXPECT_EQ(e.file().filename(), layout.light_file);
      return e.what();
    }
    return "no error";
  }
  testing::TempDir dir_;
};

TEST_P(FitInputTest, FewerLightsThanTheMethodNeeds) {
  EXPECT_THAT(FitError({"0.5 0 0.866", "0 0.5 0.866", "-0.5 0 0.866", "0 -0.5 0.866"}, "ptm"),
              HasSubstr("ptm needs at least 6 images; the set has 4"));
}

TEST_P(FitInputTest, CoplanarLights) {
  EXPECT_THAT(FitError({"0.5 0 0.866", "0.7 0 0.7", "-0.5 0 0.866", "-0.2 0 0.98"}, "gradient"),
              AllOf(HasSubstr("gradient: the 4 lights are coplanar"),
                    HasSubstr("three independent directions")));
}

INSTANTIATE_TEST_SUITE_P(AllLayouts, FitInputTest, ::testing::Values(0, 1, 2),
                         [](const auto& param_info) {
                           return std::string(ToString(testing::Layouts()[param_info.param].kind));
                         });

}  // namespace
}  // namespace photomat
