#include "represent/streaming/fitted_stack_writer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/error.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

// A band of `fitted`'s rows whose details hold `robust` as that band's robust summary.
Representation Band(const Representation& fitted, int first, int rows,
                    const RobustFitSummary& robust) {
  nlohmann::json details = fitted.details();
  details["robust_summary"] = robust.ToJson();
  return fitted.WithMapsAndDetails(Image(fitted.maps().Rows(first, rows)), details);
}

// Bands with rows no band covers (before, between and after them: bands the mask leaves empty)
// read back as the bands' maps with zeros in those rows, and the description's robust summary
// is the bands' summed, not the first band's.
TEST(FittedStackWriterTest, UncoveredRowsAreZeroAndTheSummariesAreTheBandsSummed) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(12);
  const Representation fitted = Fit(synthetic.set, Method::Parse("ptm"));
  const RobustFitSummary upper{.observations = 40, .not_measured = 1, .mean_weight = 0.25};
  const RobustFitSummary lower{.observations = 120, .down_weighted = 2, .mean_weight = 0.75};
  const auto path = dir / "ptm.exr";
  FittedStackWriter writer(path, 12, 12, kDefaultExrCompression, {});
  EXPECT_EQ(writer.maps(), 0);
  writer.Write(2, Band(fitted, 2, 3, upper));
  writer.Write(7, Band(fitted, 7, 2, lower));
  EXPECT_EQ(writer.maps(), fitted.maps().channels());
  EXPECT_THAT([&] { writer.Write(8, Band(fitted, 8, 1, lower)); },
              ThrowsMessage<Error>(HasSubstr("after row 9")));
  writer.Commit();

  const LoadedStack loaded = LoadRepresentation(path);
  const Image& maps = loaded.representation.maps();
  ASSERT_EQ(maps.height(), 12);
  for (int y = 0; y < 12; ++y) {
    const bool covered = (y >= 2 && y < 5) || (y >= 7 && y < 9);
    for (int x = 0; x < 12; ++x) {
      for (int c = 0; c < maps.channels(); ++c) {
        ASSERT_EQ(maps.at(x, y, c), covered ? fitted.maps().at(x, y, c) : 0.0f)
            << x << ", " << y << ", " << c;
      }
    }
  }
  RobustFitSummary whole = upper;
  whole.Add(lower);
  EXPECT_EQ(loaded.representation.details().at("robust_summary"), whole.ToJson());
  EXPECT_EQ(whole.observations, 160u);
  EXPECT_DOUBLE_EQ(whole.mean_weight, 0.625);
}

TEST(FittedStackWriterTest, NoBandOrAnAbandonedWriterLeavesNoStack) {
  testing::TempDir dir;
  const auto synthetic = testing::ShadowedSpecularSet(8);
  const Representation fitted = Fit(synthetic.set, Method::Parse("gradient"));
  const auto path = dir / "gradient.exr";
  {
    FittedStackWriter writer(path, 8, 8, kDefaultExrCompression, {});
    EXPECT_THAT([&] { writer.Commit(); }, ThrowsMessage<Error>(HasSubstr("no band")));
  }
  {
    FittedStackWriter writer(path, 8, 8, kDefaultExrCompression, {});
    writer.Write(0, fitted.WithMaps(Image(fitted.maps().Rows(0, 4))));
    // 4 rows from row 6 would reach past the stack's 8.
    EXPECT_THAT([&] { writer.Write(6, fitted.WithMaps(Image(fitted.maps().Rows(4, 4)))); },
                ThrowsMessage<Error>(HasSubstr("rows 6 to 10")));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

}  // namespace
}  // namespace photomat
