#include "calibrate/radiometry/flat_field.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr const char* kFlatFieldFormat = "photomat-flatfield";
constexpr const char* kFlatFieldFile = "flatfield.json";
// Samples per polynomial fit: plenty for 15 coefficients, cheap for large targets.
constexpr std::size_t kPolynomialSamples = 20000;
// Below this share of target pixels in the smoothing window, the smoothed value is unreliable.
constexpr double kMinimumCoverage = 0.05;
// Lights this close to the horizon give no usable flat-field (l.z is the denominator).
constexpr double kMinimumLightZ = 0.02;

// The monomials x^a y^b (a + b <= degree) at normalised coordinates in [-1, 1].
Eigen::VectorXd Monomials(double u, double v, int degree) {
  Eigen::VectorXd terms((degree + 1) * (degree + 2) / 2);
  int t = 0;
  for (int total = 0; total <= degree; ++total) {
    for (int a = total; a >= 0; --a) terms[t++] = std::pow(u, a) * std::pow(v, total - a);
  }
  return terms;
}

double NormalisedX(int x, int width) { return (x + 0.5) / (0.5 * width) - 1.0; }
double NormalisedY(int y, int height) { return (y + 0.5) / (0.5 * height) - 1.0; }

// Least-squares polynomial of log(values) over the set pixels of `mask`, evaluated everywhere and
// exponentiated: lamp fall-off and vignetting are multiplicative and span a large range, which a
// polynomial in log space follows with few terms, and the gains stay positive. Values at or below
// 0 (noise on a dark target) are left out; if none is left the result is 0.
cv::Mat PolynomialFit(const cv::Mat& values, const cv::Mat& mask, int degree) {
  const int width = values.cols, height = values.rows;
  const std::size_t count = static_cast<std::size_t>(cv::countNonZero(mask));
  const int stride = std::max(1, static_cast<int>(std::sqrt(count / double(kPolynomialSamples))));
  const int terms = (degree + 1) * (degree + 2) / 2;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(terms, terms);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(terms);
  for (int y = 0; y < height; y += stride) {
    for (int x = 0; x < width; x += stride) {
      if (mask.at<float>(y, x) <= 0.5f || values.at<float>(y, x) <= 0.0f) continue;
      const Eigen::VectorXd m = Monomials(NormalisedX(x, width), NormalisedY(y, height), degree);
      normal.selfadjointView<Eigen::Lower>().rankUpdate(m);
      rhs += std::log(values.at<float>(y, x)) * m;
    }
  }
  normal = normal.selfadjointView<Eigen::Lower>();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0.0)) {
    return cv::Mat::zeros(height, width, CV_32F);  // reported as a dark target
  }
  const Eigen::VectorXd coefficients = ldlt.solve(rhs);
  // Evaluation from tables of powers (pow per pixel and term would dominate the run time).
  Eigen::MatrixXd u_powers(width, degree + 1), v_powers(height, degree + 1);
  for (int x = 0; x < width; ++x) {
    for (int a = 0; a <= degree; ++a) u_powers(x, a) = std::pow(NormalisedX(x, width), a);
  }
  for (int y = 0; y < height; ++y) {
    for (int b = 0; b <= degree; ++b) v_powers(y, b) = std::pow(NormalisedY(y, height), b);
  }
  cv::Mat fitted(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    // The polynomial along this row: coefficients of u^a once v is fixed.
    Eigen::VectorXd along_row = Eigen::VectorXd::Zero(degree + 1);
    int t = 0;
    for (int total = 0; total <= degree; ++total) {
      for (int a = total; a >= 0; --a) along_row[a] += coefficients[t++] * v_powers(y, total - a);
    }
    for (int x = 0; x < width; ++x) {
      fitted.at<float>(y, x) = static_cast<float>(std::exp(u_powers.row(x).dot(along_row)));
    }
  }
  return fitted;
}

