#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

#include "core/light_direction.h"
#include "represent/fitting/observations.h"
#include "represent/model/light_basis.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"

namespace photomat {

// The fits of the light-profile methods `rbf` and `bilinear`
// (represent/model/light_profile_basis.h, README "RBF and bilinear").

// What the fits choose among by their leave-out score where the options fix nothing
// (IMPLEMENTER CHOICE, README "RBF and bilinear"): rbf kernel widths as factors of
// MedianNearestNeighbourDegrees of the fitted lights (half-octave steps from 1/4 to 4), rbf
// regularisations and bilinear smoothnesses (decades).
inline constexpr std::array<double, 9> kRbfWidthFactors = {0.25,   0.3536, 0.5,    0.7071, 1.0,
                                                           1.4142, 2.0,    2.8284, 4.0};
inline constexpr std::array<double, 7> kRbfRegularisations = {0.0,  1e-5, 1e-4, 1e-3,
                                                              1e-2, 1e-1, 1.0};
inline constexpr std::array<double, 6> kBilinearSmoothnesses = {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0};

// The median over `lights` of the angle in degrees from a light to its nearest other light: the
// scale of the rbf kernel widths.
double MedianNearestNeighbourDegrees(const std::vector<LightDirection>& lights);

// Leave-out scores over the capture of a whole light-profile fit, interpolation and PCA together,
// from the Gram matrix G = P^T P of the fitted profiles alone (no pass over the pixels). A fold
// leaves out a set H of lights (LeaveOut::kOne: one light; kBlock: every kBlockStride-th light
// from an offset, so kBlockStride folds, as a held-out test leaves lights out): its PCA axes V are
// the eigenvectors of G over the other lights O (the left-out values must not shape the axes that
// predict them), and the interpolation's weights w_h over O (the fit on O alone, evaluated at
// light h) predict light h as p_O^T V V^T w_h. With the fold's eigenvalues s_j, the error of h
// summed over every profile row with k planes is
//   G_hh + sum_{j <= k} (s_j a_j^2 - 2 a_j b_j),   a = V^T w_h, b = V^T G_{O,h},
// so one eigen-decomposition per fold serves every k and every interpolation candidate.
class LeaveOutFolds {
 public:
  // kOne: folds over every light, or over every ceil(n / kMaxFolds)-th light of larger captures.
  static constexpr int kMaxFolds = 128;
  // kBlock (IMPLEMENTER CHOICE): every 8th light at once, as the held-out benchmark holds out.
  static constexpr int kBlockStride = 8;
  // kEdge: one fold per light of HullBoundaryLights(lights); kSide: one fold per side of
  // HullSideLights(lights). `lights` are the Gram matrix's.
  LeaveOutFolds(const Eigen::MatrixXd& gram, LeaveOut scheme,
                const std::vector<LightDirection>& lights);

  struct Fold {
    std::vector<int> held_out;    // H
    std::vector<int> others;      // O, increasing
    Eigen::MatrixXd axes;         // |O| x |O|, by decreasing eigenvalue
    Eigen::VectorXd eigenvalues;  // decreasing
    Eigen::MatrixXd cross;        // axes^T G_{O,H}, |O| x |H|
  };
  const std::vector<Fold>& folds() const { return folds_; }
  LeaveOut scheme() const { return scheme_; }

