#include "represent/fitting/prediction_folds.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"

namespace photomat {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

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

// Eight images, every fourth held out: six fitted, enough for PTM (6), not for HSH9 (9).
TEST(PredictionFoldsTest, CheckFoldsFitRefusesAFoldTooSmallForTheMethod) {
  const std::vector<PredictionFold> folds = PredictionFolds(8, 4);
  EXPECT_NO_THROW(CheckFoldsFit(folds, Method::Parse("ptm"), "set"));
  EXPECT_THAT(
      [&] { CheckFoldsFit(folds, Method::Parse("hsh9"), "set"); },
      ThrowsMessage<Error>(HasSubstr("set: a prediction fold fits 6 images; hsh9 needs 9")));
}

}  // namespace
}  // namespace photomat
