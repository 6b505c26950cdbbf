#include "capture/io/load_photometric_set.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "capture/io/capture_manifest.h"
#include "capture/io/diligent.h"
#include "capture/io/lp_file.h"
#include "core/enum_names.h"
#include "core/error.h"
#include "core/image_io.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// A set described by any light file, before its images are read.
struct SetDescription {
  std::vector<fs::path> image_files;
  std::vector<LightDirection> lights;
  std::vector<std::vector<float>> intensities;  // empty: none given
  std::optional<fs::path> mask;
  std::optional<ColourSpace> colour_space;
  std::optional<fs::path> ground_truth_normals;
};

SetDescription DescribeLpSet(const fs::path& lp) {
  SetDescription description;
  for (const LightFileEntry& entry : ReadLpFile(lp)) {
    const fs::path image = ResolveImagePath(lp.parent_path(), entry.image);
    std::error_code ec;
    if (!fs::exists(image, ec)) {
      throw Error(lp, fmt::format("line {}: image \"{}\" not found (looked for {})", entry.line,
                                  entry.image, image.string()));
    }
    description.image_files.push_back(image);
    description.lights.push_back(entry.light);
  }
  return description;
}

SetDescription DescribeManifestSet(const fs::path& path) {
  const CaptureManifest manifest = ReadCaptureManifest(path);
  const fs::path folder = path.parent_path();
  SetDescription description;
  bool any_intensity = false;
  for (const CaptureManifestImage& image : manifest.images) {
    description.image_files.push_back(folder / image.file);
    description.lights.push_back(image.light);
    description.intensities.push_back(image.intensity.empty() ? std::vector<float>{1.0f}
                                                              : image.intensity);
    any_intensity |= !image.intensity.empty();
  }
  if (!any_intensity) description.intensities.clear();
  if (manifest.mask) description.mask = folder / *manifest.mask;
  description.colour_space = manifest.colour_space;
  if (manifest.ground_truth_normals) {
    description.ground_truth_normals = folder / *manifest.ground_truth_normals;
  }
  return description;
}

SetDescription DescribeDiligentSet(const fs::path& folder) {
  DiligentFiles files = ReadDiligentFiles(folder);
  SetDescription description;
  description.image_files = std::move(files.images);
  description.lights = std::move(files.lights);
  description.intensities = std::move(files.intensities);
  description.mask = files.mask;
  description.ground_truth_normals = files.ground_truth_normals;
  return description;
}

}  // namespace

std::string_view ToString(InputKind kind) {
  static constexpr std::array<NamedValue<InputKind>, 3> kNames = {
      {{InputKind::kLpFile, "lp"},
       {InputKind::kDiligent, "diligent"},
       {InputKind::kManifest, "manifest"}}};
  return NameOf(kind, kNames);
}

InputLocation DetectInput(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path, "no such file or folder");
  if (!fs::is_directory(path, ec)) {
    const std::string name = path.filename().string();
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    if (extension == ".json") return {InputKind::kManifest, path};
    if (extension == ".lp") return {InputKind::kLpFile, path};
    if (name == "filenames.txt" || name == "light_directions.txt") {
      return {InputKind::kDiligent, path.parent_path()};
    }
    throw Error(path, "not a light file: expected manifest.json, a .lp file or a DiLiGenT folder");
  }
  if (fs::exists(path / kCaptureManifestName, ec)) {
    return {InputKind::kManifest, path / kCaptureManifestName};
  }
  if (fs::exists(path / "light_directions.txt", ec) || fs::exists(path / "filenames.txt", ec)) {
    return {InputKind::kDiligent, path};
  }
  std::vector<fs::path> lp_files;
  for (const auto& entry : fs::directory_iterator(path, ec)) {
    std::string extension = entry.path().extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    if (extension == ".lp") lp_files.push_back(entry.path());
  }
  std::sort(lp_files.begin(), lp_files.end());
  if (lp_files.size() == 1) return {InputKind::kLpFile, lp_files.front()};
  if (lp_files.size() > 1) {
    std::string names;
    for (const auto& file : lp_files)
      names += (names.empty() ? "" : ", ") + file.filename().string();
    throw Error(path, fmt::format("several light files ({}); name the one to use", names));
  }
  throw Error(path,
              "no light file found: expected manifest.json, a .lp file, or DiLiGenT's "
              "filenames.txt and light_directions.txt");
}

std::vector<LightDirection> ReadLightDirections(const fs::path& path) {
  const InputLocation input = DetectInput(path);
  switch (input.kind) {
    case InputKind::kLpFile: {
      std::vector<LightDirection> lights;
      for (const LightFileEntry& entry : ReadLpFile(input.file)) lights.push_back(entry.light);
      return lights;
    }
    case InputKind::kDiligent:
      return ReadDiligentFiles(input.file).lights;
    case InputKind::kManifest:
      break;
  }
  std::vector<LightDirection> lights;
  for (const auto& image : ReadCaptureManifest(input.file).images) lights.push_back(image.light);
  return lights;
}

LoadedSet LoadPhotometricSet(const fs::path& path, const LoadOptions& options) {
  const InputLocation input = DetectInput(path);
  SetDescription description;
  switch (input.kind) {
    case InputKind::kLpFile:
      description = DescribeLpSet(input.file);
      break;
    case InputKind::kDiligent:
      description = DescribeDiligentSet(input.file);
      break;
    case InputKind::kManifest:
      description = DescribeManifestSet(input.file);
      break;
  }

  ImageReadOptions read;
  read.colour_space = options.colour_space;
  read.untagged_colour_space =
      options.untagged_colour_space ? options.untagged_colour_space : description.colour_space;
  const std::size_t count = description.image_files.size();
  std::vector<Image> images(count);
  std::vector<std::size_t> saturated(count);
  std::vector<ImageEncodingRecord> encodings(count);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("load", count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    LoadedImage loaded = ReadImage(description.image_files[i], read);
    images[i] = std::move(loaded.image);
    saturated[i] = loaded.info.saturated_pixels;
    const SampleEncoding& encoding = loaded.info.encoding;
    encodings[i] = {description.image_files[i].filename().string(), encoding.Name(),
                    encoding.decided_by, encoding.evidence};
    progress.Advance();
  });
  progress.Finish();
  WarnIfEncodingsDisagree(encodings);

  std::vector<std::string> names;
  for (const auto& file : description.image_files) names.push_back(file.string());
  // The set's source is the file its lights came from: messages about the lights point there.
  const fs::path source =
      input.kind == InputKind::kDiligent ? input.file / "light_directions.txt" : input.file;
  LoadedSet loaded{
      PhotometricSet(std::move(images), std::move(description.lights), std::move(names), source),
      input.kind, std::move(saturated), description.ground_truth_normals, std::move(encodings)};
  if (description.mask) {
    try {
      loaded.set.set_mask(ReadMask(*description.mask));
    } catch (const Error& error) {
      throw Error(*description.mask, error.fault());
    }
  }
  if (!description.intensities.empty()) {
    loaded.set.set_intensities(std::move(description.intensities));
    if (options.apply_intensities) loaded.set.ApplyIntensities();
  }
  return loaded;
}

}  // namespace photomat
