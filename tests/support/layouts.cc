#include "tests/support/layouts.h"

#include <fmt/format.h>

#include "core/image_io.h"
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

}  // namespace photomat::testing
