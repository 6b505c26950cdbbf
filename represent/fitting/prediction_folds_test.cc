#include "represent/fitting/prediction_folds.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace photomat {
namespace {

using ::testing::ElementsAre;

TEST(PredictionFoldsTest, LeaveOneOutPredictsEachImageFromAllOthers) {
  const std::vector<PredictionFold> folds = PredictionFolds(4, 0);
  ASSERT_EQ(folds.size(), 4u);
  EXPECT_THAT(folds[0].predicted, ElementsAre(0));
  EXPECT_THAT(folds[0].fitted, ElementsAre(1, 2, 3));
  EXPECT_THAT(folds[2].predicted, ElementsAre(2));
  EXPECT_THAT(folds[2].fitted, ElementsAre(0, 1, 3));
}

TEST(PredictionFoldsTest, HoldingOutEveryKthIsOneFoldFromTheFirst) {
  const std::vector<PredictionFold> folds = PredictionFolds(8, 3);
  ASSERT_EQ(folds.size(), 1u);
  EXPECT_THAT(folds[0].predicted, ElementsAre(0, 3, 6));
  EXPECT_THAT(folds[0].fitted, ElementsAre(1, 2, 4, 5, 7));
}

}  // namespace
}  // namespace photomat