  // Per plane count, entry k - 1 for k = 1..m, m the smallest |O| of a fold (k = m: every axis
  // of each fold, no PCA):
  //  - relative_error: sqrt(the error summed over the left-out lights / their G_hh);
  //  - mean_snr_db: the mean over the left-out lights of 10 log10(G_hh / error_h), the left-out
  //    images' signal-to-error ratio in dB. IMPLEMENTER CHOICE: the fits choose by this one, the
  //    mean of per-image decibels as the held-out benchmark's mean PSNR (with a fixed peak, PSNR
  //    and this differ by a constant per image); the summed error is dominated by the few hardest
  //    lights (on DiLiGenT ball, highlights), where more planes help, and chose 14 to 16 planes
  //    where most lights are predicted better by 4 to 6.
  // `weights(fold)` is |H| x |O|, row h the weights of left-out light h over the fold's others.
  // NaN throughout when a fold's weights are not finite or have the wrong size.
  struct Scores {
    Eigen::VectorXd relative_error;
    Eigen::VectorXd mean_snr_db;
  };
  using FoldWeights = std::function<Eigen::MatrixXd(const Fold&)>;
  Scores Score(const FoldWeights& weights) const;
  // Folds of one light (kOne, kEdge): `weights` n x n, row i the leave-one-out weights of light i
  // (Rippa's).
  Scores Score(const Eigen::MatrixXd& weights) const;
  // Per fold (in folds()' order), its |H| x |O| weights; NaN throughout for a wrong count.
  Scores Score(const std::vector<Eigen::MatrixXd>& weights) const;

