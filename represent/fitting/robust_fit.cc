#include "represent/fitting/robust_fit.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <numeric>
#include <string>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/text_parsing.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/light_profile_fit.h"
#include "represent/fitting/observations.h"
#include "represent/model/hsh.h"
#include "represent/model/light_basis.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// Same limits as the least-squares fits (fit.cc): lights within about 1 degree of a plane.
constexpr double kGradientConditionLimit = 0.02;
constexpr double kBasisConditionLimit = 1e-6;
// Pixels per parallel task: enough work to amortise scheduling, small enough to balance 2 cores.
constexpr Eigen::Index kPixelGrain = 256;

double Median(std::vector<double>& values) {
  const std::size_t n = values.size();
  std::nth_element(values.begin(), values.begin() + n / 2, values.end());
  const double upper = values[n / 2];
  if (n % 2) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + n / 2));
}

// Weighted least squares b = argmin sum w_i (y_i - b.l_i)^2; false when the weighted lights do
// not span 3 directions.
bool SolveWeightedLambertian(const Eigen::Matrix3Xd& l, std::span<const double> y,
                             std::span<const double> w, Eigen::Vector3d& b) {
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (Eigen::Index i = 0; i < l.cols(); ++i) {
    if (w[i] <= 0.0) continue;
    const Eigen::Vector3d weighted = w[i] * l.col(i);
    a.noalias() += weighted * l.col(i).transpose();
    rhs += y[i] * weighted;
  }
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(a);
  // The weighted Gram matrix of unit vectors: reject when its smallest pivot is tiny next to the
  // largest (lights nearly coplanar after rejection).
  const auto d = ldlt.vectorD();
  if (ldlt.info() != Eigen::Success || d.minCoeff() <= 1e-6 * std::max(d.maxCoeff(), 1e-300)) {
    return false;
  }
  b = ldlt.solve(rhs);
  return b.allFinite();
}

// Weights of one pixel's observations (one entry per selected image).
struct PixelWeights {
  std::span<float> inlier;   // the final IRLS weights of the normal fit (0 outside the window)
  std::span<float> outlier;  // shared outlier weights of every observation
};

// The per-pixel robust Lambertian problem (see the header): y are the channel-sum intensities of
// the selected images, `measured` flags the usable ones. Returns the albedo-scaled normal (zero
// when the pixel has too few usable observations) and writes both weight vectors.
class PixelSolver {
 public:
  PixelSolver(const Eigen::Matrix3Xd& lights, const RobustFitOptions& options)
      : l_(lights),
        options_(options),
        scale_(options.loss_scale > 0.0 ? options.loss_scale : DefaultLossScale(options.loss)),
        n_(lights.cols()),
        window_(n_),
        active_(n_),
        w_(n_) {
    order_.reserve(n_);
    residuals_.reserve(n_);
  }

  Eigen::Vector3d Solve(std::span<const double> y, std::span<const std::uint8_t> measured,
                        const PixelWeights& out) {
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    if (!Start(y, measured, b)) {
      std::fill(out.inlier.begin(), out.inlier.end(), 0.0f);
      std::fill(out.outlier.begin(), out.outlier.end(), 0.0f);
      return b;
    }
    for (int iteration = 0; iteration < options_.max_iterations; ++iteration) {
      Reweight(y, window_, b);
      Eigen::Vector3d next;
      if (!SolveWeightedLambertian(l_, y, w_, next)) break;
      const double change = (next - b).norm();
      b = next;
      if (change <= 1e-7 * std::max(b.norm(), 1e-30)) break;
    }
    Reweight(y, window_, b);
    for (Eigen::Index i = 0; i < n_; ++i) out.inlier[i] = static_cast<float>(w_[i]);
    // The shared weights judge every measured observation against the robust model.
    for (Eigen::Index i = 0; i < n_; ++i) window_[i] = measured[i];
    Reweight(y, window_, b);
    for (Eigen::Index i = 0; i < n_; ++i) out.outlier[i] = static_cast<float>(w_[i]);
    return b;
  }

