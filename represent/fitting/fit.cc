#include "represent/fitting/fit.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <string_view>

#include "core/error.h"
#include "represent/fitting/light_profile_fit.h"
#include "represent/fitting/robust_fit.h"
#include "represent/model/hsh.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// A lighting matrix whose smallest singular value is below this fraction of its largest is
// treated as rank deficient. For Gradient: lights within about 1 degree of one plane.
constexpr double kGradientConditionLimit = 0.02;
constexpr double kPtmConditionLimit = 1e-6;
constexpr double kHshConditionLimit = 1e-6;
// |det [l1 l2 l3]| of unit vectors; 0.05 rejects triples within about 3 degrees of a plane.
constexpr double kThreeImageDeterminantLimit = 0.05;

struct FitContext {
  const Observations& observations;
  const std::vector<LightDirection>& lights;
  std::span<const int> selected;
  const fs::path& source;

  [[noreturn]] void Fail(const std::string& fault) const { throw Error(source, fault); }
  std::vector<LightDirection> SelectedLights() const { return SelectLights(lights, selected); }
  Eigen::Index m() const { return observations.pixels(); }
  int channels() const { return observations.channels(); }
  // An N x d weight matrix that is `rows` (|S| x d) on the selected images and 0 elsewhere, so
  // that I * W fits from the selected images only.
  Eigen::MatrixXf Scatter(const Eigen::MatrixXd& rows) const {
    Eigen::MatrixXf full = Eigen::MatrixXf::Zero(observations.images(), rows.cols());
    for (std::size_t i = 0; i < selected.size(); ++i) {
      full.row(selected[i]) = rows.row(static_cast<Eigen::Index>(i)).cast<float>();
    }
    return full;
  }
  // A maps image with `names`; pixels outside the selection stay 0.
  Image NewMaps(std::vector<std::string> names) const {
    return Image(observations.width(), observations.height(), std::move(names));
  }
  std::size_t PixelIndex(Eigen::Index k) const { return observations.pixel_indices()[k]; }
};

void StorePerChannelTerms(const FitContext& fit, const Eigen::MatrixXf& terms, Image& maps) {
  photomat::StorePerChannelTerms(fit.observations, terms, maps);
}

Eigen::JacobiSVD<Eigen::MatrixXd> CheckedSvd(const Eigen::MatrixXd& matrix) {
  return Eigen::JacobiSVD<Eigen::MatrixXd>(matrix, Eigen::ComputeThinU | Eigen::ComputeThinV);
}

// Pseudo-inverse (transposed, |S| x d) of a d x |S| lighting matrix via its SVD (thesis 4.4.1).
Eigen::MatrixXd PseudoInverseTransposed(const Eigen::JacobiSVD<Eigen::MatrixXd>& svd) {
  const Eigen::VectorXd inverse = svd.singularValues().cwiseInverse();
  return svd.matrixV() * inverse.asDiagonal() * svd.matrixU().transpose();
}

Representation FitGradient(const FitContext& fit) {
  const auto lights = fit.SelectedLights();
  const Eigen::MatrixXd l = LightMatrix(lights);
  const auto svd = CheckedSvd(l);
  const Eigen::VectorXd s = svd.singularValues();
  if (s[2] < kGradientConditionLimit * s[0]) {
    fit.Fail(fmt::format(
        "gradient: the {} lights are coplanar (singular values {:.3g}, {:.3g}, {:.3g}); "
        "photometric stereo needs lights in three independent directions",
        lights.size(), s[0], s[1], s[2]));
  }
  // N_a = I L+ (eq. 4.4.8), one albedo-scaled normal per channel.
  const Eigen::MatrixXf scaled =
      ParallelProduct(fit.observations.matrix(), fit.Scatter(PseudoInverseTransposed(svd)));
  const int channels = fit.channels();
  const auto channel_names = OutputChannelNames(channels);
  std::vector<std::string> names = {"normal.X", "normal.Y", "normal.Z"};
  for (const auto& c : channel_names) names.push_back("albedo." + c);
  Image maps = fit.NewMaps(names);
  const Eigen::Index m = fit.m();
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index k) {
    // One normal per pixel: the sum of the channels' scaled normals, i.e. the least-squares
    // normal of the channel sum. Each channel's albedo is its scaled normal's component along it
    // (exact for a Lambertian pixel).
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int c = 0; c < channels; ++c) sum += scaled.row(c * m + k).transpose().cast<double>();
    const double norm = sum.norm();
    const Eigen::Vector3d n = norm > 0.0 ? (sum / norm).eval() : Eigen::Vector3d::UnitZ();
    const auto pixel = maps.pixel(fit.PixelIndex(k));
    for (int i = 0; i < 3; ++i) pixel[i] = static_cast<float>(n[i]);
    for (int c = 0; c < channels; ++c) {
      pixel[3 + c] = static_cast<float>(scaled.row(c * m + k).cast<double>().dot(n));
    }
  });
  return Representation("gradient", std::move(maps), {3, false, true, channels},
                        LinearLightBasis::Lambertian());
}

