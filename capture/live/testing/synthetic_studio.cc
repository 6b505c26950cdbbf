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

EmulatedCameraOptions SyntheticStudio::Camera(const std::filesystem::path& state_file,
                                              std::uint32_t fourcc) {
  EmulatedCameraOptions options;
  options.fourccs = {fourcc};
  options.width = material_.normals.width();
  options.height = material_.normals.height();
  options.scene = SceneFromStateFile(state_file);
  options.noise_sigma = 0.002;
  options.dark_level = 0.03;
  options.dark_pattern = 0.02;
  return options;
}

CaptureSettings QuickCaptureSettings() {
  CaptureSettings settings;
  settings.frames_per_light = 3;
  settings.settle = std::chrono::milliseconds(3);
  settings.frame_timeout = std::chrono::milliseconds(300);
  settings.controls.exposure_us = 10000.0;  // the emulator's reference: scale 1
  return settings;
}

}  // namespace photomat::testing