 private:
  // The rank window: the measured observations between the dark and bright rank quantiles of the
  // pixel (all measured ones if the window does not determine a normal); least squares on it.
  bool Start(std::span<const double> y, std::span<const std::uint8_t> measured,
             Eigen::Vector3d& b) {
    order_.clear();
    for (Eigen::Index i = 0; i < n_; ++i) {
      if (measured[i]) order_.push_back(static_cast<int>(i));
    }
    if (order_.size() < 3) return false;
    std::sort(order_.begin(), order_.end(), [&](int a, int c) { return y[a] < y[c]; });
    const auto count = static_cast<double>(order_.size());
    const auto first = static_cast<std::size_t>(std::floor(options_.dark_fraction * count));
    const auto last =
        order_.size() - static_cast<std::size_t>(std::floor(options_.bright_fraction * count));
    std::fill(window_.begin(), window_.end(), 0.0);
    for (std::size_t r = first; r < last; ++r) window_[order_[r]] = 1.0;
    if (last > first + 2 && SolveWeightedLambertian(l_, y, window_, b)) return true;
    for (int i : order_) window_[i] = 1.0;
    return SolveWeightedLambertian(l_, y, window_, b);
  }

  // IRLS weights of the observations in `window` under the model b: 0 in attached shadow, the
  // loss's weight of the residual over the robust scale of the window's residuals otherwise.
  void Reweight(std::span<const double> y, std::span<const double> window,
                const Eigen::Vector3d& b) {
    const double albedo = b.norm();
    residuals_.clear();
    for (Eigen::Index i = 0; i < n_; ++i) {
      const double shading = b.dot(l_.col(i));
      active_[i] = window[i] > 0.0 && shading >= options_.attached_shadow_cosine * albedo;
      w_[i] = y[i] - shading;  // the residual until the weights are known
      if (active_[i]) residuals_.push_back(std::abs(w_[i]));
    }
    if (residuals_.size() < 3) {
      for (Eigen::Index i = 0; i < n_; ++i) w_[i] = active_[i] ? 1.0 : 0.0;
      return;
    }
    const double sigma =
        std::max(1.4826 * Median(residuals_), options_.minimum_relative_scale * albedo);
    const double c = scale_ * std::max(sigma, 1e-30);
    for (Eigen::Index i = 0; i < n_; ++i) {
      w_[i] = active_[i] ? RobustWeight(options_.loss, w_[i] / c) : 0.0;
    }
  }

  const Eigen::Matrix3Xd& l_;
  const RobustFitOptions& options_;
  double scale_;
  Eigen::Index n_;
  std::vector<double> window_;
  std::vector<std::uint8_t> active_;
  std::vector<double> w_;
  std::vector<int> order_;
  std::vector<double> residuals_;
};

constexpr std::array<NamedValue<RobustLoss>, 3> kLossNames = {{{RobustLoss::kHuber, "huber"},
                                                               {RobustLoss::kCauchy, "cauchy"},
                                                               {RobustLoss::kTukey, "tukey"}}};

}  // namespace

std::string_view ToString(RobustLoss loss) { return NameOf(loss, kLossNames); }

std::optional<RobustLoss> ParseRobustLoss(std::string_view name) {
  return FindValueNamed(ToLower(name), kLossNames);
}

double DefaultLossScale(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::kHuber:
      return 1.345;
    case RobustLoss::kTukey:
      return 4.685;
    case RobustLoss::kCauchy:
      break;
  }
  return 2.385;
}

double RobustWeight(RobustLoss loss, double u) {
  const double a = std::abs(u);
  switch (loss) {
    case RobustLoss::kHuber:
      return a <= 1.0 ? 1.0 : 1.0 / a;
    case RobustLoss::kTukey: {
      if (a >= 1.0) return 0.0;
      const double t = 1.0 - a * a;
      return t * t;
    }
    case RobustLoss::kCauchy:
      break;
  }
  return 1.0 / (1.0 + a * a);
}

nlohmann::json RobustFitOptions::ToJson() const {
  return {{"loss", std::string(ToString(loss))},
          {"loss_scale", loss_scale > 0.0 ? loss_scale : DefaultLossScale(loss)},
          {"dark_fraction", dark_fraction},
          {"bright_fraction", bright_fraction},
          {"attached_shadow_cosine", attached_shadow_cosine},
          {"minimum_relative_scale", minimum_relative_scale},
          {"max_iterations", max_iterations},
          {"measured_masks", !measured.empty()}};
}