// Normalises the gains to a mean of 1 per channel over all lights and pixels.
void NormaliseGains(std::vector<Image>& gains) {
  const int channels = gains.front().channels();
  for (int c = 0; c < channels; ++c) {
    double sum = 0.0;
    std::size_t count = 0;
    for (const Image& gain : gains) {
      for (float v : gain.plane(c)) sum += v;
      count += gain.pixel_count();
    }
    const auto scale = static_cast<float>(count / sum);
    for (Image& gain : gains) {
      for (float& v : gain.plane(c)) v *= scale;
    }
  }
}

}  // namespace

std::string_view ToString(FlatFieldModel model) {
  return model == FlatFieldModel::kSmoothed ? "smoothed" : "polynomial";
}

std::optional<FlatFieldModel> ParseFlatFieldModel(std::string_view name) {
  if (name == "smoothed") return FlatFieldModel::kSmoothed;
  if (name == "polynomial") return FlatFieldModel::kPolynomial;
  return std::nullopt;
}

FlatField::FlatField(std::vector<Image> gains, std::vector<LightDirection> lights)
    : gains_(std::move(gains)), lights_(std::move(lights)) {
  if (gains_.empty()) throw Error("a flat-field needs at least one gain map");
  if (gains_.size() != lights_.size()) {
    throw Error(fmt::format("{} gain maps for {} lights", gains_.size(), lights_.size()));
  }
  for (const Image& gain : gains_) {
    if (!gain.SameShape(gains_.front())) throw Error("the flat-field's gain maps differ in size");
  }
}

FlatField EstimateFlatField(const PhotometricSet& target, const FlatFieldOptions& options) {
  if (options.polynomial_degree < 0 || options.polynomial_degree > 8) {
    throw Error("the flat-field polynomial degree must be in 0..8");
  }
  if (!(options.smoothing_sigma > 0.0)) throw Error("the smoothing sigma must be positive");
  const int width = target.width(), height = target.height(), channels = target.channels();
  const Mask region = target.MaskOrAll();
  cv::Mat mask(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) mask.at<float>(y, x) = region(x, y) ? 1.0f : 0.0f;
  }
  const int terms = (options.polynomial_degree + 1) * (options.polynomial_degree + 2) / 2;
  if (static_cast<int>(region.CountSet()) < 4 * terms) {
    target.Fail(fmt::format("the flat-field target covers {} pixels: too few", region.CountSet()));
  }
  cv::Mat coverage;
  if (options.model == FlatFieldModel::kSmoothed) {
    cv::GaussianBlur(mask, coverage, cv::Size(0, 0), options.smoothing_sigma);
  }
  for (int i = 0; i < target.size(); ++i) {
    if (target.light(i).z() < kMinimumLightZ) {
      target.Fail(fmt::format("{}: the light is at the horizon (z = {:.3f}); no flat-field",
                              target.image_name(i), target.light(i).z()));
    }
  }
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("flat-field", static_cast<std::size_t>(target.size()));
  std::vector<Image> gains(target.size());
  std::vector<std::string> faults(target.size());
  tbb::parallel_for(0, target.size(), [&](int i) {
    const Image& image = target.image(i);
    Image gain(width, height, channels);
    const double z = target.light(i).z();
    for (int c = 0; c < channels; ++c) {
      // The plane as an OpenCV matrix (a header on the image's storage), times the mask.
      const cv::Mat plane(height, width, CV_32F, const_cast<float*>(image.plane(c).data()));
      cv::Mat values;
      cv::multiply(plane, mask, values);
      const cv::Mat polynomial = PolynomialFit(values, mask, options.polynomial_degree);
      cv::Mat smoothed;
      if (options.model == FlatFieldModel::kSmoothed) {
        cv::GaussianBlur(values, smoothed, cv::Size(0, 0), options.smoothing_sigma);
      }
      for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
          double value = polynomial.at<float>(y, x);
          if (options.model == FlatFieldModel::kSmoothed &&
              coverage.at<float>(y, x) >= kMinimumCoverage) {
            value = smoothed.at<float>(y, x) / coverage.at<float>(y, x);
          }
          if (!(value > 0.0) && faults[i].empty()) {
            faults[i] = fmt::format(
                "{}: the target is dark at pixel ({}, {}) in channel {} "
                "(value {:.3g}); a flat-field needs the target lit everywhere",
                target.image_name(i), x, y, c, value);
          }
          gain.at(x, y, c) = static_cast<float>(value / z);
        }
      }
    }
    gains[i] = std::move(gain);
    progress.Advance();
  });
  progress.Finish();
  for (const std::string& fault : faults) {
    if (!fault.empty()) target.Fail(fault);
  }
  NormaliseGains(gains);
  return FlatField(std::move(gains), target.lights());
}

