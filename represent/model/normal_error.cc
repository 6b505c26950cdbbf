#include "represent/model/normal_error.h"

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <numeric>
#include <vector>

#include "core/error.h"
#include "core/light_direction.h"

namespace photomat {

nlohmann::json NormalErrorStats::ToJson() const {
  return {{"pixels", pixels},
          {"mean_angular_error_deg", mean_degrees},
          {"median_angular_error_deg", median_degrees},
          {"max_angular_error_deg", max_degrees},
          {"fraction_below_5_deg", fraction_below_5_degrees},
          {"fraction_below_10_deg", fraction_below_10_degrees}};
}

NormalErrorStats CompareNormals(const Image& estimated, const Image& truth, const Mask& mask) {
  NormalErrors errors;
  errors.Add(estimated, truth, mask);
  return errors.Summary();
}

void NormalErrors::Add(const Image& estimated, const Image& truth, const Mask& mask) {
  if (estimated.width() != truth.width() || estimated.height() != truth.height()) {
    throw Error(fmt::format("ground-truth normals are {}x{} but the estimate is {}x{}",
                            truth.width(), truth.height(), estimated.width(), estimated.height()));
  }
  if (estimated.channels() < 3 || truth.channels() < 3) {
    throw Error("normal maps need 3 channels (x, y, z)");
  }
  for (std::size_t p = 0; p < truth.pixel_count(); ++p) {
    if (mask.width() == truth.width() && !mask[p]) continue;
    const auto t = truth.pixel(p);
    const auto e = estimated.pixel(p);
    const Eigen::Vector3d tv(t[0], t[1], t[2]), ev(e[0], e[1], e[2]);
    if (tv.squaredNorm() < 0.25 || ev.squaredNorm() == 0.0) continue;  // outside the truth
    errors_.push_back(AngleBetweenDegrees(tv, ev));
  }
}

NormalErrorStats NormalErrors::Summary() const {
  if (errors_.empty()) throw Error("no pixel has both a ground-truth and an estimated normal");
  std::vector<double> errors = errors_;
  NormalErrorStats stats;
  stats.pixels = errors.size();
  stats.mean_degrees =
      std::accumulate(errors.begin(), errors.end(), 0.0) / static_cast<double>(errors.size());
  const auto count_below = [&](double limit) {
    return static_cast<double>(
               std::count_if(errors.begin(), errors.end(), [&](double e) { return e < limit; })) /
           errors.size();
  };
  stats.fraction_below_5_degrees = count_below(5.0);
  stats.fraction_below_10_degrees = count_below(10.0);
  std::sort(errors.begin(), errors.end());
  const std::size_t n = errors.size();
  stats.median_degrees = n % 2 ? errors[n / 2] : 0.5 * (errors[n / 2 - 1] + errors[n / 2]);
  stats.max_degrees = errors.back();
  return stats;
}

}  // namespace photomat