void RobustFitSummary::Add(const RobustFitSummary& other) {
  const auto mine = static_cast<double>(observations);
  const auto theirs = static_cast<double>(other.observations);
  const double total = std::max(mine + theirs, 1.0);
  mean_weight = (mean_weight * mine + other.mean_weight * theirs) / total;
  normal_inlier_fraction =
      (normal_inlier_fraction * mine + other.normal_inlier_fraction * theirs) / total;
  observations += other.observations;
  not_measured += other.not_measured;
  attached_shadow += other.attached_shadow;
  down_weighted += other.down_weighted;
}

RobustFitSummary RobustFitSummary::FromJson(const nlohmann::json& json) {
  RobustFitSummary summary;
  summary.observations = json.at("observations").get<std::size_t>();
  summary.not_measured = json.at("not_measured").get<std::size_t>();
  summary.attached_shadow = json.at("attached_shadow").get<std::size_t>();
  summary.down_weighted = json.at("down_weighted").get<std::size_t>();
  summary.mean_weight = json.at("mean_weight").get<double>();
  summary.normal_inlier_fraction = json.at("normal_inlier_fraction").get<double>();
  return summary;
}

nlohmann::json RobustFitSummary::ToJson() const {
  return {{"observations", observations},       {"not_measured", not_measured},
          {"attached_shadow", attached_shadow}, {"down_weighted", down_weighted},
          {"mean_weight", mean_weight},         {"normal_inlier_fraction", normal_inlier_fraction}};
}

