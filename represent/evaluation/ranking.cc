#include "represent/evaluation/ranking.h"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <numbers>
#include <numeric>

#include "core/error.h"

namespace photomat {
namespace {

using Quadrature = boost::math::quadrature::gauss_kronrod<double, 61>;

// Adaptive quadrature limits: bisection depth and relative tolerance. The inner integral (the
// range of normals) is asked for more than the outer one (over the scale), which adds its error.
constexpr unsigned kMaxDepth = 15;
constexpr double kInnerTolerance = 1e-12;
constexpr double kOuterTolerance = 1e-10;
// phi(z) < 1e-21 beyond |z| = 10: the range's integrand is negligible there.
constexpr double kNormalSupport = 10.0;
// The scale s = sqrt(chi2_df / df) is integrated between its 1e-14 and 1 - 1e-14 quantiles.
constexpr double kScaleTail = 1e-14;

double NormalCdf(double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); }

double NormalPdf(double z) { return std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi); }

// P(range of k standard normals <= q): k * integral phi(z) (Phi(z) - Phi(z - q))^(k-1) dz.
double NormalRangeCdf(double q, int k) {
  if (q <= 0.0) return 0.0;
  const auto integrand = [q, k](double z) {
    return NormalPdf(z) * std::pow(NormalCdf(z) - NormalCdf(z - q), k - 1);
  };
  const double integral =
      Quadrature::integrate(integrand, -kNormalSupport, kNormalSupport, kMaxDepth, kInnerTolerance);
  return std::clamp(k * integral, 0.0, 1.0);
}

void CheckTreatments(int treatments) {
  if (treatments < 2) {
    throw Error(
        fmt::format("the studentized range needs at least 2 treatments, got {}", treatments));
  }
}

}  // namespace

std::vector<double> MidRanks(std::span<const double> scores) {
  std::vector<int> order(scores.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return scores[a] < scores[b]; });
  std::vector<double> ranks(scores.size());
  for (std::size_t first = 0; first < order.size();) {
    std::size_t last = first + 1;
    while (last < order.size() && scores[order[last]] == scores[order[first]]) ++last;
    // Positions first..last-1 hold ranks first+1..last: their mean.
    const double mid_rank = 0.5 * static_cast<double>(first + 1 + last);
    for (std::size_t i = first; i < last; ++i) ranks[order[i]] = mid_rank;
    first = last;
  }
  return ranks;
}

double ImanDavenportStatistic(double chi_square, int blocks, int treatments) {
  const double n = blocks, k = treatments;
  const double denominator = n * (k - 1) - chi_square;
  // Every block ranking alike makes chi_square = n (k - 1) exactly, up to rounding.
  if (denominator <= 1e-12 * n * (k - 1)) return std::numeric_limits<double>::infinity();
  return (n - 1) * chi_square / denominator;
}

FriedmanTest Friedman(const Eigen::MatrixXd& scores) {
  const auto n = static_cast<int>(scores.rows());
  const auto k = static_cast<int>(scores.cols());
  if (n < 2 || k < 2) {
    throw Error(fmt::format(
        "the Friedman test needs at least 2 blocks and 2 treatments, got {} and {}", n, k));
  }
  FriedmanTest test;
  test.blocks = n;
  test.treatments = k;
  test.degrees_of_freedom = k - 1;
  std::vector<double> rank_sums(k, 0.0);
  double tie_sum = 0.0;  // sum over blocks and tie groups of t^3 - t
  std::vector<double> row(k);
  for (int b = 0; b < n; ++b) {
    for (int j = 0; j < k; ++j) {
      row[j] = scores(b, j);
      if (!std::isfinite(row[j])) {
        throw Error(fmt::format("block {}, treatment {}: score {} is not finite", b, j, row[j]));
      }
    }
    const std::vector<double> ranks = MidRanks(row);
    for (int j = 0; j < k; ++j) rank_sums[j] += ranks[j];
    std::sort(row.begin(), row.end());
    for (int first = 0; first < k;) {
      int last = first + 1;
      while (last < k && row[last] == row[first]) ++last;
      const double t = last - first;
      tie_sum += t * t * t - t;
      first = last;
    }
  }
  double sum_of_squares = 0.0;
  for (int j = 0; j < k; ++j) {
    test.mean_ranks.push_back(rank_sums[j] / n);
    sum_of_squares += rank_sums[j] * rank_sums[j];
  }
  const double nd = n, kd = k;
  test.chi_square_without_tie_correction =
      std::max(0.0, 12.0 / (nd * kd * (kd + 1)) * sum_of_squares - 3.0 * nd * (kd + 1));
  const double tie_correction = 1.0 - tie_sum / (nd * (kd * kd * kd - kd));
  if (tie_correction <= 1e-12) return test;  // every block ties every treatment: no evidence
  test.chi_square = test.chi_square_without_tie_correction / tie_correction;
  namespace bm = boost::math;
  test.p_value = bm::cdf(bm::complement(bm::chi_squared(kd - 1), test.chi_square));
  test.kendalls_w = std::min(1.0, test.chi_square / (nd * (kd - 1)));
  test.iman_davenport_f = ImanDavenportStatistic(test.chi_square, n, k);
  test.iman_davenport_p_value =
      std::isinf(test.iman_davenport_f)
          ? 0.0
          : bm::cdf(
                bm::complement(bm::fisher_f(kd - 1, (kd - 1) * (nd - 1)), test.iman_davenport_f));
  return test;
}

