#include "relight/formats/compact_stack.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "relight/formats/interchange.h"  // RefitLights
#include "relight/render/output_folder.h"
#include "represent/stack/stack_band_writer.h"  // StackDescription

namespace photomat {
namespace {

namespace fs = std::filesystem;

fs::path PlaneFileName(int plane, CompactPlaneCoding coding) {
  return fmt::format("map_{:03d}.{}", plane, coding == CompactPlaneCoding::kPng ? "png" : "jpg");
}

// The plane's low and high ends over the mask: minimum and maximum, or the (1 - q) and q
// quantiles.
std::pair<double, double> MaskedRange(std::span<const float> values,
                                      const std::vector<std::size_t>& inside, double quantile) {
  if (inside.empty()) return {0.0, 0.0};
  std::vector<float> masked(inside.size());
  for (std::size_t i = 0; i < inside.size(); ++i) masked[i] = values[inside[i]];
  if (quantile >= 1.0) {
    const auto [low, high] = std::minmax_element(masked.begin(), masked.end());
    return {*low, *high};
  }
  const auto at = [&](double q) {
    const auto index = static_cast<std::ptrdiff_t>(std::lround(q * (masked.size() - 1.0)));
    std::nth_element(masked.begin(), masked.begin() + index, masked.end());
    return static_cast<double>(masked[static_cast<std::size_t>(index)]);
  };
  return {at(1.0 - quantile), at(quantile)};
}

// IMPLEMENTER CHOICE: the planes are written with OpenImageIO directly, as the bytes themselves
// (core's WriteImage takes floats and has no JPEG quality); they are read back with ReadImage.
void WritePlaneFile(const fs::path& path, const CompactPlanes& planes, int plane,
                    const CompactStackOptions& options) {
  auto output = OIIO::ImageOutput::create(path.string());
  OIIO::ImageSpec spec(planes.width, planes.height, 1, OIIO::TypeDesc::UINT8);
  if (options.coding == CompactPlaneCoding::kJpeg) {
    spec.attribute("Compression", fmt::format("jpeg:{}", options.jpeg_quality));
  }
  if (!output || !output->open(path.string(), spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, planes.bytes[plane].data()) || !output->close()) {
    throw Error(path, fmt::format("cannot write the plane: {}",
                                  output ? output->geterror() : OIIO::geterror()));
  }
}

// The stored bytes of one plane file, which must be `width` x `height` with one channel.
std::vector<std::uint8_t> ReadPlaneFile(const fs::path& path, int width, int height) {
  ImageReadOptions read;
  read.colour_space = ColourSpace::kLinear;  // the stored codes / 255, whatever the file's tags
  const LoadedImage loaded = ReadImage(path, read);
  const Image& image = loaded.image;
  if (image.width() != width || image.height() != height || image.channels() != 1 ||
      loaded.info.bits_per_sample != 8) {
    throw Error(path, fmt::format("{}x{} with {} channel(s) of {} bits, the manifest says {}x{} "
                                  "with 1 channel of 8 bits",
                                  image.width(), image.height(), image.channels(),
                                  loaded.info.bits_per_sample, width, height));
  }
  std::vector<std::uint8_t> bytes(image.pixel_count());
  const auto values = image.plane(0);
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    bytes[i] = static_cast<std::uint8_t>(std::clamp(std::lround(values[i] * 255.0f), 0L, 255L));
  }
  return bytes;
}

// IMPLEMENTER CHOICE (issue 19: what is published carries no absolute local path): the source
// is written relative to the compact folder, as a stack's provenance may be.
StackProvenance PublishedProvenance(StackProvenance provenance, const fs::path& folder) {
  const fs::path source(provenance.source);
  if (source.is_absolute()) {
    provenance.source = source.lexically_proximate(fs::absolute(folder)).generic_string();
  }
  return provenance;
}

void CheckOptions(const CompactStackOptions& options) {
  if (options.jpeg_quality < 1 || options.jpeg_quality > 100) {
    throw Error(fmt::format("JPEG quality {} is not in 1..100", options.jpeg_quality));
  }
  if (options.pca_planes < -1) throw Error(fmt::format("{} PCA planes", options.pca_planes));
}

nlohmann::json VectorToJson(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

Eigen::VectorXd VectorFromJson(const JsonReader& json, Eigen::Index size) {
  const std::vector<double> values = json.Numbers();
  if (static_cast<Eigen::Index>(values.size()) != size) {
    json.Fail(fmt::format("expected {} values, got {}", size, values.size()));
  }
  return Eigen::Map<const Eigen::VectorXd>(values.data(), size);
}

}  // namespace

std::string_view ToString(CompactPlaneCoding coding) {
  return coding == CompactPlaneCoding::kPng ? "png" : "jpeg";
}

CompactPlaneCoding ParseCompactPlaneCoding(std::string_view name) {
  if (name == "png") return CompactPlaneCoding::kPng;
  if (name == "jpeg" || name == "jpg") return CompactPlaneCoding::kJpeg;
  throw Error(fmt::format("plane coding \"{}\": expected png or jpeg", name));
}

Mask NonzeroMapsMask(const Image& maps) {
  Mask mask(maps.width(), maps.height(), false);
  for (int c = 0; c < maps.channels(); ++c) {
    const auto plane = maps.plane(c);
    for (std::size_t p = 0; p < plane.size(); ++p) {
      if (!std::isfinite(plane[p])) {
        throw Error(fmt::format("map {} has a non-finite value at pixel ({}, {})",
                                c < static_cast<int>(maps.channel_names().size())
                                    ? maps.channel_names()[c]
                                    : std::to_string(c),
                                p % maps.width(), p / maps.width()));
      }
      if (plane[p] != 0.0f) mask.Set(p, true);
    }
  }
  return mask;
}

CompactPlanes QuantiseMaps(const Image& maps, const Mask& mask, double range_quantile) {
  if (!(range_quantile > 0.5 && range_quantile <= 1.0)) {
    throw Error(fmt::format("range quantile {} is not in (0.5, 1]", range_quantile));
  }
  if (!mask.SameSize(maps)) throw Error("the compact form's mask is not the maps' size");
  CompactPlanes planes;
  planes.width = maps.width();
  planes.height = maps.height();
  planes.channels = maps.channel_names();
  planes.mask = mask;
  const std::vector<std::size_t> inside = mask.SetIndices();
  for (int c = 0; c < maps.channels(); ++c) {
    const auto values = maps.plane(c);
    const auto [low, high] = MaskedRange(values, inside, range_quantile);
    // A constant plane keeps a nonzero step so that decoding never divides by zero.
    const double scale = high > low ? (high - low) / 255.0 : 1.0;
    std::vector<std::uint8_t> bytes(values.size(), 0);
    for (std::size_t p : inside) {
      const long code = std::lround((values[p] - low) / scale);
      bytes[p] = static_cast<std::uint8_t>(std::clamp(code, 0L, 255L));
    }
    planes.bytes.push_back(std::move(bytes));
    planes.scale.push_back(scale);
    planes.bias.push_back(low);
  }
  return planes;
}

Image DequantiseMaps(const CompactPlanes& planes) {
  Image maps(planes.width, planes.height, planes.channels);
  for (int c = 0; c < planes.PlaneCount(); ++c) {
    auto out = maps.plane(c);
    for (std::size_t p = 0; p < out.size(); ++p) {
      if (planes.mask[p]) {
        out[p] = static_cast<float>(planes.bias[c] + planes.scale[c] * planes.bytes[c][p]);
      }
    }
  }
  return maps;
}

Eigen::VectorXd MapWeights(const LoadedStack& stack) {
  const Representation& r = stack.representation;
  const MapLayout& layout = r.layout();
  const int n = r.maps().channels();
  Eigen::VectorXd weights = Eigen::VectorXd::Ones(n);
  if (layout.shading_maps > 0) return weights;
  const std::vector<LightDirection>& lights =
      stack.provenance.capture_lights.empty() ? RefitLights() : stack.provenance.capture_lights;
  Eigen::VectorXd sum_of_squares = Eigen::VectorXd::Zero(layout.basis_size);
  for (const LightDirection& light : lights) {
    sum_of_squares += r.basis().Coefficients(light).cwiseAbs2();
  }
  for (int j = 0; j < layout.GainOffset(); ++j) {
    const double rms = std::sqrt(sum_of_squares[j / layout.BasisMapsPerTerm()] / lights.size());
    if (rms > 0 && std::isfinite(rms)) weights[j] = rms;
  }
  return weights;
}

CompactPca FitMapPca(const Image& maps, const Mask& mask, const Eigen::VectorXd& weights,
                     int planes) {
  const int n = maps.channels();
  if (weights.size() != n) throw Error("one weight per map expected");
  const int k = planes < 0 ? n : planes;
  if (k < 1 || k > n) throw Error(fmt::format("{} PCA planes of {} maps", k, n));
  CompactPca pca;
  pca.channels = maps.channel_names();
  pca.weights = weights;
  const std::vector<std::size_t> inside = mask.SetIndices();
  pca.mean = Eigen::VectorXd::Zero(n);
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd x(n);
  for (std::size_t p : inside) {
    for (int j = 0; j < n; ++j) x[j] = weights[j] * maps.plane(j)[p];
    pca.mean += x;
  }
  if (!inside.empty()) pca.mean /= static_cast<double>(inside.size());
  for (std::size_t p : inside) {
    for (int j = 0; j < n; ++j) x[j] = weights[j] * maps.plane(j)[p] - pca.mean[j];
    covariance.selfadjointView<Eigen::Lower>().rankUpdate(x);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(
      covariance.selfadjointView<Eigen::Lower>());
  // Largest variance first; each axis's sign fixed so its largest entry is positive.
  pca.axes.resize(n, k);
  for (int c = 0; c < k; ++c) {
    Eigen::VectorXd axis = eigen.eigenvectors().col(n - 1 - c);
    Eigen::Index largest;
    axis.cwiseAbs().maxCoeff(&largest);
    pca.axes.col(c) = axis[largest] < 0 ? Eigen::VectorXd(-axis) : axis;
  }
  return pca;
}

Image ProjectMaps(const Image& maps, const Mask& mask, const CompactPca& pca) {
  const int n = static_cast<int>(pca.mean.size());
  const int k = static_cast<int>(pca.axes.cols());
  std::vector<std::string> names;
  for (int c = 0; c < k; ++c) names.push_back(fmt::format("pca.{}", c));
  Image planes(maps.width(), maps.height(), names);
  Eigen::VectorXd x(n);
  for (std::size_t p : mask.SetIndices()) {
    for (int j = 0; j < n; ++j) x[j] = pca.weights[j] * maps.plane(j)[p] - pca.mean[j];
    const Eigen::VectorXd projected = pca.axes.transpose() * x;
    for (int c = 0; c < k; ++c) planes.plane(c)[p] = static_cast<float>(projected[c]);
  }
  return planes;
}

Image ReconstructMaps(const Image& planes, const Mask& mask, const CompactPca& pca) {
  const int n = static_cast<int>(pca.mean.size());
  const int k = static_cast<int>(pca.axes.cols());
  Image maps(planes.width(), planes.height(), pca.channels);
  Eigen::VectorXd projected(k);
  for (std::size_t p : mask.SetIndices()) {
    for (int c = 0; c < k; ++c) projected[c] = planes.plane(c)[p];
    const Eigen::VectorXd x = pca.mean + pca.axes * projected;
    for (int j = 0; j < n; ++j) maps.plane(j)[p] = static_cast<float>(x[j] / pca.weights[j]);
  }
  return maps;
}

bool IsCompactStackFolder(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) && fs::exists(path / kCompactStackManifest, ec);
}

int CompactPlaneCount(const Representation& representation, const CompactStackOptions& options) {
  const int maps = representation.maps().channels();
  return options.pca_planes <= 0 ? maps : std::min(options.pca_planes, maps);
}

void WriteCompactStack(const fs::path& folder, const LoadedStack& stack,
                       const CompactStackOptions& options) {
  const Representation& r = stack.representation;
  if (r.shading()) {
    throw Error(folder, fmt::format("a {} stack is a nonlinear {} shading, which the compact "
                                    "form's 8-bit maps do not hold within a bound: keep its .exr",
                                    r.method(), r.shading()->kind()));
  }
  CheckOptions(options);
  const Mask mask = NonzeroMapsMask(r.maps());
  std::optional<CompactPca> pca;
  if (options.pca_planes != 0) {
    pca = FitMapPca(r.maps(), mask, MapWeights(stack), CompactPlaneCount(r, options));
  }
  const CompactPlanes planes = QuantiseMaps(pca ? ProjectMaps(r.maps(), mask, *pca) : r.maps(),
                                            mask, options.range_quantile);
  nlohmann::ordered_json manifest;
  manifest["format"] = kCompactStackFormat;
  manifest["version"] = 1;
  manifest["width"] = planes.width;
  manifest["height"] = planes.height;
  manifest["coding"] = ToString(options.coding);
  if (options.coding == CompactPlaneCoding::kJpeg) manifest["quality"] = options.jpeg_quality;
  manifest["mask"] = "mask.png";
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (int c = 0; c < planes.PlaneCount(); ++c) {
    list.push_back({{"file", PlaneFileName(c, options.coding).string()},
                    {"channel", planes.channels[c]},
                    {"scale", planes.scale[c]},
                    {"bias", planes.bias[c]}});
  }
  manifest["planes"] = std::move(list);
  if (pca) {
    manifest["pca"] = {{"channels", pca->channels},
                       {"weights", VectorToJson(pca->weights)},
                       {"mean", VectorToJson(pca->mean)},
                       {"axes", MatrixToJson(pca->axes)}};
  }
  nlohmann::json description = StackDescription(r, PublishedProvenance(stack.provenance, folder));
  description.erase("extra_layers");
  manifest["stack"] = std::move(description);
  WriteFolderAtomically(
      folder, kCompactStackManifest, kCompactStackFormat, [&](const fs::path& temp) {
        WriteMask(temp / "mask.png", planes.mask);
        for (int c = 0; c < planes.PlaneCount(); ++c) {
          WritePlaneFile(temp / PlaneFileName(c, options.coding), planes, c, options);
        }
        WriteTextFileAtomically(temp / kCompactStackManifest, manifest.dump(1) + "\n");
      });
}

LoadedStack ReadCompactStack(const fs::path& folder) {
  const fs::path file = folder / kCompactStackManifest;
  const nlohmann::json document = ReadJsonFile(file);
  const JsonReader json(document, file);
  if (!document.is_object() || json["format"].String() != kCompactStackFormat) {
    json.Fail(fmt::format("expected format \"{}\"", kCompactStackFormat));
  }
  if (json["version"].Integer() != 1) json["version"].Fail("unsupported version");
  CompactPlanes planes;
  planes.width = json["width"].Integer();
  planes.height = json["height"].Integer();
  if (planes.width <= 0 || planes.height <= 0 || planes.width > 65535 || planes.height > 65535) {
    throw Error(file, fmt::format("image size {}x{} is not valid", planes.width, planes.height));
  }
  ParseCompactPlaneCoding(json["coding"].String());
  const std::string mask_name = json["mask"].String();
  if (mask_name.empty() || fs::path(mask_name).has_parent_path()) {
    json["mask"].Fail(fmt::format("\"{}\" is not a file name in the folder", mask_name));
  }
  const fs::path mask_file = folder / mask_name;
  planes.mask = ReadMask(mask_file);
  if (planes.mask.width() != planes.width || planes.mask.height() != planes.height) {
    throw Error(mask_file, fmt::format("{}x{}, the manifest says {}x{}", planes.mask.width(),
                                       planes.mask.height(), planes.width, planes.height));
  }
  const JsonReader list = json["planes"];
  if (list.ArraySize() == 0) list.Fail("no planes");
  for (std::size_t i = 0; i < list.ArraySize(); ++i) {
    const JsonReader plane = list[i];
    planes.channels.push_back(plane["channel"].String());
    const double scale = plane["scale"].Number();
    if (!(scale > 0)) plane["scale"].Fail("the scale must be positive");
    planes.scale.push_back(scale);
    planes.bias.push_back(plane["bias"].Number());
    const std::string name = plane["file"].String();
    if (name.empty() || fs::path(name).has_parent_path()) {
      plane["file"].Fail(fmt::format("\"{}\" is not a file name in the folder", name));
    }
    planes.bytes.push_back(ReadPlaneFile(folder / name, planes.width, planes.height));
  }
  Image maps = DequantiseMaps(planes);
  if (json.Has("pca")) {
    const JsonReader pca_json = json["pca"];
    CompactPca pca;
    const JsonReader channels = pca_json["channels"];
    for (std::size_t i = 0; i < channels.ArraySize(); ++i) {
      pca.channels.push_back(channels[i].String());
    }
    const auto n = static_cast<Eigen::Index>(pca.channels.size());
    pca.weights = VectorFromJson(pca_json["weights"], n);
    if ((pca.weights.array() <= 0).any()) pca_json["weights"].Fail("weights must be positive");
    pca.mean = VectorFromJson(pca_json["mean"], n);
    pca.axes = MatrixFromJson(pca_json["axes"], planes.PlaneCount());
    if (pca.axes.rows() != n) {
      pca_json["axes"].Fail(fmt::format("{} rows for {} maps", pca.axes.rows(), n));
    }
    maps = ReconstructMaps(maps, planes.mask, pca);
  }
  // The description names the maps it needs; SelectChannels reports one that no plane holds.
  return StackFromDescription(json["stack"].value().dump(), maps, file);
}

}  // namespace photomat