FlatField FlatField::Rows(int first, int count) const {
  std::vector<Image> rows;
  rows.reserve(gains_.size());
  for (const Image& gain : gains_) rows.emplace_back(gain.Rows(first, count));
  return FlatField(std::move(rows), lights_);
}

NearLightGains::NearLightGains(std::vector<NearLight> lights, int width, int height, int channels)
    : lights_(std::move(lights)), width_(width), height_(height), channels_(channels) {
  if (lights_.empty()) throw Error("no near lights");
  for (const NearLight& light : lights_) nominal_z_.push_back(NominalDirection(light).z());
  // As NormaliseGains: a mean of 1 over every light and pixel (the same in every channel). Each
  // light's sum is taken alone, in parallel, and the sums added in light order, so that the
  // scale does not depend on the threads.
  std::vector<double> sums(lights_.size(), 0.0);
  tbb::parallel_for(std::size_t{0}, lights_.size(), [&](std::size_t i) {
    double sum = 0.0;
    for (int y = 0; y < height_; ++y) {
      for (int x = 0; x < width_; ++x) sum += Unnormalised(i, x, y);
    }
    sums[i] = sum;
  });
  double sum = 0.0;
  for (double s : sums) sum += s;
  const double count = static_cast<double>(lights_.size()) * width_ * height_;
  scale_ = static_cast<float>(count / sum);
}

float NearLightGains::Unnormalised(std::size_t i, int x, int y) const {
  const NearLight& light = lights_[i];
  const Eigen::Vector3d to_light = light.position - SamplePoint(width_, height_, x, y);
  const double distance = to_light.norm();
  return static_cast<float>(light.intensity * to_light.z() / (distance * distance * distance) /
                            nominal_z_[i]);
}

FlatField NearLightGains::Rows(int first, int count) const {
  if (first < 0 || count < 1 || first + count > height_) {
    throw Error(fmt::format("rows {}..{} of near-light gains {} rows high", first,
                            first + count - 1, height_));
  }
  std::vector<Image> gains(lights_.size());
  tbb::parallel_for(std::size_t{0}, lights_.size(), [&](std::size_t i) {
    Image gain(width_, count, channels_);
    for (int y = 0; y < count; ++y) {
      for (int x = 0; x < width_; ++x) {
        const float value = Unnormalised(i, x, first + y) * scale_;
        for (int c = 0; c < channels_; ++c) gain.at(x, y, c) = value;
      }
    }
    gains[i] = std::move(gain);
  });
  return FlatField(std::move(gains), NominalDirections(lights_));
}

FlatField FlatFieldFromNearLights(const std::vector<NearLight>& lights, int width, int height,
                                  int channels) {
  return NearLightGains(lights, width, height, channels).Rows(0, height);
}

