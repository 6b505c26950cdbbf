#include "capture/live/testing/synthetic_studio.h"

#include <fmt/format.h>

#include <fstream>

#include "core/error.h"

namespace photomat::testing {

SyntheticStudio::SyntheticStudio(SyntheticMaterial material, std::vector<LightDirection> lights,
                                 double brightness)
    : material_(std::move(material)), lights_(std::move(lights)), brightness_(brightness) {}

const Image& SyntheticStudio::Render(int number) {
  if (number < 0 || number > static_cast<int>(lights_.size())) {
    throw Error(fmt::format("studio: no light {} (it has {})", number, lights_.size()));
  }
  auto it = cache_.find(number);
  if (it != cache_.end()) return it->second;
  Image image;
  if (number == 0) {
    image = Image(material_.albedo.width(), material_.albedo.height(), 3);
  } else {
    image = RenderSyntheticCapture(material_, {lights_[number - 1]}).image(0);
    for (float& v : image.values()) v *= static_cast<float>(brightness_);
  }
  return cache_.emplace(number, std::move(image)).first->second;
}

int SyntheticStudio::ReadLightNumber(const std::filesystem::path& state_file) {
  std::ifstream in(state_file);
  int number = 0;
  if (in >> number) return number;
  return 0;
}

SceneRenderer SyntheticStudio::SceneFromStateFile(std::filesystem::path state_file) {
  return [this, state_file] { return Render(ReadLightNumber(state_file)); };
}

}  // namespace photomat::testing
