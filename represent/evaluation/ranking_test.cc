#include "represent/evaluation/ranking.h"

#include <gtest/gtest.h>

#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.h"

namespace photomat {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

Eigen::MatrixXd Rows(int columns, std::initializer_list<double> values) {
  const auto rows = static_cast<Eigen::Index>(values.size()) / columns;
  Eigen::MatrixXd matrix(rows, columns);
  auto value = values.begin();
  for (Eigen::Index r = 0; r < rows; ++r) {
    for (Eigen::Index c = 0; c < columns; ++c) matrix(r, c) = *value++;
  }
  return matrix;
}

TEST(MidRanksTest, TiedScoresShareTheMeanOfTheirRanks) {
  const std::vector<double> scores = {0.3, 0.1, 0.3, 0.2, 0.3};
  EXPECT_EQ(MidRanks(scores), (std::vector<double>{4, 1, 4, 2, 4}));
  const std::vector<double> all_tied = {5, 5, 5, 5};
  EXPECT_EQ(MidRanks(all_tied), (std::vector<double>{2.5, 2.5, 2.5, 2.5}));
}

// Hollander & Wolfe (1973, p. 140; Example 7.1 of the 2nd edition): times of 22 players rounding
// first base by three methods (round out, narrow angle, wide angle); four players tie two methods.
// The book and R's friedman.test give the tie-corrected S' = 11.14 (11.143) and p = 0.003805.
TEST(FriedmanTest, MatchesHollanderAndWolfesRoundingFirstBaseExample) {
  const Eigen::MatrixXd times =
      Rows(3, {5.40, 5.50, 5.55, 5.85, 5.70, 5.75, 5.20, 5.60, 5.50, 5.55, 5.50, 5.40, 5.90, 5.85,
               5.70, 5.45, 5.55, 5.60, 5.40, 5.40, 5.35, 5.45, 5.50, 5.35, 5.25, 5.15, 5.00, 5.85,
               5.80, 5.70, 5.25, 5.20, 5.10, 5.65, 5.55, 5.45, 5.60, 5.35, 5.45, 5.05, 5.00, 4.95,
               5.50, 5.50, 5.40, 5.45, 5.55, 5.50, 5.55, 5.55, 5.35, 5.45, 5.50, 5.55, 5.50, 5.45,
               5.25, 5.65, 5.60, 5.40, 5.70, 5.65, 5.55, 6.30, 6.30, 6.25});
  const FriedmanTest test = Friedman(times);
  EXPECT_EQ(test.blocks, 22);
  EXPECT_EQ(test.treatments, 3);
  EXPECT_EQ(test.degrees_of_freedom, 2);
  // Rank sums by hand: 53, 47, 32 (the wide angle is fastest).
  EXPECT_DOUBLE_EQ(test.mean_ranks[0] * 22, 53.0);
  EXPECT_DOUBLE_EQ(test.mean_ranks[1] * 22, 47.0);
  EXPECT_DOUBLE_EQ(test.mean_ranks[2] * 22, 32.0);
  // R prints 11.143 and 0.003805: the published digits, +- half their last place.
  EXPECT_NEAR(test.chi_square, 11.143, 5e-4);
  EXPECT_NEAR(test.p_value, 0.003805, 5e-7);
  // Without the correction for the four tied pairs: 12/(22*3*4) * (53^2 + 47^2 + 32^2) - 3*22*4.
  EXPECT_NEAR(test.chi_square_without_tie_correction, 117.0 / 11.0, 1e-12);
  EXPECT_NEAR(test.kendalls_w, test.chi_square / (22 * 2), 1e-12);
  EXPECT_NEAR(test.iman_davenport_f, 21 * test.chi_square / (44 - test.chi_square), 1e-12);
  EXPECT_LT(test.iman_davenport_p_value, test.p_value);  // the F form is less conservative
}

// Demsar (2006), section 3.2.2 and Table 6: AUC of four C4.5 variants on 14 data sets, ranked in
// the table (the ranks in parentheses, used here as the scores, lower = better). The paper prints
// mean ranks 3.143, 2.000, 2.893, 1.964, chi2_F = 9.28 (its formula has no tie correction),
// F_F = 3.69 and the Nemenyi critical difference 1.25 at alpha 0.05 and 1.12 at alpha 0.10.
TEST(FriedmanTest, MatchesDemsarsWorkedExample) {
  const Eigen::MatrixXd ranks =
      Rows(4, {4,   3,   2,   1,   1,   2,   3, 4, 4, 1,   2,   3, 4, 1, 3, 2, 4, 2,   3,
               1,   1,   2.5, 4,   2.5, 3,   2, 4, 1, 2.5, 2.5, 4, 1, 4, 3, 2, 1, 2.5, 2.5,
               2.5, 2.5, 4,   2.5, 1,   2.5, 3, 2, 4, 1,   4,   1, 2, 3, 3, 1, 4, 2});
  const FriedmanTest test = Friedman(ranks);
  EXPECT_NEAR(test.mean_ranks[0], 3.143, 5e-4);
  EXPECT_NEAR(test.mean_ranks[1], 2.000, 5e-4);
  EXPECT_NEAR(test.mean_ranks[2], 2.893, 5e-4);
  EXPECT_NEAR(test.mean_ranks[3], 1.964, 5e-4);
  EXPECT_NEAR(test.chi_square_without_tie_correction, 9.28, 5e-3);
  EXPECT_NEAR(ImanDavenportStatistic(test.chi_square_without_tie_correction, 14, 4), 3.69, 5e-3);
  // Ties: three pairs and one block of four, sum(t^3 - t) = 3 * 6 + 60 = 78 of n (k^3 - k) = 840.
  EXPECT_NEAR(test.chi_square, test.chi_square_without_tie_correction / (1.0 - 78.0 / 840.0),
              1e-12);
  EXPECT_NEAR(NemenyiCriticalDifference(4, 14, 0.05), 1.25, 5e-3);
  EXPECT_NEAR(NemenyiCriticalDifference(4, 14, 0.10), 1.12, 5e-3);
  // "Even the difference between the best and the worst performing algorithm is already smaller".
  const Eigen::MatrixXd p = NemenyiPValues(test.mean_ranks, 14);
  EXPECT_GT(p.minCoeff(), 0.05);
  // At alpha 0.10 pure C4.5 differs from C4.5+m and C4.5+m+cf, and from nothing else.
  EXPECT_LT(p(0, 1), 0.10);
  EXPECT_LT(p(0, 3), 0.10);
  EXPECT_GT(p(0, 2), 0.10);
  EXPECT_GT(p(1, 2), 0.10);
  EXPECT_GT(p(2, 3), 0.10);
}

TEST(FriedmanTest, TheSameTableFromItsAucValuesRanksTheVotingTieAsATie) {
  // The AUC values themselves (higher = better, so negated): the paper ranks voting's two 0.975 as
  // 2 and 3; mid-ranks give both 2.5, so C4.5+cf's rank sum is 41 and C4.5+m+cf's 27
  // (hand-computed).
  const Eigen::MatrixXd auc =
      Rows(4, {0.763, 0.768, 0.771, 0.798, 0.599, 0.591, 0.590, 0.569, 0.954, 0.971, 0.968, 0.967,
               0.628, 0.661, 0.654, 0.657, 0.882, 0.888, 0.886, 0.898, 0.936, 0.931, 0.916, 0.931,
               0.661, 0.668, 0.609, 0.685, 0.583, 0.583, 0.563, 0.625, 0.775, 0.838, 0.866, 0.875,
               1.000, 1.000, 1.000, 1.000, 0.940, 0.962, 0.965, 0.962, 0.619, 0.666, 0.614, 0.669,
               0.972, 0.981, 0.975, 0.975, 0.957, 0.978, 0.946, 0.970});
  const FriedmanTest test = Friedman(-auc);
  EXPECT_DOUBLE_EQ(test.mean_ranks[0] * 14, 44.0);
  EXPECT_DOUBLE_EQ(test.mean_ranks[1] * 14, 28.0);
  EXPECT_DOUBLE_EQ(test.mean_ranks[2] * 14, 41.0);
  EXPECT_DOUBLE_EQ(test.mean_ranks[3] * 14, 27.0);
  // 12/(14*4*5) * (44^2 + 28^2 + 41^2 + 27^2) - 3*14*5 = 69/7; four pairs (iris, lung cancer,
  // primary tumor, voting) and a block of four (mushroom) tie: sum(t^3 - t) = 84.
  EXPECT_NEAR(test.chi_square_without_tie_correction, 69.0 / 7.0, 1e-12);
  EXPECT_NEAR(test.chi_square, 69.0 / 7.0 / (1.0 - 84.0 / 840.0), 1e-12);
}

TEST(FriedmanTest, UnanimousBlocksGiveConcordanceOneAndAnInfiniteF) {
  const Eigen::MatrixXd scores = Rows(3, {1, 2, 3, 0.1, 0.5, 0.9, 10, 20, 30, 4, 5, 6});
  const FriedmanTest test = Friedman(scores);
  EXPECT_NEAR(test.chi_square, 8.0, 1e-12);  // n (k - 1): 4 blocks, 3 treatments
  EXPECT_NEAR(test.kendalls_w, 1.0, 1e-12);
  EXPECT_NEAR(test.p_value, std::exp(-4.0), 1e-12);  // chi-square(2)'s tail is exp(-x / 2)
  EXPECT_TRUE(std::isinf(test.iman_davenport_f));
  EXPECT_EQ(test.iman_davenport_p_value, 0.0);
}

TEST(FriedmanTest, EveryBlockTiedIsNoEvidence) {
  const FriedmanTest test = Friedman(Eigen::MatrixXd::Ones(5, 3));
  EXPECT_EQ(test.chi_square, 0.0);
  EXPECT_EQ(test.p_value, 1.0);
  EXPECT_EQ(test.kendalls_w, 0.0);
  EXPECT_EQ(test.mean_ranks, (std::vector<double>{2, 2, 2}));
}

TEST(FriedmanTest, RejectsTooFewBlocksAndNonFiniteScores) {
  EXPECT_THROW(Friedman(Eigen::MatrixXd::Ones(1, 3)), Error);
  EXPECT_THROW(Friedman(Eigen::MatrixXd::Ones(3, 1)), Error);
  Eigen::MatrixXd scores = Eigen::MatrixXd::Ones(3, 3);
  scores(1, 2) = std::nan("");
  try {
    Friedman(scores);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("block 1, treatment 2"), std::string::npos) << e.what();
  }
}

