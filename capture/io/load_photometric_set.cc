#include "capture/io/load_photometric_set.h"

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <utility>

#include "capture/io/capture_manifest.h"
#include "capture/io/diligent.h"
#include "capture/io/lp_file.h"
#include "capture/io/streamed_set.h"
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
  std::vector<NearLight> near_lamps;  // empty: distant lights
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
    // The lamps' intensities were divided out with their fall-off: position alone matters.
    if (image.lamp) description.near_lamps.push_back(NearLight{*image.lamp, 1.0});
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

StreamedSet OpenStreamedSet(const fs::path& path, const LoadOptions& options) {
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
  StreamedSet set;
  set.kind_ = input.kind;
  // The set's source is the file its lights came from: messages about the lights point there.
  set.source_ =
      input.kind == InputKind::kDiligent ? input.file / "light_directions.txt" : input.file;
  if (description.image_files.empty()) {
    throw Error(set.source_, "a photometric set needs at least one image");
  }
  if (description.image_files.size() != description.lights.size()) {
    throw Error(set.source_,
                fmt::format("{} images but {} light directions", description.image_files.size(),
                            description.lights.size()));
  }
  set.read_.colour_space = options.colour_space;
  set.read_.untagged_colour_space =
      options.untagged_colour_space ? options.untagged_colour_space : description.colour_space;
  set.files_ = description.image_files;
  for (const auto& file : set.files_) set.names_.push_back(file.string());
  set.readers_.resize(set.files_.size());
  tbb::parallel_for(std::size_t{0}, set.files_.size(), [&](std::size_t i) {
    set.readers_[i] = ImageBandReader(set.files_[i], set.read_);
  });
  const ImageBandReader& first = set.readers_.front();
  for (std::size_t i = 1; i < set.readers_.size(); ++i) {
    const ImageBandReader& image = set.readers_[i];
    if (image.width() != first.width() || image.height() != first.height()) {
      throw Error(set.source_,
                  fmt::format("{} is {}x{} but {} is {}x{}: all images of a set must have one size",
                              set.names_[i], image.width(), image.height(), set.names_[0],
                              first.width(), first.height()));
    }
    if (image.channels() != first.channels()) {
      throw Error(set.source_, fmt::format("{} has {} channels but {} has {}", set.names_[i],
                                           image.channels(), set.names_[0], first.channels()));
    }
  }
  set.lights_ = std::move(description.lights);
  // Each image's encoding was decided as its reader opened it (core/sample_encoding); a set
  // decoded in several ways is warned about once here, for the in-memory and streamed paths alike.
  WarnIfEncodingsDisagree(set.encodings());
  if (description.mask) {
    try {
      Mask mask = ReadMask(*description.mask);
      if (mask.width() != first.width() || mask.height() != first.height()) {
        throw Error(set.source_,
                    fmt::format("the mask is {}x{} but the images are {}x{}", mask.width(),
                                mask.height(), first.width(), first.height()));
      }
      if (mask.CountSet() == 0) throw Error(set.source_, "the mask selects no pixel");
      set.mask_ = std::move(mask);
    } catch (const Error& error) {
      throw Error(*description.mask, error.fault());
    }
  }
  set.intensities_ = std::move(description.intensities);
  set.apply_intensities_ = options.apply_intensities;
  set.ground_truth_normals_ = description.ground_truth_normals;
  set.near_lamps_ = std::move(description.near_lamps);
  return set;
}

std::size_t StreamedSet::SelectedPixels(int first, int rows) const {
  if (!mask_) return static_cast<std::size_t>(rows) * width();
  std::size_t count = 0;
  const std::size_t offset = static_cast<std::size_t>(first) * width();
  for (std::size_t p = 0; p < static_cast<std::size_t>(rows) * width(); ++p) {
    count += (*mask_)[offset + p] ? 1 : 0;
  }
  return count;
}

Mask StreamedSet::MaskRows(int first, int rows) const {
  Mask mask(width(), rows, !mask_);
  if (!mask_) return mask;
  const std::size_t offset = static_cast<std::size_t>(first) * width();
  for (std::size_t p = 0; p < mask.pixel_count(); ++p) mask.Set(p, (*mask_)[offset + p]);
  return mask;
}

std::vector<std::size_t> StreamedSet::SelectedPixelIndices(int first, int rows) const {
  const std::size_t pixels = static_cast<std::size_t>(rows) * width();
  std::vector<std::size_t> indices;
  indices.reserve(SelectedPixels(first, rows));
  const std::size_t offset = static_cast<std::size_t>(first) * width();
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!mask_ || (*mask_)[offset + p]) indices.push_back(p);
  }
  return indices;
}