// The conic that lights leaving PTM's biquadratic undetermined lie on: the weakest left singular
// vector w of the 6 x |S| term matrix has sum_j w_j term_j(l) ~ 0 at every light. Written with
// its largest coefficient 1 and terms below 1e-3 of it left out: "lu^2 + lv^2 - 0.413 = 0" for a
// ring of equal slant, "lu*lv = 0" for lights only on the image axes. Tells a user which lights
// to add, where "degenerate" alone would not.
std::string PtmDegenerateConic(const Eigen::VectorXd& w) {
  static constexpr std::array<const char*, 6> kTerms = {"lu^2", "lv^2", "lu*lv", "lu", "lv", ""};
  Eigen::Index largest = 0;
  w.cwiseAbs().maxCoeff(&largest);
  const Eigen::VectorXd scaled = w / w[largest];
  std::string conic;
  for (int j = 0; j < 6; ++j) {
    const double c = scaled[j];
    if (std::abs(c) < 1e-3) continue;
    const std::string_view sign =
        c < 0 ? (conic.empty() ? "-" : " - ") : (conic.empty() ? "" : " + ");
    const std::string_view term = kTerms[j];
    const bool unit = std::abs(std::abs(c) - 1.0) < 1e-3 && !term.empty();
    const std::string magnitude = unit ? "" : fmt::format("{:.3g}", std::abs(c));
    conic += fmt::format("{}{}{}{}", sign, magnitude, unit || term.empty() ? "" : " ", term);
  }
  return conic + " = 0";
}

Eigen::MatrixXd PtmPseudoInverse(const FitContext& fit) {
  const Eigen::MatrixXd terms = PtmTerms(fit.SelectedLights());
  const auto svd = CheckedSvd(terms);
  const Eigen::VectorXd s = svd.singularValues();
  if (s[5] < kPtmConditionLimit * s[0]) {
    fit.Fail(fmt::format(
        "ptm: the {} lights do not determine the 6 PTM coefficients: their directions' (lu, lv) "
        "all lie on the conic {} (as lights on one ring of equal slant, on one line or on the "
        "image axes do); add lights off it, at other slants or tilts",
        fit.selected.size(), PtmDegenerateConic(svd.matrixU().col(5))));
  }
  return PseudoInverseTransposed(svd);
}

Representation FitPtm(const FitContext& fit) {
  const Eigen::MatrixXf coefficients =
      ParallelProduct(fit.observations.matrix(), fit.Scatter(PtmPseudoInverse(fit)));
  Image maps = fit.NewMaps(CoefficientMapNames("ptm.a", 6, OutputChannelNames(fit.channels())));
  StorePerChannelTerms(fit, coefficients, maps);
  return Representation("ptm", std::move(maps), {6, true, false, fit.channels()},
                        std::make_shared<PtmLightBasis>());
}

