#include "capture/io/capture_manifest.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <memory>

#include "core/error.h"
#include "core/json_file.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr double kSlantTiltAgreementDegrees = 0.05;

// A saved set's images: float and half samples as OpenEXR, integer ones as PNG.
bool WritesExr(SampleType type) { return type == SampleType::kFloat || type == SampleType::kHalf; }

LightDirection ReadLight(const JsonReader& entry) {
  const bool has_vector = entry.Has("light");
  const bool has_angles = entry.Has("slant_deg") || entry.Has("tilt_deg");
  if (!has_vector && !has_angles) {
    entry.Fail("no light: give \"light\": [x, y, z] or \"slant_deg\" and \"tilt_deg\"");
  }
  std::optional<LightDirection> from_vector, from_angles;
  if (has_vector) {
    const std::vector<double> v = entry["light"].Numbers();
    if (v.size() != 3) entry["light"].Fail("expected 3 numbers [x, y, z]");
    if (v[2] < 0.0) entry["light"].Fail("light below the sample plane (z < 0)");
    try {
      from_vector = LightDirection::FromVector(v[0], v[1], v[2]);
    } catch (const Error& error) {
      entry["light"].Fail(error.fault());
    }
  }
  if (has_angles) {
    const double slant = entry["slant_deg"].Number();
    const double tilt = entry["tilt_deg"].Number();
    if (slant < 0.0 || slant > 90.0) entry["slant_deg"].Fail("slant must be in [0, 90] degrees");
    from_angles = LightDirection::FromSlantTilt(slant, tilt);
  }
  if (from_vector && from_angles &&
      from_vector->AngleToDegrees(*from_angles) > kSlantTiltAgreementDegrees) {
    entry.Fail(fmt::format("\"light\" and \"slant_deg\"/\"tilt_deg\" disagree by {:.3f} degrees",
                           from_vector->AngleToDegrees(*from_angles)));
  }
  return from_vector ? *from_vector : *from_angles;
}

std::vector<float> ReadIntensity(const JsonReader& entry) {
  if (!entry.Has("intensity")) return {};
  const JsonReader value = entry["intensity"];
  std::vector<double> numbers =
      value.value().is_array() ? value.Numbers() : std::vector<double>{value.Number()};
  if (numbers.empty()) value.Fail("expected a number or an array of numbers");
  std::vector<float> intensity;
  for (double v : numbers) {
    if (v <= 0.0) value.Fail("intensities must be positive");
    intensity.push_back(static_cast<float>(v));
  }
  return intensity;
}

std::optional<Eigen::Vector3d> ReadLamp(const JsonReader& entry) {
  if (!entry.Has("lamp")) return std::nullopt;
  const JsonReader value = entry["lamp"];
  const std::vector<double> v = value.Numbers();
  if (v.size() != 3) value.Fail("expected 3 numbers [x, y, z] (sample frame, pixels)");
  const Eigen::Vector3d lamp(v[0], v[1], v[2]);
  if (!lamp.allFinite() || !(lamp.z() > 0.0)) {
    value.Fail("the lamp must be above the sample plane (z > 0)");
  }
  return lamp;
}

std::optional<std::string> OptionalString(const JsonReader& reader, const std::string& key) {
  return reader.Has(key) ? std::optional(reader[key].String()) : std::nullopt;
}

}  // namespace

CaptureManifest ReadCaptureManifest(const fs::path& path) {
  const nlohmann::json document = ReadJsonFile(path);
  const JsonReader root(document, path);
  if (!document.is_object()) root.Fail("expected a JSON object");
  if (!root.Has("format") || root["format"].String() != kCaptureManifestFormat) {
    root.Fail(fmt::format("not a photomat capture manifest (\"format\" must be \"{}\")",
                          kCaptureManifestFormat));
  }
  if (root.Has("version") && root["version"].Integer() != 1) {
    root["version"].Fail("unsupported version (this photomat reads version 1)");
  }
  CaptureManifest manifest;
  if (root.Has("colour_space")) {
    manifest.colour_space = ParseColourSpace(root["colour_space"].String());
    if (!manifest.colour_space) root["colour_space"].Fail("expected \"linear\" or \"srgb\"");
  }
  manifest.mask = OptionalString(root, "mask");
  const JsonReader images = root["images"];
  if (images.ArraySize() == 0) images.Fail("no images");
  for (std::size_t i = 0; i < images.ArraySize(); ++i) {
    const JsonReader entry = images[i];
    manifest.images.push_back(
        {entry["file"].String(), ReadLight(entry), ReadIntensity(entry), ReadLamp(entry)});
    if (manifest.images.back().lamp.has_value() != manifest.images.front().lamp.has_value()) {
      entry.Fail("\"lamp\" is given for some images but not for others: give it for all or none");
    }
  }
  if (root.Has("ground_truth")) {
    const JsonReader truth = root["ground_truth"];
    manifest.ground_truth_normals = OptionalString(truth, "normals");
    manifest.ground_truth_albedo = OptionalString(truth, "albedo");
    manifest.ground_truth_height = OptionalString(truth, "height");
  }
  if (root.Has("provenance")) manifest.provenance = document.at("provenance");
  return manifest;
}