void StreamedSet::VisitBand(int rows,
                            const std::function<void(int image, ConstImageView band)>& use) {
  tbb::enumerable_thread_specific<Image> scratch;
  tbb::parallel_for(std::size_t{0}, readers_.size(), [&](std::size_t i) {
    Image& band = scratch.local();
    if (band.height() != rows) band = Image(width(), rows, channels());
    readers_[i].ReadNext(band.View());
    use(static_cast<int>(i), std::as_const(band).View());
  });
}

void StreamedSet::ReadBandInto(std::span<const ImageView> destinations, Progress* progress) {
  if (destinations.size() != readers_.size()) {
    throw Error(source_, fmt::format("{} band views for a set of {} images", destinations.size(),
                                     readers_.size()));
  }
  const int rows = destinations.empty() ? 0 : destinations.front().height();
  for (const ImageView& view : destinations) {
    if (view.height() != rows) {
      throw Error(source_, "the band views of one band differ in height");
    }
  }
  tbb::parallel_for(std::size_t{0}, readers_.size(), [&](std::size_t i) {
    readers_[i].ReadNext(destinations[i]);
    if (progress) progress->Advance();
  });
}

PhotometricSet StreamedSet::ReadBand(int rows, bool raw, Progress* progress) {
  const int first = next_row();
  std::vector<Image> images(readers_.size());
  std::vector<ImageView> views(readers_.size());
  // Allocated (zero-filled) in parallel too: touching the pages is a share of the band's time.
  tbb::parallel_for(std::size_t{0}, readers_.size(), [&](std::size_t i) {
    images[i] = Image(width(), rows, channels());
    // The file's channel names, as ReadImage gives them (stacks and samples keep them).
    if (!readers_[i].channel_names().empty()) {
      images[i].set_channel_names(readers_[i].channel_names());
    }
    views[i] = images[i].View();
  });
  ReadBandInto(views, progress);
  PhotometricSet band(std::move(images), lights_, names_, source_);
  if (mask_) {
    Mask mask = MaskRows(first, rows);
    // A band outside the mask selects no pixel (SelectedPixels: callers skip its fit).
    if (mask.CountSet() > 0) band.set_mask(std::move(mask));
  }
  if (!near_lamps_.empty()) band.set_near_lighting({near_lamps_, width(), height(), first});
  if (!intensities_.empty()) {
    band.set_intensities(intensities_);
    if (apply_intensities_ && !raw) band.ApplyIntensities();
  }
  return band;
}

void StreamedSet::Rewind() {
  tbb::parallel_for(std::size_t{0}, readers_.size(),
                    [&](std::size_t i) { readers_[i] = ImageBandReader(files_[i], read_); });
}

StreamedSet StreamedSet::Subset(std::span<const int> images) const {
  if (images.empty()) throw Error(source_, "a subset of a photometric set needs an image");
  StreamedSet subset;
  subset.read_ = read_;
  subset.source_ = source_;
  subset.kind_ = kind_;
  subset.mask_ = mask_;
  subset.apply_intensities_ = apply_intensities_;
  subset.ground_truth_normals_ = ground_truth_normals_;
  subset.near_lamps_ = near_lamps_;
  for (int image : images) {
    if (image < 0 || image >= size()) {
      throw Error(source_, fmt::format("image {} is not in the set (0 to {})", image, size() - 1));
    }
    const auto i = static_cast<std::size_t>(image);
    subset.files_.push_back(files_[i]);
    subset.names_.push_back(names_[i]);
    subset.lights_.push_back(lights_[i]);
    if (!intensities_.empty()) subset.intensities_.push_back(intensities_[i]);
  }
  subset.readers_.resize(subset.files_.size());
  subset.Rewind();
  return subset;
}

std::vector<ImageEncodingRecord> StreamedSet::encodings() const {
  std::vector<ImageEncodingRecord> records;
  for (const ImageBandReader& reader : readers_) {
    const SampleEncoding& encoding = reader.info().encoding;
    records.push_back({reader.path().filename().string(), encoding.Name(), encoding.decided_by,
                       encoding.evidence});
  }
  return records;
}

std::vector<std::size_t> StreamedSet::SaturatedPixels() const {
  std::vector<std::size_t> counts;
  for (const ImageBandReader& reader : readers_) counts.push_back(reader.info().saturated_pixels);
  return counts;
}

LoadedSet LoadPhotometricSet(const fs::path& path, const LoadOptions& options) {
  StreamedSet streamed = OpenStreamedSet(path, options);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("load", static_cast<std::size_t>(streamed.size()));
  PhotometricSet set = streamed.ReadBand(streamed.height(), true, &progress);
  progress.Finish();
  LoadedSet loaded{std::move(set), streamed.kind(), streamed.SaturatedPixels(),
                   streamed.ground_truth_normals(), streamed.encodings()};
  if (streamed.apply_intensities() && !streamed.intensities().empty()) {
    loaded.set.ApplyIntensities();
  }
  return loaded;
}

}  // namespace photomat
