#include "calibrate/radiometry/flat_field.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <functional>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "capture/io/streamed_set.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/scratch_folder.h"

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

// Per channel, the sum of a gain map's values (in double, in pixel order).
std::vector<double> ChannelSums(const Image& gain) {
  std::vector<double> sums(static_cast<std::size_t>(gain.channels()), 0.0);
  for (int c = 0; c < gain.channels(); ++c) {
    for (float v : gain.plane(c)) sums[static_cast<std::size_t>(c)] += v;
  }
  return sums;
}

// Per channel, what makes the gains' mean 1 over all lights and pixels: `sums` holds each light's
// ChannelSums, added here in light order, so the scales do not depend on how the gains were made
// (all at once, or light by light in any thread order).
std::vector<float> NormalisationScales(const std::vector<std::vector<double>>& sums,
                                       std::size_t pixels_per_light) {
  std::vector<float> scales(sums.front().size());
  for (std::size_t c = 0; c < scales.size(); ++c) {
    double sum = 0.0;
    for (const std::vector<double>& light : sums) sum += light[c];
    scales[c] = static_cast<float>(static_cast<double>(pixels_per_light * sums.size()) / sum);
  }
  return scales;
}

void Scale(Image& gain, const std::vector<float>& scales) {
  for (int c = 0; c < gain.channels(); ++c) {
    for (float& v : gain.plane(c)) v *= scales[static_cast<std::size_t>(c)];
  }
}

// What every light's gain shares: the options checked, the target's region as an OpenCV float
// mask and, for kSmoothed, the mask's smoothed coverage.
struct TargetRegion {
  cv::Mat mask;
  cv::Mat coverage;
};

TargetRegion MakeTargetRegion(const Mask& region, const FlatFieldOptions& options,
                              const std::function<void(const std::string&)>& fail) {
  if (options.polynomial_degree < 0 || options.polynomial_degree > 8) {
    throw Error("the flat-field polynomial degree must be in 0..8");
  }
  if (!(options.smoothing_sigma > 0.0)) throw Error("the smoothing sigma must be positive");
  TargetRegion target;
  target.mask = cv::Mat(region.height(), region.width(), CV_32F);
  for (int y = 0; y < region.height(); ++y) {
    for (int x = 0; x < region.width(); ++x)
      target.mask.at<float>(y, x) = region(x, y) ? 1.0f : 0.0f;
  }
  const int terms = (options.polynomial_degree + 1) * (options.polynomial_degree + 2) / 2;
  if (static_cast<int>(region.CountSet()) < 4 * terms) {
    fail(fmt::format("the flat-field target covers {} pixels: too few", region.CountSet()));
  }
  if (options.model == FlatFieldModel::kSmoothed) {
    cv::GaussianBlur(target.mask, target.coverage, cv::Size(0, 0), options.smoothing_sigma);
  }
  return target;
}

void CheckTargetLights(const std::vector<LightDirection>& lights,
                       const std::vector<std::string>& names,
                       const std::function<void(const std::string&)>& fail) {
  for (std::size_t i = 0; i < lights.size(); ++i) {
    if (lights[i].z() < kMinimumLightZ) {
      fail(fmt::format("{}: the light is at the horizon (z = {:.3f}); no flat-field", names[i],
                       lights[i].z()));
    }
  }
}

// A light's gain before the normalisation, from its target image alone: the target's values over
// the region (polynomial or smoothed) divided by the light's z. `fault` gets the first dark pixel
// (a flat-field needs the target lit everywhere); empty when there is none.
Image UnnormalisedGain(ConstImageView image, double z, const TargetRegion& target,
                       const FlatFieldOptions& options, const std::string& name,
                       std::string& fault) {
  const int width = image.width(), height = image.height(), channels = image.channels();
  Image gain(width, height, channels);
  for (int c = 0; c < channels; ++c) {
    // The plane as an OpenCV matrix (a header on the image's storage), times the mask.
    const cv::Mat plane(height, width, CV_32F,
                        const_cast<float*>(image.data() + c * image.plane_stride()),
                        static_cast<std::size_t>(image.row_stride()) * sizeof(float));
    cv::Mat values;
    cv::multiply(plane, target.mask, values);
    const cv::Mat polynomial = PolynomialFit(values, target.mask, options.polynomial_degree);
    cv::Mat smoothed;
    if (options.model == FlatFieldModel::kSmoothed) {
      cv::GaussianBlur(values, smoothed, cv::Size(0, 0), options.smoothing_sigma);
    }
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        double value = polynomial.at<float>(y, x);
        if (options.model == FlatFieldModel::kSmoothed &&
            target.coverage.at<float>(y, x) >= kMinimumCoverage) {
          value = smoothed.at<float>(y, x) / target.coverage.at<float>(y, x);
        }
        if (!(value > 0.0) && fault.empty()) {
          fault = fmt::format(
              "{}: the target is dark at pixel ({}, {}) in channel {} "
              "(value {:.3g}); a flat-field needs the target lit everywhere",
              name, x, y, c, value);
        }
        gain.at(x, y, c) = static_cast<float>(value / z);
      }
    }
  }
  return gain;
}

