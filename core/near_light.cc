#include "core/near_light.h"

namespace photomat {

Eigen::Vector3d SamplePoint(int width, int height, int column, int row, double surface_height) {
  return {column + 0.5 - width / 2.0, height / 2.0 - row - 0.5, surface_height};
}

LightDirection NominalDirection(const NearLight& light) {
  return LightDirection::FromVector(light.position);
}

std::vector<LightDirection> NominalDirections(const std::vector<NearLight>& lights) {
  std::vector<LightDirection> directions;
  for (const NearLight& light : lights) directions.push_back(NominalDirection(light));
  return directions;
}

LampAtPixel NearLighting::At(int image, int column, int row) const {
  const NearLight& lamp = lamps[static_cast<std::size_t>(image)];
  const Eigen::Vector3d direction =
      (lamp.position - SamplePoint(width, height, column, first_row + row)).normalized();
  const double nominal_z = lamp.position.z() / lamp.position.norm();
  return {direction, nominal_z / direction.z()};
}

}  // namespace photomat