// PTM's LRGB form: a luminance polynomial L fitted to the mean of the channels, and per channel
// the least-squares chroma s_c = sum_k I_ck L_k / sum_k L_k^2, so that I_c ~ s_c L.
Representation FitPtmLrgb(const FitContext& fit) {
  const int channels = fit.channels();
  const Eigen::Index m = fit.m();
  Eigen::MatrixXf luminance = fit.observations.Channel(0);
  for (int c = 1; c < channels; ++c) luminance += fit.observations.Channel(c);
  luminance /= static_cast<float>(channels);
  const Eigen::MatrixXf coefficients =
      ParallelProduct(luminance, fit.Scatter(PtmPseudoInverse(fit)));
  const Eigen::MatrixXf terms = PtmTerms(fit.lights).cast<float>();
  Eigen::VectorXf in_fit = Eigen::VectorXf::Zero(fit.observations.images());
  for (int i : fit.selected) in_fit[i] = 1.0f;

  std::vector<std::string> names;
  for (int j = 0; j < 6; ++j) names.push_back(fmt::format("ptm.a{}", j));
  for (const auto& c : OutputChannelNames(channels)) names.push_back("rgb." + c);
  Image maps = fit.NewMaps(names);
  tbb::parallel_for(Eigen::Index{0}, m, [&](Eigen::Index k) {
    const Eigen::RowVectorXf fitted = coefficients.row(k) * terms;  // L at every light
    const double denominator = fitted.cwiseProduct(fitted).dot(in_fit);
    const auto pixel = maps.pixel(fit.PixelIndex(k));
    for (int j = 0; j < 6; ++j) pixel[j] = coefficients(k, j);
    for (int c = 0; c < channels; ++c) {
      const double numerator =
          fit.observations.matrix().row(c * m + k).cwiseProduct(fitted).dot(in_fit);
      pixel[6 + c] = denominator > 0.0 ? static_cast<float>(numerator / denominator) : 0.0f;
    }
  });
  return Representation("ptm-lrgb", std::move(maps), {6, false, true, channels},
                        std::make_shared<PtmLightBasis>());
}

// Hemispherical harmonics per channel, fitted like PTM: least squares through the SVD
// pseudo-inverse of the lights' HSH terms.
Representation FitHsh(const FitContext& fit, int terms) {
  const auto svd = CheckedSvd(HshTerms(fit.SelectedLights(), terms));
  const Eigen::VectorXd s = svd.singularValues();
  if (s[terms - 1] < kHshConditionLimit * s[0]) {
    const int slants = static_cast<int>(std::sqrt(terms));  // the order: 2, 3 or 4
    fit.Fail(fmt::format(
        "hsh{}: the {} lights do not determine the {} hemispherical-harmonic coefficients (too "
        "few distinct slants or tilts: {} terms need lights at {} or more slants); add lights",
        terms, fit.selected.size(), terms, terms, slants));
  }
  const Eigen::MatrixXf coefficients =
      ParallelProduct(fit.observations.matrix(), fit.Scatter(PseudoInverseTransposed(svd)));
  Image maps = fit.NewMaps(CoefficientMapNames("hsh.h", terms, OutputChannelNames(fit.channels())));
  StorePerChannelTerms(fit, coefficients, maps);
  return Representation(fmt::format("hsh{}", terms), std::move(maps),
                        {terms, true, false, fit.channels()},
                        std::make_shared<HshLightBasis>(terms));
}

Representation FitThreeImage(const FitContext& fit) {
  const std::array<int, 3> chosen = SelectThreeImageLights(fit.lights, fit.selected, fit.source);
  Eigen::Matrix3d l;
  for (int j = 0; j < 3; ++j) l.col(j) = fit.lights[chosen[j]].vector();
  const Eigen::MatrixXd inverse = l.inverse();  // c = L^-1 l (eq. 4.4.9-10)
  const int channels = fit.channels();
  Eigen::MatrixXf images(fit.observations.matrix().rows(), 3);
  nlohmann::json used = nlohmann::json::array();
  for (int j = 0; j < 3; ++j) {
    images.col(j) = fit.observations.matrix().col(chosen[j]);
    const LightDirection& light = fit.lights[chosen[j]];
    used.push_back({{"image", chosen[j]},
                    {"slant_deg", light.SlantDegrees()},
                    {"tilt_deg", light.TiltDegrees()}});
  }
  Image maps = fit.NewMaps(CoefficientMapNames("image", 3, OutputChannelNames(channels)));
  StorePerChannelTerms(fit, images, maps);
  return Representation("3i", std::move(maps), {3, true, false, channels},
                        std::make_shared<LinearLightBasis>(inverse), {{"images", used}});
}

// Eigen-k (thesis 4.4.5) from the Gram matrix and column sums of the whole set's image matrix.
Representation FitEigen(const FitContext& fit, int k) {
  const EigenBasis basis = EigenBasisFromGram(
      fit.observations.Gram(), fit.observations.ColumnSums(), fit.selected, k, fit.source);
  return FitEigenWithBasis(fit.observations, fit.lights, fit.selected, basis);
}

}  // namespace