double StudentizedRangeCdf(double q, int treatments, double degrees_of_freedom) {
  CheckTreatments(treatments);
  if (!(degrees_of_freedom > 0.0)) {
    throw Error(fmt::format("the studentized range needs positive degrees of freedom, got {}",
                            degrees_of_freedom));
  }
  if (q <= 0.0) return 0.0;
  if (std::isinf(degrees_of_freedom)) return NormalRangeCdf(q, treatments);
  // Average the range's CDF at q s over the density of s = sqrt(X / df), X ~ chi2(df):
  // g(s) = 2 (df/2)^(df/2) / Gamma(df/2) s^(df-1) exp(-df s^2 / 2).
  const double df = degrees_of_freedom;
  const double log_constant = std::log(2.0) + 0.5 * df * std::log(0.5 * df) - std::lgamma(0.5 * df);
  const auto integrand = [&](double s) {
    if (s <= 0.0) return 0.0;
    const double density = std::exp(log_constant + (df - 1) * std::log(s) - 0.5 * df * s * s);
    return density * NormalRangeCdf(q * s, treatments);
  };
  namespace bm = boost::math;
  const bm::chi_squared scale(df);
  const double low = std::sqrt(bm::quantile(scale, kScaleTail) / df);
  const double high = std::sqrt(bm::quantile(bm::complement(scale, kScaleTail)) / df);
  const double integral = Quadrature::integrate(integrand, low, high, kMaxDepth, kOuterTolerance);
  return std::clamp(integral, 0.0, 1.0);
}

double StudentizedRangeQuantile(double probability, int treatments, double degrees_of_freedom) {
  CheckTreatments(treatments);
  if (!(probability > 0.0 && probability < 1.0)) {
    throw Error(fmt::format("a studentized range quantile needs 0 < p < 1, got {}", probability));
  }
  const auto excess = [&](double q) {
    return StudentizedRangeCdf(q, treatments, degrees_of_freedom) - probability;
  };
  double high = 8.0;
  while (excess(high) < 0.0) high *= 2.0;
  std::uintmax_t iterations = 100;
  const auto [a, b] =
      boost::math::tools::toms748_solve(excess, 0.0, high, -probability, excess(high),
                                        boost::math::tools::eps_tolerance<double>(40), iterations);
  return 0.5 * (a + b);
}

double NemenyiStandardError(int treatments, int blocks) {
  const double k = treatments, n = blocks;
  return std::sqrt(k * (k + 1) / (6.0 * n));
}

double NemenyiCriticalDifference(int treatments, int blocks, double alpha) {
  const double q_alpha = StudentizedRangeQuantile(1.0 - alpha, treatments) / std::numbers::sqrt2;
  return q_alpha * NemenyiStandardError(treatments, blocks);
}

Eigen::MatrixXd NemenyiPValues(std::span<const double> mean_ranks, int blocks) {
  const auto k = static_cast<int>(mean_ranks.size());
  CheckTreatments(k);
  const double standard_error = NemenyiStandardError(k, blocks);
  Eigen::MatrixXd p = Eigen::MatrixXd::Ones(k, k);
  for (int i = 0; i < k; ++i) {
    for (int j = i + 1; j < k; ++j) {
      const double q =
          std::numbers::sqrt2 * std::abs(mean_ranks[i] - mean_ranks[j]) / standard_error;
      p(i, j) = p(j, i) = 1.0 - StudentizedRangeCdf(q, k);
    }
  }
  return p;
}

}  // namespace photomat
