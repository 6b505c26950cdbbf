#include "calibrate/radiometry/response_curve.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/photo.hpp>

#include "core/colour.h"
#include "core/error.h"
#include "core/json_file.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr const char* kResponseFormat = "photomat-response";

}  // namespace

ResponseCurve::ResponseCurve(std::vector<std::vector<double>> tables, std::string source)
    : tables_(std::move(tables)), source_(std::move(source)) {
  if (tables_.empty()) throw Error("a response curve needs at least one channel");
  for (const auto& table : tables_) {
    if (table.size() < 2 || table.size() != tables_.front().size()) {
      throw Error("a response curve needs tables of equal length >= 2 for every channel");
    }
    for (std::size_t code = 0; code < table.size(); ++code) {
      if (!std::isfinite(table[code]) || (code > 0 && table[code] < table[code - 1])) {
        throw Error(
            fmt::format("the response curve must be finite and non-decreasing (code {})", code));
      }
    }
  }
}

ResponseCurve ResponseCurve::Srgb(int channels, int levels) {
  std::vector<double> table(levels);
  for (int code = 0; code < levels; ++code) table[code] = SrgbToLinear(code / double(levels - 1));
  return ResponseCurve(std::vector<std::vector<double>>(channels, table), "srgb");
}

ResponseCurve ResponseCurve::Identity(int channels, int levels) {
  std::vector<double> table(levels);
  for (int code = 0; code < levels; ++code) table[code] = code / double(levels - 1);
  return ResponseCurve(std::vector<std::vector<double>>(channels, table), "identity");
}

double ResponseCurve::ToLinear(int channel, double encoded) const {
  const std::vector<double>& table = tables_[channel];
  const double position = std::clamp(encoded, 0.0, 1.0) * static_cast<double>(table.size() - 1);
  const auto below = std::min(static_cast<std::size_t>(position), table.size() - 2);
  const double t = position - static_cast<double>(below);
  return (1 - t) * table[below] + t * table[below + 1];
}

Image ResponseCurve::Linearise(const Image& encoded) const {
  if (channels() != 1 && channels() != encoded.channels()) {
    throw Error(fmt::format("the response curve has {} channels but the image {}", channels(),
                            encoded.channels()));
  }
  Image linear = encoded;
  tbb::parallel_for(0, linear.height(), [&](int y) {
    for (int x = 0; x < linear.width(); ++x) {
      const auto pixel = linear.pixel(x, y);
      for (std::size_t c = 0; c < pixel.size(); ++c) {
        pixel[c] =
            static_cast<float>(ToLinear(channels() == 1 ? 0 : static_cast<int>(c), pixel[c]));
      }
    }
  });
  return linear;
}

nlohmann::json ResponseCurve::ToJson() const {
  return {{"format", kResponseFormat}, {"version", 1}, {"source", source_}, {"channels", tables_}};
}

ResponseCurve ResponseCurve::FromJson(const nlohmann::json& json, const fs::path& file) {
  const JsonReader reader(json, file);
  if (reader["format"].String() != kResponseFormat) {
    reader["format"].Fail(fmt::format("expected \"{}\"", kResponseFormat));
  }
  std::vector<std::vector<double>> tables;
  const JsonReader channels = reader["channels"];
  for (std::size_t c = 0; c < channels.ArraySize(); ++c) tables.push_back(channels[c].Numbers());
  try {
    return ResponseCurve(std::move(tables), reader.Has("source") ? reader["source"].String() : "");
  } catch (const Error& error) {
    throw error.InFile(file);
  }
}

ResponseCurve RecoverResponseDebevec(const std::vector<Image>& exposures,
                                     const std::vector<double>& times, double smoothness,
                                     int samples) {
  if (exposures.size() < 2) throw Error("a response curve needs at least 2 exposures");
  if (exposures.size() != times.size()) {
    throw Error(fmt::format("{} exposures but {} exposure times", exposures.size(), times.size()));
  }
  const int channels = exposures.front().channels();
  if (channels != 1 && channels != 3) {
    throw Error(fmt::format("exposures need 1 or 3 channels, not {}", channels));
  }
  std::vector<cv::Mat> mats;
  for (const Image& image : exposures) {
    if (!image.SameShape(exposures.front())) throw Error("the exposures differ in size");
    cv::Mat mat(image.height(), image.width(), CV_8UC3);
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) {
        for (int c = 0; c < 3; ++c) {
          const float v = image.at(x, y, channels == 1 ? 0 : c);
          mat.at<cv::Vec3b>(y, x)[c] =
              static_cast<std::uint8_t>(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
        }
      }
    }
    mats.push_back(mat);
  }
  std::vector<float> seconds;
  for (double t : times) {
    if (!(t > 0.0) || !std::isfinite(t)) throw Error("exposure times must be positive");
    seconds.push_back(static_cast<float>(t));
  }
  cv::Mat response;
  cv::createCalibrateDebevec(samples, static_cast<float>(smoothness), false)
      ->process(mats, response, seconds);
  // response: 256 x 1, 3 channels, the exposure (radiance x time) each code stands for.
  std::vector<std::vector<double>> tables(channels, std::vector<double>(256));
  for (int c = 0; c < channels; ++c) {
    double running = 0.0;
    for (int code = 0; code < 256; ++code) {
      running = std::max(running, static_cast<double>(response.at<cv::Vec3f>(code, 0)[c]));
      tables[c][code] = running;
    }
    const double top = tables[c][255];
    if (!(top > 0.0)) throw Error("the recovered response curve is degenerate");
    for (double& v : tables[c]) v /= top;
  }
  return ResponseCurve(std::move(tables), fmt::format("debevec ({} exposures, lambda {})",
                                                      exposures.size(), smoothness));
}

void WriteResponseCurve(const fs::path& path, const ResponseCurve& curve) {
  WriteJsonFile(path, curve.ToJson());
}

ResponseCurve ReadResponseCurve(const fs::path& path) {
  return ResponseCurve::FromJson(ReadJsonFile(path), path);
}

PhotometricSet LineariseSet(const PhotometricSet& set, const ResponseCurve& curve) {
  std::vector<Image> images(set.size());
  tbb::parallel_for(0, set.size(), [&](int i) {
    try {
      images[i] = curve.Linearise(set.image(i));
    } catch (const Error&) {
      images[i] = Image();  // reported below, with the image's name
    }
  });
  for (int i = 0; i < set.size(); ++i) {
    if (images[i].empty()) {
      set.Fail(fmt::format("{}: {} channels, but the response curve has {}", set.image_name(i),
                           set.channels(), curve.channels()));
    }
  }
  PhotometricSet out(std::move(images), set.lights(), set.image_names(), set.source());
  if (set.mask()) out.set_mask(*set.mask());
  if (!set.intensities().empty()) out.set_intensities(set.intensities());
  return out;
}

}  // namespace photomat