namespace {

void CheckRobustFitInputs(const Observations& observations,
                          const std::vector<LightDirection>& lights, std::size_t selected,
                          const RobustFitOptions& options, const fs::path& source) {
  const int n_all = observations.images();
  if (selected < 3) {
    throw Error(source, fmt::format("robust fit needs at least 3 images; {} given", selected));
  }
  if (static_cast<int>(lights.size()) != n_all) {
    throw Error(source, fmt::format("{} lights for {} images", lights.size(), n_all));
  }
  if (options.measured.empty()) return;
  if (static_cast<int>(options.measured.size()) != n_all) {
    throw Error(source, fmt::format("{} measured-pixel masks for {} images",
                                    options.measured.size(), n_all));
  }
  for (const Mask& mask : options.measured) {
    if (mask.width() != observations.width() || mask.height() != observations.height()) {
      throw Error(source, fmt::format("a measured-pixel mask is {}x{} but the images are {}x{}",
                                      mask.width(), mask.height(), observations.width(),
                                      observations.height()));
    }
  }
}

// The selected lights as columns; an error when they lie near one plane.
Eigen::Matrix3Xd IndependentLightMatrix(const std::vector<LightDirection>& lights,
                                        std::span<const int> selected, const fs::path& source) {
  const Eigen::Matrix3Xd l = LightMatrix(lights, selected);
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> svd(l);
  const Eigen::Vector3d s = svd.singularValues();
  if (s[2] < kGradientConditionLimit * s[0]) {
    throw Error(source, fmt::format("robust fit: the {} lights are coplanar (singular values "
                                    "{:.3g}, {:.3g}, {:.3g}); photometric stereo needs lights "
                                    "in three independent directions",
                                    selected.size(), s[0], s[1], s[2]));
  }
  return l;
}

// What the pixels' robust fits found, counted per thread and added at the end.
struct RobustTally {
  std::size_t not_measured = 0, attached = 0, down = 0, inliers = 0;
  void Add(const RobustTally& other) {
    not_measured += other.not_measured;
    attached += other.attached;
    down += other.down;
    inliers += other.inliers;
  }
};

// One thread's solver and per-pixel buffers (n selected observations).
struct RobustPixelWork {
  RobustPixelWork(const Eigen::Matrix3Xd& l, const RobustFitOptions& options)
      : solver(l, options),
        y(static_cast<std::size_t>(l.cols())),
        measured(static_cast<std::size_t>(l.cols())),
        inlier(static_cast<std::size_t>(l.cols())),
        outlier(static_cast<std::size_t>(l.cols())) {}
  PixelSolver solver;
  std::vector<double> y;
  std::vector<std::uint8_t> measured;
  std::vector<float> inlier, outlier;
};

// Where the robust fit of the pixels goes: column k of each is pixel k's.
struct RobustPixelMaps {
  Eigen::Matrix3Xf& normals;
  Eigen::MatrixXf& albedo;
  Eigen::MatrixXf& weights;  // pixels x all images; the selected images' columns are written
};

// Pixel k: the robust normal from the channels' sum, the albedo per channel along it from the
// normal's inliers, and each selected observation's weight; counted in `tally`. Returns the sum of
// the pixel's weights.
double FitRobustPixel(const Observations& observations, std::span<const int> selected,
                      const RobustFitOptions& options, const Eigen::Matrix3Xd& l, Eigen::Index k,
                      RobustPixelWork& work, RobustPixelMaps maps, RobustTally& tally) {
  const Eigen::Index m = observations.pixels();
  const auto n = static_cast<Eigen::Index>(selected.size());
  const int channels = observations.channels();
  const Eigen::MatrixXf& matrix = observations.matrix();
  const std::size_t pixel = observations.pixel_indices()[k];
  for (Eigen::Index i = 0; i < n; ++i) {
    const int image = selected[i];
    double sum = 0.0;
    for (int c = 0; c < channels; ++c) sum += matrix(c * m + k, image);
    work.y[i] = sum;
    work.measured[i] = options.measured.empty() || options.measured[image][pixel];
  }
  const Eigen::Vector3d b = work.solver.Solve(work.y, work.measured, {work.inlier, work.outlier});
  const double norm = b.norm();
  const Eigen::Vector3d normal = norm > 0.0 ? (b / norm).eval() : Eigen::Vector3d::UnitZ();
  maps.normals.col(k) = normal.cast<float>();
  for (int c = 0; c < channels; ++c) {
    double numerator = 0.0, denominator = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      if (work.inlier[i] <= 0.0f) continue;
      const double shading = normal.dot(l.col(i));
      numerator += work.inlier[i] * matrix(c * m + k, selected[i]) * shading;
      denominator += work.inlier[i] * shading * shading;
    }
    maps.albedo(c, k) = denominator > 0.0 ? static_cast<float>(numerator / denominator) : 0.0f;
  }
  double weight_sum = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    maps.weights(k, selected[i]) = work.outlier[i];
    weight_sum += work.outlier[i];
    if (work.inlier[i] > 0.0f) ++tally.inliers;
    if (!work.measured[i]) {
      ++tally.not_measured;
    } else if (normal.dot(l.col(i)) < options.attached_shadow_cosine) {
      ++tally.attached;
    } else if (work.outlier[i] < 0.5f) {
      ++tally.down;
    }
  }
  return weight_sum;
}

RobustFitSummary SummaryOf(const RobustTally& total, double weight_sum, std::size_t observations) {
  RobustFitSummary summary;
  summary.observations = observations;
  summary.not_measured = total.not_measured;
  summary.attached_shadow = total.attached;
  summary.down_weighted = total.down;
  const auto count = static_cast<double>(std::max<std::size_t>(observations, 1));
  summary.mean_weight = weight_sum / count;
  summary.normal_inlier_fraction = static_cast<double>(total.inliers) / count;
  return summary;
}

}  // namespace

