#include "represent/fitting/pbr_fit_summary.h"

#include <gtest/gtest.h>

namespace photomat {
namespace {

TEST(PbrFitSummaryTest, BandsAddUpToTheWholeSetAndSurviveJson) {
  const PbrFitSummary top{100, 70, 30, 30, 2.0};
  const PbrFitSummary bottom{300, 290, 10, 10, 1.0};
  PbrFitSummary whole;
  whole.Add(PbrFitSummary::FromJson(top.ToJson()));
  whole.Add(PbrFitSummary::FromJson(bottom.ToJson()));
  EXPECT_EQ(whole.pixels, 400u);
  EXPECT_EQ(whole.lobe_sampled, 360u);
  EXPECT_EQ(whole.lobe_unsampled, 40u);
  EXPECT_EQ(whole.regularised, 40u);
  EXPECT_DOUBLE_EQ(whole.ToJson().at("mean_final_cost").get<double>(), 3.0 / 400.0);
}

TEST(PbrFitSummaryTest, AnEmptyFitHasAZeroMeanCost) {
  EXPECT_EQ(PbrFitSummary{}.ToJson().at("mean_final_cost").get<double>(), 0.0);
}

TEST(PbrFitSummaryTest, AnotherObjectIsAnError) {
  EXPECT_THROW(PbrFitSummary::FromJson(nlohmann::json{{"pixels", 3}}), nlohmann::json::exception);
}

}  // namespace
}  // namespace photomat
