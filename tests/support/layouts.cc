#include "tests/support/layouts.h"

#include <fmt/format.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "core/image_io.h"
#include "core/light_direction.h"
#include "core/text_parsing.h"
#include "tests/support/test_support.h"

namespace photomat::testing {

namespace fs = std::filesystem;

void WriteImages(const fs::path& dir, const std::vector<std::string>& names, int width,
                 int height) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    Image image(width, height, 3);
    for (std::size_t p = 0; p < image.pixel_count(); ++p) {
      for (std::size_t c = 0; c < 3; ++c) {
        const std::size_t v = 3 * p + c;  // the sample's index in the file
        image.pixel(p)[c] = static_cast<float>((v * 7 + i * 13) % 50) / 50.0f + 0.1f;
      }
    }
    ImageWriteOptions options;
    options.sample_type = SampleType::kUint16;
    WriteImage(dir / names[i], image, options);
  }
}

std::vector<LayoutWriter> Layouts() {
  return {
      {InputKind::kLpFile,
       [](const fs::path& dir, const auto& names, const auto& lights, int count) {
         std::string text = fmt::format("{}\n", count);
         for (std::size_t i = 0; i < lights.size(); ++i) {
           text += names[i] + " " + lights[i] + "\n";
         }
         WriteFile(dir / "lights.lp", text);
       },
       "lights.lp"},
      {InputKind::kDiligent,
       [](const fs::path& dir, const auto& names, const auto& lights, int count) {
         std::string files, directions, intensities;
         for (int i = 0; i < count; ++i) {
           files += names[i % names.size()] + "\n";
           intensities += "1 1 1\n";
         }
         for (const auto& light : lights) directions += light + "\n";
         WriteFile(dir / "filenames.txt", files);
         WriteFile(dir / "light_directions.txt", directions);
         WriteFile(dir / "light_intensities.txt", intensities);
       },
       "light_directions.txt"},
      {InputKind::kManifest,
       [](const fs::path& dir, const auto& names, const auto& lights, int count) {
         std::string images;
         for (std::size_t i = 0; i < lights.size(); ++i) {
           // JSON wants numbers; anything else goes in quotes (still not a number).
           std::string vector;
           for (auto token : SplitWhitespace(lights[i])) {
             const std::string text(token);
             vector +=
                 (vector.empty() ? "" : ", ") + (ParseNumber(text) ? text : "\"" + text + "\"");
           }
           const std::string intensity = count == static_cast<int>(lights.size()) ? "1" : "[1, 1]";
           images += fmt::format("{}{{\"file\": \"{}\", \"light\": [{}], \"intensity\": {}}}",
                                 i ? ", " : "", names[i], vector, intensity);
         }
         WriteFile(dir / "manifest.json",
                   "{\"format\": \"photomat-capture\", \"images\": [" + images + "]}");
       },
       "manifest.json"},
  };
}

fs::path WriteLargeLambertianCapture(const fs::path& folder, int width, int height) {
  fs::create_directories(folder);
  std::vector<LightDirection> lights;
  for (double slant : {30.0, 45.0, 60.0}) {
    for (int t = 0; t < 12; ++t) lights.push_back(LightDirection::FromSlantTilt(slant, 30.0 * t));
  }
  // Normals of a gently waved surface, and an albedo that varies per channel.
  Image normals(width, height, 3);
  Image albedo(width, height, 3);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double gx = 0.3 * std::cos(x / 37.0), gy = 0.3 * std::sin(y / 53.0);
      const double norm = std::sqrt(gx * gx + gy * gy + 1.0);
      const auto n = normals.pixel(x, y);
      n[0] = static_cast<float>(-gx / norm);
      n[1] = static_cast<float>(-gy / norm);
      n[2] = static_cast<float>(1.0 / norm);
      const auto a = albedo.pixel(x, y);
      for (int c = 0; c < 3; ++c)
        a[c] = 0.3f + 0.2f * c + 0.1f * std::sin((x + 2 * y) / (9.0f + c));
    }
  }
  ImageWriteOptions half;
  half.sample_type = SampleType::kHalf;
  half.exr_compression = ExrCompression::kNone;
  std::string lp = std::to_string(lights.size()) + "\n";
  Image image(width, height, 3);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    const Eigen::Vector3f l = lights[i].vector().cast<float>();
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const auto n = normals.pixel(x, y);
        const float shading = std::max(0.0f, n[0] * l.x() + n[1] * l.y() + n[2] * l.z());
        const auto a = albedo.pixel(x, y);
        const auto out = image.pixel(x, y);
        for (int c = 0; c < 3; ++c) out[c] = a[c] * shading;
      }
    }
    const std::string name = fmt::format("img_{:03}.exr", i);
    WriteImage(folder / name, image, half);
    lp += fmt::format("{} {} {} {}\n", name, l.x(), l.y(), l.z());
  }
  WriteFile(folder / "lights.lp", lp);
  return folder / "lights.lp";
}

}  // namespace photomat::testing