RobustFit::RobustFit(const Observations& observations, const std::vector<LightDirection>& lights,
                     std::span<const int> selected, const RobustFitOptions& options,
                     fs::path source)
    : observations_(observations),
      lights_(lights),
      selected_(selected.begin(), selected.end()),
      options_(options),
      source_(std::move(source)) {
  CheckRobustFitInputs(observations, lights, selected_.size(), options_, source_);
  const Eigen::Matrix3Xd l = IndependentLightMatrix(lights, selected_, source_);
  const Eigen::Index m = observations.pixels();
  weights_ = Eigen::MatrixXf::Zero(m, observations.images());
  normals_ = Eigen::Matrix3Xf::Zero(3, m);
  albedo_ = Eigen::MatrixXf::Zero(observations.channels(), m);
  NullProgress no_progress;
  Progress& progress = OrNull(options_.progress, no_progress);
  progress.Start("robust fit", static_cast<std::size_t>((m + kPixelGrain - 1) / kPixelGrain));
  tbb::enumerable_thread_specific<RobustTally> tallies;
  // Each pixel's sum of weights, added in pixel order after the loop: a sum in the threads'
  // tallies would depend on how the scheduler split the pixels (the summary's last digits would
  // differ from run to run).
  std::vector<double> weight_sums(static_cast<std::size_t>(m));
  tbb::enumerable_thread_specific<RobustPixelWork> works(
      [&] { return RobustPixelWork(l, options_); });
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, m, kPixelGrain),
                    [&](const tbb::blocked_range<Eigen::Index>& range) {
                      RobustPixelWork& work = works.local();
                      RobustTally& tally = tallies.local();
                      for (Eigen::Index k = range.begin(); k < range.end(); ++k) {
                        weight_sums[static_cast<std::size_t>(k)] =
                            FitRobustPixel(observations, selected_, options_, l, k, work,
                                           {normals_, albedo_, weights_}, tally);
                      }
                      progress.Advance();
                    });
  progress.Finish();
  RobustTally total;
  for (const RobustTally& tally : tallies) total.Add(tally);
  summary_ = SummaryOf(total, std::accumulate(weight_sums.begin(), weight_sums.end(), 0.0),
                       static_cast<std::size_t>(m) * selected_.size());
}

Representation RobustFit::Fit(const Method& method) const {
  switch (method.kind) {
    case Method::Kind::kThreeImage:
      break;
    case Method::Kind::kGradient:
      return FitGradient();
    case Method::Kind::kPtm:
      return FitPtm(false);
    case Method::Kind::kPtmLrgb:
      return FitPtm(true);
    case Method::Kind::kEigen:
      return FitEigen(method.eigen_k);
    case Method::Kind::kHsh:
      return FitHsh(method.hsh_terms);
    case Method::Kind::kRbf:
    case Method::Kind::kBilinear:
      return FitLightProfileMethod(method);
    case Method::Kind::kPbr:
      return FitPbr(observations_, lights_, options_.near_lighting, selected_, normals_, albedo_,
                    options_.measured, options_.pbr,
                    {{"robust", options_.ToJson()}, {"robust_summary", summary_.ToJson()}}, source_,
                    options_.progress);
    case Method::Kind::kNeural:
      throw Error(source_, NeuralIsTrainedApart());
  }
  return FitObservations(observations_, lights_, method, selected_, source_);
}

Representation RobustFit::FitGradient() const {
  const Eigen::Index m = observations_.pixels();
  const int channels = observations_.channels();
  std::vector<std::string> names = {"normal.X", "normal.Y", "normal.Z"};
  for (const auto& c : OutputChannelNames(channels)) names.push_back("albedo." + c);
  Image maps(observations_.width(), observations_.height(), names);
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index k) {
    const auto pixel = maps.pixel(observations_.pixel_indices()[k]);
    for (int i = 0; i < 3; ++i) pixel[i] = normals_(i, k);
    for (int c = 0; c < channels; ++c) pixel[3 + c] = albedo_(c, k);
  });
  return Representation("gradient", std::move(maps), {3, false, true, channels},
                        LinearLightBasis::Lambertian(),
                        {{"robust", options_.ToJson()}, {"robust_summary", summary_.ToJson()}});
}

Representation RobustFit::FitPtm(bool lrgb) const {
  return FitBasisTerms(std::make_shared<PtmLightBasis>(), lrgb ? "ptm-lrgb" : "ptm", "ptm.a", lrgb);
}

Representation RobustFit::FitHsh(int terms) const {
  return FitBasisTerms(std::make_shared<HshLightBasis>(terms), fmt::format("hsh{}", terms), "hsh.h",
                       false);
}

