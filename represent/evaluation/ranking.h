#pragma once

#include <Eigen/Core>
#include <limits>
#include <span>
#include <vector>

namespace photomat {

// Rank statistics for comparing several treatments (methods) over the same blocks (images): the
// Friedman test with its tie correction, Kendall's coefficient of concordance, the Iman-Davenport
// F form, and the Nemenyi post-hoc comparison of every pair through the studentized range
// distribution (Demsar 2006, "Statistical comparisons of classifiers over multiple data sets";
// Hollander & Wolfe, "Nonparametric statistical methods", ch. 7).

// The ranks of `scores` within one block, lowest score = rank 1; tied scores share the mean of the
// ranks they span (mid-ranks), so that every block's ranks sum to k (k + 1) / 2.
std::vector<double> MidRanks(std::span<const double> scores);

struct FriedmanTest {
  int blocks = 0;      // n: rows of the score matrix (images)
  int treatments = 0;  // k: columns (methods)
  // Per treatment: the mean over blocks of its mid-rank (1 = best, lowest score).
  std::vector<double> mean_ranks;
  // The tie-corrected Friedman statistic (as R's friedman.test and Hollander & Wolfe's S'):
  // 12 / (n k (k + 1)) sum_j R_j^2 - 3 n (k + 1), divided by 1 - sum(t^3 - t) / (n (k^3 - k)) over
  // every group of t tied scores in a block. Chi-square with k - 1 degrees of freedom under the
  // null hypothesis that every treatment is as good.
  double chi_square = 0.0;
  // The same without the tie correction (the formula Demsar 2006 prints); equal without ties.
  double chi_square_without_tie_correction = 0.0;
  int degrees_of_freedom = 0;  // k - 1
  double p_value = 1.0;        // upper tail of chi-square(k - 1) at chi_square
  // Kendall's W = chi_square / (n (k - 1)), in [0, 1]: 1 when every block ranks alike.
  double kendalls_w = 0.0;
  // Iman and Davenport's F = (n - 1) chi_square / (n (k - 1) - chi_square), F-distributed with
  // k - 1 and (k - 1)(n - 1) degrees of freedom; less conservative than chi-square. Infinite (p 0)
  // when every block ranks alike.
  double iman_davenport_f = 0.0;
  double iman_davenport_p_value = 1.0;
};

// The Friedman test of `scores` (rows: blocks, columns: treatments; lower is better). Needs at
// least 2 blocks and 2 treatments and finite scores (throws Error naming the block and treatment).
// IMPLEMENTER CHOICE: when every block ties every treatment the statistic is 0/0; it is reported
// as 0 with p = 1 and W = 0 (no evidence of any difference), not as NaN.
FriedmanTest Friedman(const Eigen::MatrixXd& scores);

// Iman and Davenport's F from a Friedman chi-square over n blocks and k treatments.
double ImanDavenportStatistic(double chi_square, int blocks, int treatments);

// P(Q <= q) for the studentized range Q of `treatments` independent standard normal values, with
// an independent scale estimate on `degrees_of_freedom` (infinity: known scale, the Nemenyi case).
// Boost has no ptukey: the range's CDF is k * integral phi(z) (Phi(z) - Phi(z - q))^(k-1) dz, and
// for finite degrees of freedom that is averaged over the distribution of s = sqrt(chi2_df / df),
// both by adaptive Gauss-Kronrod quadrature (absolute error about 1e-9).
double StudentizedRangeCdf(double q, int treatments,
                           double degrees_of_freedom = std::numeric_limits<double>::infinity());

// The q with StudentizedRangeCdf(q, ...) = probability (R's qtukey), by bracketing root finding.
double StudentizedRangeQuantile(
    double probability, int treatments,
    double degrees_of_freedom = std::numeric_limits<double>::infinity());

// The Nemenyi test's standard error of a difference of mean ranks: sqrt(k (k + 1) / (6 n)).
double NemenyiStandardError(int treatments, int blocks);

// Demsar's critical difference: two treatments whose mean ranks differ by at least this much differ
// at level alpha (q_alpha / sqrt 2 times the standard error, q_alpha the studentized range's
// 1 - alpha quantile with infinite degrees of freedom).
double NemenyiCriticalDifference(int treatments, int blocks, double alpha = 0.05);

// The Nemenyi p-value of every pair (symmetric, ones on the diagonal): the studentized range's
// upper tail at sqrt 2 |R_i - R_j| / standard error, i.e. already adjusted for the k (k - 1) / 2
// pairs. Computed as 1 - CDF: p-values below about 1e-9 are at the quadrature's resolution.
Eigen::MatrixXd NemenyiPValues(std::span<const double> mean_ranks, int blocks);

}  // namespace photomat
