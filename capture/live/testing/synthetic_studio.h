#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <vector>

#include "capture/live/capture_session.h"
#include "capture/live/testing/emulated_v4l2_device.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/image.h"
#include "core/light_direction.h"

namespace photomat::testing {

// A synthetic sample under a dome of known lights, for the emulated camera to look at: the
// generator's Lambertian rendering of the light that is on (scaled by `brightness`), black with
// every light off.
class SyntheticStudio {
 public:
  SyntheticStudio(SyntheticMaterial material, std::vector<LightDirection> lights,
                  double brightness = 0.85);

  const SyntheticMaterial& material() const { return material_; }
  const std::vector<LightDirection>& lights() const { return lights_; }
  // The radiance with light `number` (1-based) on, or 0 for all off.
  const Image& Render(int number);

  // The light number a command light controller last wrote to `state_file` (e.g. with the
  // template "echo {n} > FILE"); 0 while the file is missing or empty.
  static int ReadLightNumber(const std::filesystem::path& state_file);
  // A scene for EmulatedCameraOptions: the light named in `state_file` at each frame.
  SceneRenderer SceneFromStateFile(std::filesystem::path state_file);

  // The emulated camera of the capture tests: `fourcc` at the material's size, looking at
  // SceneFromStateFile(state_file), with a little noise and a dark level with a fixed pattern.
  EmulatedCameraOptions Camera(const std::filesystem::path& state_file, std::uint32_t fourcc);

 private:
  SyntheticMaterial material_;
  std::vector<LightDirection> lights_;
  double brightness_;
  std::map<int, Image> cache_;
};

// Capture settings that keep the tests fast: 3 frames per light, 3 ms to settle, frames within
// 300 ms, the emulator's reference exposure.
CaptureSettings QuickCaptureSettings();

}  // namespace photomat::testing