Representation RobustFit::FitBasisTerms(std::shared_ptr<const LightBasis> basis,
                                        const std::string& method, const std::string& prefix,
                                        bool lrgb) const {
  const int size = basis->size();
  Eigen::MatrixXd terms(size, static_cast<Eigen::Index>(selected_.size()));  // size x n
  for (std::size_t i = 0; i < selected_.size(); ++i) {
    terms.col(static_cast<Eigen::Index>(i)) = basis->Coefficients(lights_[selected_[i]]);
  }
  {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(terms);
    const Eigen::VectorXd s = svd.singularValues();
    if (s.size() < size || s[size - 1] < kBasisConditionLimit * s[0]) {
      throw Error(source_, fmt::format("{}: the {} lights do not determine the {} coefficients; "
                                       "add lights at other slants",
                                       method, selected_.size(), size));
    }
  }
  const Eigen::Index m = observations_.pixels();
  const auto n = static_cast<Eigen::Index>(selected_.size());
  const int channels = observations_.channels();
  const int fitted = lrgb ? 1 : channels;  // polynomials per pixel
  const auto channel_names = OutputChannelNames(channels);
  std::vector<std::string> names;
  if (lrgb) {
    for (int j = 0; j < size; ++j) names.push_back(fmt::format("{}{}", prefix, j));
    for (const auto& c : channel_names) names.push_back("rgb." + c);
  } else {
    names = CoefficientMapNames(prefix, size, channel_names);
  }
  Image maps(observations_.width(), observations_.height(), names);
  const Eigen::MatrixXf& matrix = observations_.matrix();
  // The unweighted normal matrix: the fallback for a pixel whose weights leave too few
  // observations to determine the coefficients.
  const Eigen::MatrixXd unweighted = terms * terms.transpose();
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index k) {
    Eigen::VectorXd w(n);
    int used = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      w[i] = weights_(k, selected_[i]);
      if (w[i] > 0.0) ++used;
    }
    const Eigen::MatrixXd a = terms * w.asDiagonal() * terms.transpose();
    Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
    const bool usable = used >= size + 2 && ldlt.info() == Eigen::Success &&
                        ldlt.vectorD().minCoeff() > 1e-6 * ldlt.vectorD().maxCoeff();
    if (!usable) {
      w.setOnes();
      ldlt.compute(unweighted);
    }
    // Values to fit: each channel, or (LRGB) the channel mean.
    Eigen::MatrixXd values(n, fitted);
    for (Eigen::Index i = 0; i < n; ++i) {
      if (lrgb) {
        double sum = 0.0;
        for (int c = 0; c < channels; ++c) sum += matrix(c * m + k, selected_[i]);
        values(i, 0) = sum / channels;
      } else {
        for (int c = 0; c < channels; ++c) values(i, c) = matrix(c * m + k, selected_[i]);
      }
    }
    const Eigen::MatrixXd coefficients = ldlt.solve(terms * w.asDiagonal() * values);  // size x f
    const auto pixel = maps.pixel(observations_.pixel_indices()[k]);
    if (!lrgb) {
      for (int j = 0; j < size; ++j) {
        for (int c = 0; c < channels; ++c)
          pixel[j * channels + c] = static_cast<float>(coefficients(j, c));
      }
      return;
    }
    for (int j = 0; j < size; ++j) pixel[j] = static_cast<float>(coefficients(j, 0));
    const Eigen::VectorXd luminance = terms.transpose() * coefficients.col(0);  // at each light
    const double denominator = (w.array() * luminance.array().square()).sum();
    for (int c = 0; c < channels; ++c) {
      double numerator = 0.0;
      for (Eigen::Index i = 0; i < n; ++i) {
        numerator += w[i] * matrix(c * m + k, selected_[i]) * luminance[i];
      }
      pixel[size + c] = denominator > 0.0 ? static_cast<float>(numerator / denominator) : 0.0f;
    }
  });
  const MapLayout layout =
      lrgb ? MapLayout{size, false, true, channels} : MapLayout{size, true, false, channels};
  return Representation(method, std::move(maps), layout, std::move(basis),
                        {{"robust", options_.ToJson()}});
}