PhotometricSet ApplyFlatField(const PhotometricSet& set, const FlatField& flat_field,
                              double max_light_difference_degrees) {
  if (flat_field.size() != set.size()) {
    set.Fail(fmt::format("the flat-field has {} lights but the set {} images", flat_field.size(),
                         set.size()));
  }
  const Image& first = flat_field.gain(0);
  if (first.width() != set.width() || first.height() != set.height() ||
      first.channels() != set.channels()) {
    set.Fail(fmt::format(
        "the flat-field is {}x{} with {} channels but the images are {}x{} with {}", first.width(),
        first.height(), first.channels(), set.width(), set.height(), set.channels()));
  }
  for (int i = 0; i < set.size(); ++i) {
    const double difference = set.light(i).AngleToDegrees(flat_field.lights()[i]);
    if (difference > max_light_difference_degrees) {
      set.Fail(
          fmt::format("{}: its light differs by {:.1f} degrees from the flat-field's light {} "
                      "(is the flat-field from another light set?)",
                      set.image_name(i), difference, i));
    }
  }
  std::vector<Image> images(set.size());
  tbb::parallel_for(0, set.size(), [&](int i) {
    Image image = set.image(i);
    const Image& gain = flat_field.gain(i);
    auto values = image.values();
    const auto gains = gain.values();
    for (std::size_t v = 0; v < values.size(); ++v) values[v] /= std::max(gains[v], 1e-6f);
    images[i] = std::move(image);
  });
  PhotometricSet corrected(std::move(images), set.lights(), set.image_names(), set.source());
  if (set.mask()) corrected.set_mask(*set.mask());
  if (!set.intensities().empty()) corrected.set_intensities(set.intensities());
  return corrected;
}

void SaveFlatField(const fs::path& folder, const FlatField& flat_field) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw Error(folder, "cannot create the folder: " + error.message());
  nlohmann::json json = {{"format", kFlatFieldFormat}, {"version", 1}};
  nlohmann::json entries = nlohmann::json::array();
  ImageWriteOptions write;
  write.sample_type = SampleType::kHalf;
  for (int i = 0; i < flat_field.size(); ++i) {
    const std::string file = fmt::format("gain_{:03d}.exr", i);
    WriteImage(folder / file, flat_field.gain(i), write);
    const Eigen::Vector3d& l = flat_field.lights()[i].vector();
    entries.push_back({{"file", file}, {"light", {l.x(), l.y(), l.z()}}});
  }
  json["gains"] = entries;
  WriteJsonFile(folder / kFlatFieldFile, json);
}

FlatFieldBandReader::FlatFieldBandReader(const fs::path& path) {
  const fs::path file = fs::is_directory(path) ? path / kFlatFieldFile : path;
  const nlohmann::json json = ReadJsonFile(file);
  const JsonReader reader(json, file);
  if (reader["format"].String() != kFlatFieldFormat) {
    reader["format"].Fail(fmt::format("expected \"{}\"", kFlatFieldFormat));
  }
  const JsonReader entries = reader["gains"];
  for (std::size_t i = 0; i < entries.ArraySize(); ++i) {
    const JsonReader entry = entries[i];
    const std::vector<double> l = entry["light"].Numbers();
    if (l.size() != 3) entry["light"].Fail("expected an array of 3 numbers");
    try {
      lights_.push_back(LightDirection::FromVector(l[0], l[1], l[2]));
    } catch (const Error& e) {
      entry["light"].Fail(e.fault());
    }
    readers_.emplace_back(file.parent_path() / entry["file"].String());
    const ImageBandReader& first = readers_.front();
    const ImageBandReader& gain = readers_.back();
    if (gain.width() != first.width() || gain.height() != first.height() ||
        gain.channels() != first.channels()) {
      entry["file"].Fail("the gain maps differ in size or channel count");
    }
  }
  if (readers_.empty()) reader["gains"].Fail("no gain maps");
}

FlatField FlatFieldBandReader::ReadNext(int rows) {
  std::vector<Image> gains(readers_.size());
  tbb::parallel_for(std::size_t{0}, readers_.size(), [&](std::size_t i) {
    Image band(width(), rows, channels());
    readers_[i].ReadNext(band.View());
    gains[i] = std::move(band);
  });
  return FlatField(std::move(gains), lights_);
}

FlatField LoadFlatField(const fs::path& path) {
  FlatFieldBandReader reader(path);
  return reader.ReadNext(reader.height());
}

}  // namespace photomat