// For two treatments the studentized range is |Z1 - Z2| / s = sqrt 2 |T|, T Student's t: exact.
TEST(StudentizedRangeTest, TwoTreatmentsMatchStudentsT) {
  for (double df : {1.0, 3.0, 10.0, 60.0}) {
    const boost::math::students_t t(df);
    for (double q : {0.5, 2.0, 3.6, 8.0}) {
      const double exact = 2.0 * boost::math::cdf(t, q / std::numbers::sqrt2) - 1.0;
      EXPECT_NEAR(StudentizedRangeCdf(q, 2, df), exact, 1e-8) << "q " << q << ", df " << df;
    }
  }
  for (double q : {0.5, 2.0, 3.6}) {
    EXPECT_NEAR(StudentizedRangeCdf(q, 2, kInfinity), std::erf(q / 2.0), 1e-10) << q;
  }
}

// Upper percentage points of the studentized range as tabulated by Harter (1960) (the tables of
// textbooks, three decimals): q such that P(Q <= q) = 0.95 or 0.99.
TEST(StudentizedRangeTest, QuantilesMatchHartersTable) {
  struct Entry {
    double probability;
    int k;
    double df;
    double q;
  };
  for (const Entry& e :
       {Entry{0.95, 2, 5, 3.635}, Entry{0.95, 3, 10, 3.877}, Entry{0.95, 4, 20, 3.958},
        Entry{0.95, 6, 12, 4.750}, Entry{0.95, 10, 30, 4.824}, Entry{0.95, 3, kInfinity, 3.314},
        Entry{0.95, 4, kInfinity, 3.633}, Entry{0.95, 5, kInfinity, 3.858},
        Entry{0.99, 3, 10, 5.270}, Entry{0.99, 5, 20, 5.294}}) {
    // Half the table's last place, and as much again for the quadrature.
    EXPECT_NEAR(StudentizedRangeQuantile(e.probability, e.k, e.df), e.q, 1e-3)
        << "p " << e.probability << ", k " << e.k << ", df " << e.df;
  }
}