void WriteCaptureManifest(const fs::path& path, const CaptureManifest& manifest) {
  nlohmann::json document = {{"format", kCaptureManifestFormat}, {"version", 1}};
  if (manifest.colour_space) document["colour_space"] = ToString(*manifest.colour_space);
  if (manifest.mask) document["mask"] = *manifest.mask;
  nlohmann::json images = nlohmann::json::array();
  for (const CaptureManifestImage& image : manifest.images) {
    nlohmann::json entry = {
        {"file", image.file},
        {"light", {image.light.x(), image.light.y(), image.light.z()}},
        {"slant_deg", image.light.SlantDegrees()},
        {"tilt_deg", image.light.TiltDegrees()},
    };
    if (!image.intensity.empty()) entry["intensity"] = image.intensity;
    if (image.lamp) entry["lamp"] = {image.lamp->x(), image.lamp->y(), image.lamp->z()};
    images.push_back(std::move(entry));
  }
  document["images"] = std::move(images);
  nlohmann::json truth = nlohmann::json::object();
  if (manifest.ground_truth_normals) truth["normals"] = *manifest.ground_truth_normals;
  if (manifest.ground_truth_albedo) truth["albedo"] = *manifest.ground_truth_albedo;
  if (manifest.ground_truth_height) truth["height"] = *manifest.ground_truth_height;
  if (!truth.empty()) document["ground_truth"] = std::move(truth);
  if (!manifest.provenance.is_null()) document["provenance"] = manifest.provenance;
  WriteJsonFile(path, document);
}

struct CaptureBandWriter::Images {
  std::vector<std::unique_ptr<ImageBandWriter>> writers;
};

CaptureBandWriter::CaptureBandWriter(fs::path folder, int height, const SaveSetOptions& options)
    : folder_(std::move(folder)), height_(height), options_(options) {
  std::error_code ec;
  created_folder_ = fs::create_directories(folder_, ec);
  if (ec) throw Error(folder_, fmt::format("cannot create folder: {}", ec.message()));
  manifest_.colour_space = WritesExr(options.sample_type) ? ColourSpace::kLinear : options.encoding;
  manifest_.provenance = options.provenance;
}

CaptureBandWriter::~CaptureBandWriter() {
  images_.reset();  // removes the images' temporaries unless Finish renamed them
  if (created_folder_ && !finished_) {
    std::error_code ec;
    fs::remove(folder_, ec);  // only when empty: fails harmlessly otherwise
  }
}

void CaptureBandWriter::WriteNext(const PhotometricSet& band, Progress* progress) {
  const std::optional<NearLighting>& near = band.near_lighting();
  if (near && (near->first_row != rows_written_ || near->height != height_)) {
    band.Fail("cannot save rows of a capture with near lamps as a capture of its own");
  }
  if (rows_written_ + band.height() > height_) {
    band.Fail(fmt::format("{} rows after {} of {}", band.height(), rows_written_, height_));
  }
  if (!images_) {
    images_ = std::make_unique<Images>();
    const char* extension = WritesExr(options_.sample_type) ? "exr" : "png";
    ImageWriteOptions write;
    write.sample_type = options_.sample_type;
    write.encoding = *manifest_.colour_space;
    for (int i = 0; i < band.size(); ++i) {
      CaptureManifestImage entry{
          fmt::format("{}_{:03}.{}", options_.prefix, i, extension), band.light(i), {}, {}};
      if (!band.intensities().empty()) entry.intensity = band.intensities()[i];
      if (near) entry.lamp = near->lamps[static_cast<std::size_t>(i)].position;
      const Image& image = band.image(i);
      images_->writers.push_back(std::make_unique<ImageBandWriter>(
          folder_ / entry.file, image.width(), height_,
          image.channel_names().empty() ? DefaultChannelNames(image.channels())
                                        : image.channel_names(),
          write));
      manifest_.images.push_back(std::move(entry));
    }
    if (band.mask()) {
      manifest_.mask = "mask.png";
      mask_.emplace(band.width(), height_, false);
    }
  }
  if (band.size() != static_cast<int>(images_->writers.size())) {
    band.Fail(
        fmt::format("a band of {} images for a set of {}", band.size(), images_->writers.size()));
  }
  // The images are encoded in parallel (PNG's compression is the slow part of writing).
  tbb::parallel_for(0, band.size(), [&](int i) {
    images_->writers[static_cast<std::size_t>(i)]->WriteNext(band.image(i).View());
  });
  NullProgress no_progress;
  OrNull(progress, no_progress).Advance(static_cast<std::size_t>(band.size()));
  if (mask_ && band.mask()) {
    for (int y = 0; y < band.height(); ++y) {
      for (int x = 0; x < band.width(); ++x) mask_->Set(x, rows_written_ + y, (*band.mask())(x, y));
    }
  }
  rows_written_ += band.height();
}

CaptureManifest CaptureBandWriter::Finish() {
  if (!images_ || rows_written_ != height_) {
    throw Error(folder_, fmt::format("{} of {} rows written", rows_written_, height_));
  }
  for (const auto& writer : images_->writers) writer->Commit();
  if (mask_) WriteMask(folder_ / *manifest_.mask, *mask_);
  WriteCaptureManifest(folder_ / kCaptureManifestName, manifest_);
  finished_ = true;
  return manifest_;
}

CaptureManifest SavePhotometricSet(const fs::path& folder, const PhotometricSet& set,
                                   const SaveSetOptions& options, Progress* progress) {
  CaptureBandWriter writer(folder, set.height(), options);
  NullProgress no_progress;
  Progress& report = OrNull(progress, no_progress);
  report.Start("write", set.size());
  writer.WriteNext(set, &report);
  report.Finish();
  return writer.Finish();
}

}  // namespace photomat