std::array<int, 3> SelectThreeImageLights(const std::vector<LightDirection>& lights,
                                          std::span<const int> selected, const fs::path& source) {
  constexpr double kTolerance = 0.5;  // degrees
  const auto find = [&](double slant, double tilt) -> int {
    for (int i : selected) {
      const double dt = std::remainder(lights[i].TiltDegrees() - tilt, 360.0);
      if (std::abs(lights[i].SlantDegrees() - slant) < kTolerance && std::abs(dt) < kTolerance) {
        return i;
      }
    }
    return -1;
  };
  std::vector<double> tilts;
  for (int i : selected) {
    if (std::abs(lights[i].SlantDegrees() - 45.0) < kTolerance) {
      tilts.push_back(lights[i].TiltDegrees());
    }
  }
  std::sort(tilts.begin(), tilts.end());
  for (double t : tilts) {
    const int a = find(45.0, t), b = find(45.0, t + 90.0), c = find(45.0, t + 180.0);
    if (a >= 0 && b >= 0 && c >= 0) return {a, b, c};
  }
  double best = 0.0;
  std::array<int, 3> chosen = {-1, -1, -1};
  for (std::size_t a = 0; a < selected.size(); ++a) {
    for (std::size_t b = a + 1; b < selected.size(); ++b) {
      const Eigen::Vector3d ab = lights[selected[a]].vector().cross(lights[selected[b]].vector());
      for (std::size_t c = b + 1; c < selected.size(); ++c) {
        const double det = std::abs(ab.dot(lights[selected[c]].vector()));
        if (det > best) best = det, chosen = {selected[a], selected[b], selected[c]};
      }
    }
  }
  if (selected.size() < 3) {
    throw Error(source, fmt::format("3i needs 3 images; {} given", selected.size()));
  }
  if (best < kThreeImageDeterminantLimit) {
    throw Error(source, fmt::format("3i: every triple of the {} lights is coplanar (largest "
                                    "|det| {:.3g}); 3I needs three independent light directions",
                                    selected.size(), best));
  }
  return chosen;
}

