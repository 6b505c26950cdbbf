#include "apps/cli_support.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <optional>

#include "core/colour.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/memory_limits.h"
#include "core/text_parsing.h"
#include "relight/render/relight.h"

namespace photomat::app {

LightDirection ParseSlantTilt(const std::string& text) {
  const auto comma = text.find(',');
  const auto slant = comma == std::string::npos ? std::nullopt : ParseNumber(text.substr(0, comma));
  const auto tilt = comma == std::string::npos ? std::nullopt : ParseNumber(text.substr(comma + 1));
  if (!slant || !tilt) throw Error(fmt::format("\"{}\": expected SLANT,TILT in degrees", text));
  if (*slant < 0.0 || *slant > 90.0) {
    throw Error(fmt::format("\"{}\": slant must be in [0, 90] degrees", text));
  }
  return LightDirection::FromSlantTilt(*slant, *tilt);
}

std::vector<LightDirection> ParseSweep(const std::string& text) {
  const auto comma = text.find(',');
  const auto count = ParseNumber(text.substr(0, comma));
  const auto slant =
      comma == std::string::npos ? std::optional(60.0) : ParseNumber(text.substr(comma + 1));
  if (!count || *count != static_cast<int>(*count) || !slant) {
    throw Error(fmt::format("\"{}\": expected COUNT[,SLANT], e.g. 36,60", text));
  }
  return LightSweep(static_cast<int>(*count), *slant);
}

std::pair<int, int> ParseSize(const std::string& text) {
  const auto x = text.find('x');
  const auto w = x == std::string::npos ? std::nullopt : ParseNumber(text.substr(0, x));
  const auto h = x == std::string::npos ? std::nullopt : ParseNumber(text.substr(x + 1));
  if (!w || !h || *w != static_cast<int>(*w) || *h != static_cast<int>(*h) || *w < 1 || *h < 1) {
    throw Error(fmt::format("\"{}\": expected a size WIDTHxHEIGHT, e.g. 128x128", text));
  }
  return {static_cast<int>(*w), static_cast<int>(*h)};
}

std::pair<double, double> ParseRange(std::string_view option, const std::string& text) {
  const auto comma = text.find(',');
  const auto low = ParseNumber(text.substr(0, comma));
  const auto high = comma == std::string::npos ? low : ParseNumber(text.substr(comma + 1));
  if (!low || !high) {
    throw Error(fmt::format("{} \"{}\": expected MIN,MAX or one number", option, text));
  }
  return {*low, *high};
}

void WarnAboutClippedPixels(const std::vector<std::size_t>& saturated,
                            const std::vector<std::string>& names) {
  std::size_t images = 0, worst = 0;
  std::size_t worst_index = 0;
  for (std::size_t i = 0; i < saturated.size(); ++i) {
    if (saturated[i] == 0) continue;
    ++images;
    if (saturated[i] > worst) worst = saturated[i], worst_index = i;
  }
  if (images > 0) {
    spdlog::warn(
        "{} of {} images have clipped pixels (most: {} in {}); clipped values are not "
        "measurements and bias least-squares fits",
        images, saturated.size(), worst, names[worst_index]);
  }
}

LoadOptions SetInputOptions::ToLoadOptions() const {
  LoadOptions load;
  load.apply_intensities = !raw_intensities;
  if (!colour_space.empty()) {
    load.untagged_colour_space = ParseColourSpace(colour_space);
    if (!load.untagged_colour_space) throw Error("--colour-space: expected linear or srgb");
  }
  return load;
}

void AddSetInputOptions(CLI::App& command, SetInputOptions& options) {
  command
      .add_option("input", options.input,
                  "Photometric set: a folder, a .lp file, a manifest.json or a DiLiGenT folder")
      ->required();
  command.add_flag("--ignore-intensities", options.raw_intensities,
                   "Do not divide the images by the light intensities the input gives");
  command.add_option("--colour-space", options.colour_space,
                     "How untagged integer images encode light: linear or srgb (a file's own "
                     "colour tags come first; default: what the manifest says, else 8-bit "
                     "sRGB, 16-bit linear)");
}

LoadedSet LoadSetForCommand(const std::filesystem::path& input, const LoadOptions& options) {
  TerminalProgressBar bar;
  LoadOptions with_progress = options;
  with_progress.progress = &bar;
  LoadedSet loaded = LoadPhotometricSet(input, with_progress);
  WarnAboutClippedPixels(loaded.saturated_pixels, loaded.set.image_names());
  return loaded;
}

void AddExrCompressionOption(CLI::App& command, std::string& name, bool offer_auto) {
  command
      .add_option("--exr-compression", name,
                  offer_auto ? "Compression of the map stacks (lossless): auto (rle for a masked "
                               "set, none for full frames), none, rle, zips, zip or piz"
                             : "Compression of the map stack (lossless): none, rle, zips, zip or "
                               "piz")
      ->capture_default_str();
}

ExrCompression FittedStackCompression(std::string_view name, bool masked) {
  if (name != kAutoExrCompression) return ParseExrCompression(name);
  return masked ? ExrCompression::kRle : ExrCompression::kNone;
}

void AddBandMemoryOption(CLI::App& command, std::size_t& memory_mb, std::string_view bands,
                         std::size_t minimum) {
  command.add_option(
      "--memory", memory_mb,
      fmt::format("Memory in MB for {} (default: {} MB, at most half the physical memory or of "
                  "this process's memory limits, here {} MB)",
                  bands, kFastBandMemory >> 20, DefaultMemoryBudget(minimum) >> 20));
}

void CreateFolder(const std::filesystem::path& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw Error(folder, fmt::format("cannot create folder: {}", ec.message()));
}

std::string FormatEvaluationTable(const std::vector<MethodEvaluation>& evaluations) {
  const auto any = [&](auto has) {
    return std::any_of(evaluations.begin(), evaluations.end(), has);
  };
  const bool normals = any([](const auto& e) { return e.normals.has_value(); });
  const bool psnr = any([](const auto& e) { return e.psnr_prediction.has_value(); });
  const bool ssim = any([](const auto& e) { return e.ssim_prediction.has_value(); });
  const bool colour = any([](const auto& e) { return e.delta_e2000_prediction.has_value(); });
  const auto cell = [](const std::optional<double>& value, int width, int decimals) {
    return fmt::format(" {:>{}}", value ? fmt::format("{:.{}f}", *value, decimals) : "-", width);
  };
  std::string table =
      fmt::format("{:<10} {:>14} {:>14}", "method", "eta_reconstr.", "eta_predict.");
  if (psnr) table += fmt::format(" {:>8}", "psnr_dB");
  if (ssim) table += fmt::format(" {:>7}", "ssim");
  if (colour) table += fmt::format(" {:>7}", "dE2000");
  if (normals)
    table += fmt::format(" {:>10} {:>10} {:>7} {:>7}", "mean_deg", "median_deg", "<5deg", "<10deg");
  table += "\n";
  for (const MethodEvaluation& e : evaluations) {
    table += fmt::format("{:<10} {:>14.6f}{}", e.method.Name(), e.eta_reconstruction,
                         cell(e.eta_prediction, 14, 6));
    if (psnr) table += cell(e.psnr_prediction, 8, 2);
    if (ssim) table += cell(e.ssim_prediction, 7, 4);
    if (colour) table += cell(e.delta_e2000_prediction, 7, 3);
    if (e.normals) {
      table += fmt::format(" {:>10.3f} {:>10.3f} {:>6.1f}% {:>6.1f}%", e.normals->mean_degrees,
                           e.normals->median_degrees, 100 * e.normals->fraction_below_5_degrees,
                           100 * e.normals->fraction_below_10_degrees);
    }
    table += "\n";
  }
  return table;
}

int WriteSyntheticSet(const std::filesystem::path& folder, const GenerateOptions& options) {
  CreateFolder(folder);
  const std::vector<LightDirection> lights =
      options.lights ? ReadLightDirections(*options.lights) : ThesisLightGrid();
  const SyntheticMaterial material = MakeSyntheticMaterial(options.material);
  const PhotometricSet set = RenderSyntheticCapture(material, lights, options.render);
  SaveSetOptions save;
  save.sample_type = options.exr ? SampleType::kFloat : SampleType::kUint16;
  save.provenance = {
      {"generator", "photomat generate"},
      {"pattern", ToString(options.material.pattern)},
      {"size", {options.material.width, options.material.height}},
      {"max_slope_deg", options.material.max_slope_degrees},
      {"seed", options.material.seed},
      {"shadows", options.render.shadows},
      {"specular", options.render.specular},
      {"shininess", options.render.shininess},
      {"noise_sigma", options.render.noise_sigma},
  };
  WriteSyntheticCapture(folder, material, set, save);
  return set.size();
}

}  // namespace photomat::app