 private:
  LeaveOut scheme_;
  Eigen::VectorXd diagonal_;
  std::vector<Fold> folds_;
  Eigen::Index plane_entries_ = 1;
};

// Each side of the lights' convex hull in (lx, ly): the lights within 0.02 of its edges, a side
// being consecutive hull edges that turn less than 45 degrees from its first (IMPLEMENTER CHOICE:
// a grid's four rows and columns of its border, corners in both; a whole side left out at once
// is predicted from the row one step inside, as lights one grid step beyond the captured ones).
std::vector<std::vector<int>> HullSideLights(const std::vector<LightDirection>& lights);

// The lights within 0.02 of the boundary of their convex hull in (lx, ly) (IMPLEMENTER CHOICE:
// the lights a new light beyond the captured ones is extrapolated from), in increasing order.
std::vector<int> HullBoundaryLights(const std::vector<LightDirection>& lights);

// The weights each fold of `folds` (over `lights`, the Gram matrix's) gives its left-out lights
// over its others (|H| x |O|, in folds.folds()' order) for an RBF candidate (Rippa's for folds of
// one light, else each fold's interpolation over its others) and for a bilinear smoothness (the
// penalised least squares' closed form, else each fold's resampling). Empty when the candidate
// cannot be solved. A linear blend of two candidates' weights is a predictor of the same folds.
std::vector<Eigen::MatrixXd> RbfFoldWeights(const LeaveOutFolds& folds,
                                            const std::vector<LightDirection>& lights, double width,
                                            double regularisation, RbfTail tail);
std::vector<Eigen::MatrixXd> BilinearFoldWeights(const LeaveOutFolds& folds,
                                                 const std::vector<LightDirection>& lights,
                                                 int grid_size, double smoothness);

// The plane counts a fit may take: options.planes > 0 that count, 0 every axis (n - 1 in a fold),
// kChoosePlanes 1..kMaxChosenPlanes; each capped at the n - 1 a fold has.
std::vector<int> CandidatePlanes(const LightProfileOptions& options, int lights);

// The RBF's kernel width, regularisation and tail and the PCA's plane count: the options' values
// where set, otherwise those of best score over the capture itself (LeaveOutFolds with
// options.leave_out; the interpolation's leave-one-out weights are Rippa's, e_i - B_i / B_ii with
// B the system inverse's n x n block; a block fold solves the interpolation without its lights).
// Candidates (IMPLEMENTER CHOICE): widths 0.25 .. 4 times the median angle from a light to its
// nearest neighbour (9 steps of sqrt 2), regularisation 0 and 1e-5 .. 1 (decades; the kernel
// matrix's diagonal is 1), CandidatePlanes; the tail is options.rbf_tail. `leave_one_out` lists
// every width and regularisation with its best plane count and scores.
struct RbfParameters {
  double width_degrees = 0.0;
  double regularisation = 0.0;
  RbfTail tail = RbfTail::kAffine;
  int planes = 0;  // as LightProfileOptions::planes: 0 no PCA
  double relative_error = 0.0;
  double mean_snr_db = 0.0;  // the choice's LeaveOutFolds score
  // [{"width_deg", "regularisation", "planes", "relative_error", "mean_snr_db"}...]
  nlohmann::json leave_one_out;
  // The chosen width and regularisation's relative error per plane count: [{"planes", ...}...]
  nlohmann::json by_planes;
};
RbfParameters ChooseRbfParameters(const std::vector<LightDirection>& lights,
                                  const Eigen::MatrixXd& gram, const LightProfileOptions& options,
                                  const std::filesystem::path& source = {});

// The bilinear grid's resampling: grid values g of a profile p minimise
//   sum_i (b(l_i) . g - p_i)^2 + smoothness * |D g|^2,
// b the bilinear weights, D the second differences of the grid along lx and along ly
// (IMPLEMENTER CHOICE: the data term makes the grid reproduce the captured lights, the curvature
// term fills cells no light falls in smoothly and extrapolates linearly; larger values smooth
// across the lights too). Returns R, G^2 x n, with g = R p.
inline constexpr double kBilinearSmoothness = 1e-4;
Eigen::MatrixXd BilinearResampling(const std::vector<LightDirection>& lights, int grid_size,
                                   double smoothness = kBilinearSmoothness);

// The bilinear fit's smoothness and plane count of best score (LeaveOutFolds with
// options.leave_out; the leave-one-out weights of a penalised least-squares fit are
// (H_i - H_ii e_i) / (1 - H_ii), H = b(L) R its hat matrix; a block fold resamples without its
// lights). Smoothness candidates (IMPLEMENTER CHOICE): options.
// bilinear_smoothness if set, else 1e-4 .. 10 (decades); planes: CandidatePlanes.
struct BilinearParameters {
  double smoothness = kBilinearSmoothness;
  int planes = 0;
  double relative_error = 0.0;
  double mean_snr_db = 0.0;
  // [{"smoothness", "planes", "relative_error", "mean_snr_db"}...]
  nlohmann::json leave_one_out;
  nlohmann::json by_planes;
};
BilinearParameters ChooseBilinearParameters(const std::vector<LightDirection>& lights,
                                            const Eigen::MatrixXd& gram,
                                            const LightProfileOptions& options,
                                            const std::filesystem::path& source = {});

// A light-profile fit's model: everything of it but the maps. It follows from the fitted profiles'
// Gram matrix and column sums alone (the kernel width and regularisation by leave-one-out, the
// PCA axes, each plane's sign), so a streamed fit finds it in one pass over the bands and then
// projects every band with it; the in-memory fit is the one-band case.
struct LightProfileModel {
  std::string method;                       // "rbf" or "bilinear"
  Eigen::MatrixXd projection;               // n x k: a profile's k plane coefficients
  std::shared_ptr<const LightBasis> basis;  // from the k planes to a light's value
  nlohmann::json details;
};

// The model of `method` (rbf or bilinear) for profiles over `lights` whose Gram matrix is `gram`
// (n x n) and column sums `column_sums` (n). `details` are kept and the fit's own added. Throws
// Error naming `source` for degenerate lights or options.
LightProfileModel FitLightProfileModel(const Eigen::MatrixXd& gram,
                                       const Eigen::VectorXd& column_sums,
                                       const std::vector<LightDirection>& lights,
                                       const Method& method,
                                       const std::filesystem::path& source = {},
                                       nlohmann::json details = nlohmann::json::object());

// The same for the profiles over the images `selected` of a Gram matrix and column sums of every
// image (`lights` every image's): the rows and columns `selected` picks (a prediction fold, or
// every image).
LightProfileModel FitLightProfileModel(const Eigen::MatrixXd& gram,
                                       const Eigen::VectorXd& column_sums,
                                       const std::vector<LightDirection>& lights,
                                       std::span<const int> selected, const Method& method,
                                       const std::filesystem::path& source = {});

// The maps of `model` for the columns `columns` of `matrix` (rows in `observations`' order; the
// observations' own matrix or an imputed copy; entry i of the model's profile is column
// columns[i]).
Representation ProjectLightProfiles(const LightProfileModel& model,
                                    const Observations& observations, const Eigen::MatrixXf& matrix,
                                    std::span<const int> columns);

}  // namespace photomat