std::string GainFileName(std::size_t light) { return fmt::format("gain_{:03d}.exr", light); }

void WriteGain(const fs::path& path, const Image& gain) {
  ImageWriteOptions write;
  write.sample_type = SampleType::kHalf;
  WriteImage(path, gain, write);
}

// flatfield.json: the format, and each light's gain file and nominal direction.
nlohmann::json FlatFieldDescription(const std::vector<LightDirection>& lights) {
  nlohmann::json entries = nlohmann::json::array();
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const Eigen::Vector3d& l = lights[i].vector();
    entries.push_back({{"file", GainFileName(i)}, {"light", {l.x(), l.y(), l.z()}}});
  }
  return {{"format", kFlatFieldFormat}, {"version", 1}, {"gains", entries}};
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
  const auto fail = [&](const std::string& fault) { target.Fail(fault); };
  const TargetRegion region = MakeTargetRegion(target.MaskOrAll(), options, fail);
  CheckTargetLights(target.lights(), target.image_names(), fail);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("flat-field", static_cast<std::size_t>(target.size()));
  std::vector<Image> gains(target.size());
  std::vector<std::vector<double>> sums(gains.size());
  std::vector<std::string> faults(target.size());
  tbb::parallel_for(0, target.size(), [&](int i) {
    gains[i] = UnnormalisedGain(target.image(i), target.light(i).z(), region, options,
                                target.image_name(i), faults[i]);
    sums[i] = ChannelSums(gains[i]);
    progress.Advance();
  });
  progress.Finish();
  for (const std::string& fault : faults) {
    if (!fault.empty()) target.Fail(fault);
  }
  const std::vector<float> scales =
      NormalisationScales(sums, target.images().front().pixel_count());
  for (Image& gain : gains) Scale(gain, scales);
  return FlatField(std::move(gains), target.lights());
}

void EstimateFlatFieldStreamed(StreamedSet& target, const fs::path& folder,
                               const FlatFieldOptions& options) {
  const auto fail = [&](const std::string& fault) { throw Error(target.source(), fault); };
  const int width = target.width(), height = target.height();
  const TargetRegion region = MakeTargetRegion(target.MaskRows(0, height), options, fail);
  CheckTargetLights(target.lights(), target.image_names(), fail);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  const auto gain_of = [&](int i, ConstImageView image, std::string& fault) {
    return UnnormalisedGain(image, target.lights()[i].z(), region, options, target.image_names()[i],
                            fault);
  };
  // Pass 1: every light's sums (and faults), the gains discarded.
  std::vector<std::vector<double>> sums(static_cast<std::size_t>(target.size()));
  std::vector<std::string> faults(sums.size());
  progress.Start("flat-field: normalisation", sums.size());
  if (target.next_row() != 0) target.Rewind();
  target.VisitBand(height, [&](int i, ConstImageView image) {
    sums[i] = ChannelSums(gain_of(i, image, faults[i]));
    progress.Advance();
  });
  progress.Finish();
  for (const std::string& fault : faults) {
    if (!fault.empty()) fail(fault);
  }
  const std::vector<float> scales =
      NormalisationScales(sums, static_cast<std::size_t>(width) * height);
  // Pass 2: the gains again (the same bits), normalised and written into a scratch folder beside
  // `folder`, moved into place when every one is written.
  const fs::path parent = folder.parent_path().empty() ? fs::path(".") : folder.parent_path();
  std::error_code error;
  fs::create_directories(parent, error);
  if (error) throw Error(parent, "cannot create the folder: " + error.message());
  const ScratchFolder scratch(parent, folder.filename().string());
  CheckDiskSpace(scratch.path(), sums.size() * ImageFileBytes(width, height, target.channels(), 2),
                 "the flat-field's gain maps");
  progress.Start("flat-field: gains", sums.size());
  target.Rewind();
  target.VisitBand(height, [&](int i, ConstImageView image) {
    std::string fault;
    Image gain = gain_of(i, image, fault);
    Scale(gain, scales);
    WriteGain(scratch.path() / GainFileName(static_cast<std::size_t>(i)), gain);
    progress.Advance();
  });
  progress.Finish();
  WriteJsonFile(scratch.path() / kFlatFieldFile, FlatFieldDescription(target.lights()));
  fs::create_directories(folder, error);
  if (error) throw Error(folder, "cannot create the folder: " + error.message());
  // The gain maps first, the description last: a folder with a flatfield.json is complete.
  for (std::size_t i = 0; i < sums.size(); ++i) {
    fs::rename(scratch.path() / GainFileName(i), folder / GainFileName(i), error);
    if (error) throw Error(folder / GainFileName(i), "cannot move into place: " + error.message());
  }
  fs::rename(scratch.path() / kFlatFieldFile, folder / kFlatFieldFile, error);
  if (error) throw Error(folder / kFlatFieldFile, "cannot move into place: " + error.message());
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
  for (int i = 0; i < flat_field.size(); ++i) {
    WriteGain(folder / GainFileName(static_cast<std::size_t>(i)), flat_field.gain(i));
  }
  WriteJsonFile(folder / kFlatFieldFile, FlatFieldDescription(flat_field.lights()));
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