// Demsar's Table 5(a): the Nemenyi test's q_alpha (the studentized range's quantile over sqrt 2)
// for 2 to 10 classifiers. The table divides Harter's three-decimal quantiles by sqrt 2 and rounds
// again (k = 3: 3.314 / sqrt 2 = 2.3433 is printed 2.343, the exact value is 2.3437), so the two
// roundings allow 5e-4 / sqrt 2 + 5e-4 = 8.5e-4; 1e-3 with the quadrature's share.
TEST(StudentizedRangeTest, NemenyiCriticalValuesMatchDemsarsTable) {
  const std::vector<double> q05 = {1.960, 2.343, 2.569, 2.728, 2.850, 2.949, 3.031, 3.102, 3.164};
  const std::vector<double> q10 = {1.645, 2.052, 2.291, 2.459, 2.589, 2.693, 2.780, 2.855, 2.920};
  for (int k = 2; k <= 10; ++k) {
    EXPECT_NEAR(StudentizedRangeQuantile(0.95, k) / std::numbers::sqrt2, q05[k - 2], 1e-3) << k;
    EXPECT_NEAR(StudentizedRangeQuantile(0.90, k) / std::numbers::sqrt2, q10[k - 2], 1e-3) << k;
  }
}

TEST(NemenyiTest, ADifferenceOfOneCriticalDifferenceHasPValueAlpha) {
  const double cd = NemenyiCriticalDifference(5, 12, 0.05);
  const std::vector<double> mean_ranks = {1.5, 1.5 + cd, 3.0, 4.0, 5.0 - cd};
  const Eigen::MatrixXd p = NemenyiPValues(mean_ranks, 12);
  EXPECT_NEAR(p(0, 1), 0.05, 1e-7);
  EXPECT_NEAR(p(1, 0), 0.05, 1e-7);
  EXPECT_EQ(p(2, 2), 1.0);
  EXPECT_LT(p(0, 3), 0.05);  // larger differences, smaller p
  EXPECT_GT(p(2, 3), 0.05);
}

}  // namespace
}  // namespace photomat
