#include "calibrate/radiometry/near_light.h"

#include <fmt/format.h>

#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {

std::vector<NearLight> ReadNearLights(const std::filesystem::path& path) {
  std::vector<NearLight> lights;
  std::optional<std::size_t> count;
  for (const auto& [line_number, numbers] : ReadNumberLines(path)) {
    if (numbers.size() == 1 && lights.empty() && !count && numbers[0] >= 1) {
      count = static_cast<std::size_t>(numbers[0]);
      continue;
    }
    if (numbers.size() != 3 && numbers.size() != 4) {
      throw Error(path, fmt::format("line {}: expected \"x y z [intensity]\", found {} numbers",
                                    line_number, numbers.size()));
    }
    NearLight light;
    light.position = Eigen::Vector3d(numbers[0], numbers[1], numbers[2]);
    if (numbers.size() == 4) light.intensity = numbers[3];
    if (!(light.position.z() > 0.0)) {
      throw Error(path, fmt::format("line {}: the light must be above the sample plane (z > 0)",
                                    line_number));
    }
    if (!(light.intensity > 0.0)) {
      throw Error(path, fmt::format("line {}: the intensity must be positive", line_number));
    }
    lights.push_back(light);
  }
  if (lights.empty()) throw Error(path, "no near lights");
  if (count && *count != lights.size()) {
    throw Error(path,
                fmt::format("the first line says {} lights but {} follow", *count, lights.size()));
  }
  return lights;
}

}  // namespace photomat