void RobustFit::EigenImpute(Eigen::MatrixXf& filled, const Eigen::MatrixXd& v) const {
  const Eigen::Index m = observations_.pixels();
  const auto n = static_cast<Eigen::Index>(selected_.size());
  const int channels = observations_.channels();
  const Eigen::MatrixXf& matrix = observations_.matrix();
  const Eigen::MatrixXf bases = ParallelProduct(filled, v.cast<float>());
  const Eigen::MatrixXf vt = v.transpose().cast<float>();
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index p) {
    for (int c = 0; c < channels; ++c) {
      const Eigen::Index row = c * m + p;
      const Eigen::RowVectorXf model = bases.row(row) * vt;
      for (Eigen::Index i = 0; i < n; ++i) {
        const float w = weights_(p, selected_[i]);
        filled(row, i) = w * matrix(row, selected_[i]) + (1.0f - w) * model[i];
      }
    }
  });
}

Representation RobustFit::EigenFromImputed(const Eigen::MatrixXf& filled,
                                           const EigenBasis& basis) const {
  const Eigen::MatrixXf bases = ParallelProduct(filled, basis.v.cast<float>());
  return EigenRepresentation(observations_, bases, lights_, selected_, basis,
                             {{"robust", options_.ToJson()}});
}

Representation RobustFit::FitEigen(int k) const {
  const auto n = static_cast<Eigen::Index>(selected_.size());
  if (k < 1 || k > n) {
    throw Error(source_, fmt::format("eigen{} needs at least {} images; {} given", k, k, n));
  }
  std::vector<int> columns(static_cast<std::size_t>(n));
  std::iota(columns.begin(), columns.end(), 0);
  Eigen::MatrixXf filled = EigenStart();
  for (int iteration = 0;; ++iteration) {
    RowGram gram(n);
    gram.Add(filled, observations_.pixel_indices(), observations_.width(),
             observations_.channels());
    const EigenBasis basis =
        EigenBasisFromGram(gram.gram(), gram.column_sums(), columns, k, source_);
    if (iteration == kRobustEigenIterations) return EigenFromImputed(filled, basis);
    EigenImpute(filled, basis.v);
  }
}

Eigen::MatrixXf RobustFit::EigenStart() const {
  const Eigen::Index m = observations_.pixels();
  const auto n = static_cast<Eigen::Index>(selected_.size());
  const int channels = observations_.channels();
  const Eigen::MatrixXf& matrix = observations_.matrix();
  Eigen::MatrixXf filled(matrix.rows(), n);
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index p) {
    const Eigen::Vector3f normal = normals_.col(p);
    for (Eigen::Index i = 0; i < n; ++i) {
      const float w = weights_(p, selected_[i]);
      const float shading =
          std::max(0.0f, normal.dot(lights_[selected_[i]].vector().cast<float>()));
      for (int c = 0; c < channels; ++c) {
        filled(c * m + p, i) =
            w * matrix(c * m + p, selected_[i]) + (1.0f - w) * albedo_(c, p) * shading;
      }
    }
  });
  return filled;
}

Representation RobustFit::FitLightProfileMethod(const Method& method) const {
  const Eigen::MatrixXf filled = EigenStart();
  std::vector<int> columns(filled.cols());
  std::iota(columns.begin(), columns.end(), 0);
  const std::vector<LightDirection> selected_lights = SelectLights(lights_, selected_);
  // RowGram: the same sums for any band height, as the streamed fit's.
  RowGram gram(filled.cols());
  gram.Add(filled, observations_.pixel_indices(), observations_.width(), observations_.channels());
  return ProjectLightProfiles(
      FitLightProfileModel(gram.gram(), gram.column_sums(), selected_lights, method, source_,
                           {{"robust", options_.ToJson()}}),
      observations_, filled, columns);
}

Representation FitRobust(const PhotometricSet& set, const Method& method,
                         const RobustFitOptions& options) {
  std::vector<int> all(set.size());
  std::iota(all.begin(), all.end(), 0);
  const Observations observations(set);
  RobustFitOptions with_lamps = options;
  if (!with_lamps.near_lighting && set.near_lighting()) {
    with_lamps.near_lighting = &*set.near_lighting();
  }
  const RobustFit fit(observations, set.lights(), all, with_lamps, set.source());
  return fit.Fit(method);
}

}  // namespace photomat