EigenBasis EigenBasisFromGram(const Eigen::MatrixXd& gram, const Eigen::VectorXd& column_sums,
                              std::span<const int> selected, int k, const fs::path& source) {
  const auto n = static_cast<Eigen::Index>(selected.size());
  if (k < 1 || k > n) {
    throw Error(source, fmt::format("eigen{} needs at least {} images; {} given", k, k, n));
  }
  Eigen::MatrixXd sub(n, n);
  Eigen::VectorXd sums(n);
  for (Eigen::Index a = 0; a < n; ++a) {
    sums[a] = column_sums[selected[a]];
    for (Eigen::Index b = 0; b < n; ++b) sub(a, b) = gram(selected[a], selected[b]);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(sub);
  if (solver.info() != Eigen::Success) {
    throw Error(source, fmt::format("eigen{}: SVD did not converge", k));
  }
  // Eigenvalues ascend; the k largest are the last k, reversed.
  EigenBasis basis{Eigen::MatrixXd(n, k), Eigen::VectorXd(n)};
  for (Eigen::Index j = 0; j < n; ++j) {
    basis.singular[j] = std::sqrt(std::max(0.0, solver.eigenvalues()[n - 1 - j]));
  }
  for (int j = 0; j < k; ++j) {
    basis.v.col(j) = solver.eigenvectors().col(n - 1 - j);
    // Each component's sign is arbitrary; make the basis images sum positive (the sum of basis
    // image j is column_sums . v_j) so that maps are readable and fits reproducible. The sign
    // cancels in M1 M2.
    if (sums.dot(basis.v.col(j)) < 0.0) basis.v.col(j) *= -1.0;
  }
  return basis;
}

Representation EigenRepresentation(const Observations& observations, const Eigen::MatrixXf& bases,
                                   const std::vector<LightDirection>& lights,
                                   std::span<const int> selected, const EigenBasis& basis,
                                   nlohmann::json details) {
  const auto k = static_cast<int>(basis.v.cols());
  const int channels = observations.channels();
  Image maps(observations.width(), observations.height(),
             CoefficientMapNames("eigen.", k, OutputChannelNames(channels)));
  const Eigen::Index m = observations.pixels();
  const auto& pixel_indices = observations.pixel_indices();
  tbb::parallel_for(0, k * channels, [&](int map) {
    const Eigen::Index j = map / channels, c = map % channels;
    const float* values = bases.col(j).data() + c * m;
    float* plane = maps.plane(map).data();
    for (Eigen::Index p = 0; p < m; ++p) plane[pixel_indices[p]] = values[p];
  });
  const Eigen::VectorXd& singular = basis.singular;
  const Eigen::Index n = singular.size();
  const double total = singular.squaredNorm();
  nlohmann::json cumulative = nlohmann::json::array();
  double sum = 0.0;
  for (Eigen::Index j = 0; j < n; ++j) {
    sum += singular[j] * singular[j];
    cumulative.push_back(total > 0 ? std::sqrt(sum / total) : 0.0);  // f_cumu, eq. 4.4.13
  }
  const std::vector<LightDirection> selected_lights = SelectLights(lights, selected);
  auto light_basis = std::make_shared<InterpolatedLightBasis>(selected_lights, basis.v.transpose());
  const std::string scheme(ToString(light_basis->interpolator().scheme()));
  const std::vector<double> singular_values(singular.data(), singular.data() + n);
  if (!details.is_object()) details = nlohmann::json::object();
  nlohmann::json all = {{"singular_values", singular_values},
                        {"cumulative_information", cumulative},
                        {"interpolation", scheme}};
  all.update(details);
  return Representation(fmt::format("eigen{}", k), std::move(maps), {k, true, false, channels},
                        std::move(light_basis), std::move(all));
}

Representation FitEigenWithBasis(const Observations& observations,
                                 const std::vector<LightDirection>& lights,
                                 std::span<const int> selected, const EigenBasis& basis) {
  // M1 = I V_k: the basis images, from the selected images only.
  Eigen::MatrixXf v = Eigen::MatrixXf::Zero(observations.images(), basis.v.cols());
  for (std::size_t i = 0; i < selected.size(); ++i) {
    v.row(selected[i]) = basis.v.row(static_cast<Eigen::Index>(i)).cast<float>();
  }
  const Eigen::MatrixXf bases = ParallelProduct(observations.matrix(), v);
  return EigenRepresentation(observations, bases, lights, selected, basis);
}

Representation FitObservations(const Observations& observations,
                               const std::vector<LightDirection>& lights, const Method& method,
                               std::span<const int> selected, const fs::path& source) {
  const FitContext fit{observations, lights, selected, source};
  if (static_cast<int>(selected.size()) < method.MinimumImages()) {
    fit.Fail(fmt::format("{} needs at least {} images with distinct lights; {} given",
                         method.Name(), method.MinimumImages(), selected.size()));
  }
  switch (method.kind) {
    case Method::Kind::kThreeImage:
      return FitThreeImage(fit);
    case Method::Kind::kGradient:
      return FitGradient(fit);
    case Method::Kind::kPtm:
      return FitPtm(fit);
    case Method::Kind::kPtmLrgb:
      return FitPtmLrgb(fit);
    case Method::Kind::kHsh:
      return FitHsh(fit, method.hsh_terms);
    case Method::Kind::kPbr:
      // A nonlinear fit needs a start: always the robust photometric stereo's (default options).
      return RobustFit(observations, lights, selected, RobustFitOptions{}, source).Fit(method);
    case Method::Kind::kRbf:
    case Method::Kind::kBilinear: {
      return ProjectLightProfiles(
          FitLightProfileModel(observations.Gram(), observations.ColumnSums(), lights, selected,
                               method, source),
          observations, observations.matrix(), selected);
    }
    case Method::Kind::kNeural:
      fit.Fail(NeuralIsTrainedApart());
    case Method::Kind::kEigen:
      break;
  }
  return FitEigen(fit, method.eigen_k);
}

Representation Fit(const PhotometricSet& set, const Method& method) {
  std::vector<int> all(set.size());
  std::iota(all.begin(), all.end(), 0);
  if (set.size() < method.MinimumImages()) {
    set.Fail(fmt::format("{} needs at least {} images; the set has {}", method.Name(),
                         method.MinimumImages(), set.size()));
  }
  // pbr through the set, not its observations alone: the set carries its near lamps.
  if (method.kind == Method::Kind::kPbr) return FitRobust(set, method, RobustFitOptions{});
  const Observations observations(set);
  return FitObservations(observations, set.lights(), method, all, set.source());
}

}  // namespace photomat
