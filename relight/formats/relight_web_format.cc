#include "relight/formats/relight_web_format.h"

#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <numeric>
#include <span>

#include "core/atomic_file.h"
#include "core/colour.h"
#include "core/error.h"
#include "core/json_file.h"
#include "core/memory_limits.h"
#include "relight/formats/interchange.h"
#include "relight/formats/stack_file.h"
#include "relight/render/output_folder.h"
#include "represent/fitting/observations.h"
#include "represent/model/hsh.h"
#include "represent/model/method.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr int kNoTerm = -1;
// relight's PTM term j (1, lx, ly, lx^2, lx ly, ly^2) as photomat's PtmLightBasis index
// (lx^2, ly^2, lx ly, lx, ly, 1).
constexpr int kPtmTermToPhotomat[6] = {5, 3, 4, 0, 2, 1};

fs::path PlaneFile(const fs::path& folder, int jpeg) {
  return folder / fmt::format("plane_{}.jpg", jpeg);
}

int JpegCount(int planes) { return (planes + 2) / 3; }

// The three planes of plane_N.jpg; a missing third or second plane of the last file reads as 0.
void ReadPlaneJpeg(const fs::path& path, int jpeg, RelightWebStack& stack) {
  auto input = OIIO::ImageInput::open(path.string());
  if (!input) throw Error(path, fmt::format("not a readable JPEG ({})", OIIO::geterror()));
  const OIIO::ImageSpec& spec = input->spec();
  if (spec.width != stack.width || spec.height != stack.height || spec.nchannels != 3) {
    throw Error(path, fmt::format("{}x{} with {} channel(s), info.json says {}x{} RGB", spec.width,
                                  spec.height, spec.nchannels, stack.width, stack.height));
  }
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(stack.width) * stack.height * 3);
  if (!input->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, pixels.data())) {
    throw Error(path, fmt::format("cannot decode: {}", input->geterror()));
  }
  for (int k = 0; k < 3; ++k) {
    const int plane = 3 * jpeg + k;
    if (plane >= stack.PlaneCount()) break;
    auto& bytes = stack.planes[plane];
    for (std::size_t p = 0; p < bytes.size(); ++p) bytes[p] = pixels[3 * p + k];
  }
}

// IMPLEMENTER CHOICE: OpenImageIO's JPEG writer (YCbCr, no chroma subsampling: every plane keeps
// full resolution, as relight-cli writes them). relight writes mrgb planes without the colour
// transform (libjpeg's JCS_RGB), which OpenImageIO cannot; decoders read both alike.
void WritePlaneJpeg(const fs::path& path, int jpeg, const RelightWebStack& stack) {
  const std::size_t pixels = static_cast<std::size_t>(stack.width) * stack.height;
  std::vector<std::uint8_t> rgb(pixels * 3, 0);
  for (int k = 0; k < 3; ++k) {
    const int plane = 3 * jpeg + k;
    if (plane >= stack.PlaneCount()) break;
    for (std::size_t p = 0; p < pixels; ++p) rgb[3 * p + k] = stack.planes[plane][p];
  }
  auto output = OIIO::ImageOutput::create(path.string());
  OIIO::ImageSpec spec(stack.width, stack.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", fmt::format("jpeg:{}", stack.quality));
  spec.attribute("jpeg:subsampling", "4:4:4");
  if (!output || !output->open(path.string(), spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, rgb.data()) || !output->close()) {
    throw Error(path, fmt::format("cannot write the JPEG: {}",
                                  output ? output->geterror() : OIIO::geterror()));
  }
}

RelightWebBasis ParseBasis(const JsonReader& json) {
  const std::string name = json.String();
  for (auto basis : {RelightWebBasis::kPtm, RelightWebBasis::kHsh, RelightWebBasis::kRbf,
                     RelightWebBasis::kBilinear}) {
    if (name == ToString(basis)) return basis;
  }
  json.Fail(
      fmt::format("basis type \"{}\" is not one photomat reads (ptm, hsh, rbf, bilinear)", name));
}

RelightWebColourSpace ParseColourSpace(const JsonReader& json) {
  const std::string name = json.String();
  for (auto space :
       {RelightWebColourSpace::kRgb, RelightWebColourSpace::kLrgb, RelightWebColourSpace::kMrgb}) {
    if (name == ToString(space)) return space;
  }
  json.Fail(fmt::format("colour space \"{}\" is not one photomat reads (rgb, lrgb, mrgb)", name));
}

std::vector<double> PlaneNumbers(const JsonReader& json, int planes) {
  std::vector<double> values = json.Numbers();
  if (static_cast<int>(values.size()) != planes) {
    json.Fail(fmt::format("expected {} values (nplanes), got {}", planes, values.size()));
  }
  return values;
}

// The planes a basis and colour space need, or an error naming what relight writes.
void CheckPlaneCount(const RelightWebStack& stack, const fs::path& file) {
  const int n = stack.PlaneCount();
  const auto fail = [&](std::string_view expected) {
    throw Error(file, fmt::format("{} {} with {} planes: expected {}", ToString(stack.basis),
                                  ToString(stack.colour_space), n, expected));
  };
  switch (stack.basis) {
    case RelightWebBasis::kPtm:
      if (stack.colour_space == RelightWebColourSpace::kRgb && n != 9 && n != 18) fail("9 or 18");
      if (stack.colour_space == RelightWebColourSpace::kLrgb && n != 6 && n != 9) fail("6 or 9");
      if (stack.colour_space == RelightWebColourSpace::kMrgb) fail("colour space rgb or lrgb");
      break;
    case RelightWebBasis::kHsh:
      if (stack.colour_space != RelightWebColourSpace::kRgb) fail("colour space rgb");
      if (n != 12 && n != 27) fail("12 or 27");
      break;
    case RelightWebBasis::kRbf:
    case RelightWebBasis::kBilinear:
      if (stack.colour_space != RelightWebColourSpace::kMrgb) fail("colour space mrgb");
      if (n < 1) fail("at least 1");
      break;
  }
}

}  // namespace

std::string_view ToString(RelightWebBasis basis) {
  switch (basis) {
    case RelightWebBasis::kPtm:
      return "ptm";
    case RelightWebBasis::kHsh:
      return "hsh";
    case RelightWebBasis::kRbf:
      return "rbf";
    case RelightWebBasis::kBilinear:
      return "bilinear";
  }
  return "?";
}

std::string_view ToString(RelightWebColourSpace colour_space) {
  switch (colour_space) {
    case RelightWebColourSpace::kRgb:
      return "rgb";
    case RelightWebColourSpace::kLrgb:
      return "lrgb";
    case RelightWebColourSpace::kMrgb:
      return "mrgb";
  }
  return "?";
}

int RelightWebStack::Dimensions() const {
  if (basis == RelightWebBasis::kRbf) return static_cast<int>(lights.size());
  if (basis == RelightWebBasis::kBilinear) return resolution * resolution;
  return 0;
}

bool IsRelightWebFolder(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) && fs::exists(path / "info.json", ec);
}

RelightWebStack ReadRelightWeb(const fs::path& folder) {
  const fs::path file = folder / "info.json";
  const nlohmann::json document = ReadJsonFile(file);
  const JsonReader json(document, file);
  RelightWebStack stack;
  stack.width = json["width"].Integer();
  stack.height = json["height"].Integer();
  if (stack.width <= 0 || stack.height <= 0 || stack.width > 65535 || stack.height > 65535) {
    throw Error(file, fmt::format("image size {}x{} is not valid", stack.width, stack.height));
  }
  if (json.Has("format") && json["format"].String() != "jpg") {
    json["format"].Fail("only \"jpg\" planes are read");
  }
  if (json.Has("quality")) stack.quality = json["quality"].Integer();
  if (json.Has("colorprofile")) {
    const std::string profile = json["colorprofile"].String();
    if (profile == "RGB") {
      stack.linear = true;
    } else if (profile != "sRGB") {
      json["colorprofile"].Fail(fmt::format(
          "colour profile \"{}\" is not one photomat reads (RGB: linear, sRGB)", profile));
    }
  }
  stack.basis = ParseBasis(json["type"]);
  stack.colour_space = ParseColourSpace(json["colorspace"]);
  const int planes = json["nplanes"].Integer();
  if (planes < 1 || planes > 255) json["nplanes"].Fail(fmt::format("{} planes", planes));
  stack.planes.assign(
      planes, std::vector<std::uint8_t>(static_cast<std::size_t>(stack.width) * stack.height, 0));
  CheckPlaneCount(stack, file);
  if (json.Has("lights")) {
    const std::vector<double> xyz = json["lights"].Numbers();
    if (xyz.size() % 3 != 0) json["lights"].Fail("expected x, y, z for every light");
    for (std::size_t i = 0; i < xyz.size(); i += 3) {
      stack.lights.emplace_back(xyz[i], xyz[i + 1], xyz[i + 2]);
    }
  }
  if (stack.basis == RelightWebBasis::kRbf) {
    stack.sigma = json["sigma"].Number();
    if (!(stack.sigma > 0)) json["sigma"].Fail("sigma must be positive");
    if (stack.lights.empty()) json["lights"].Fail("an rbf stack needs its lights");
  }
  if (stack.basis == RelightWebBasis::kBilinear) {
    stack.resolution = json["resolution"].Integer();
    if (stack.resolution < 2 || stack.resolution > 256) {
      json["resolution"].Fail(fmt::format("grid side {} is not in 2..256", stack.resolution));
    }
  }
  const JsonReader material = json["materials"][0];
  stack.scale = PlaneNumbers(material["scale"], planes);
  stack.bias = PlaneNumbers(material["bias"], planes);
  if (stack.colour_space == RelightWebColourSpace::kMrgb) {
    stack.range = PlaneNumbers(material["range"], planes);
    for (double r : stack.range) {
      if (!(r > 0)) material["range"].Fail("every range must be positive");
    }
    const std::vector<double> values = json["basis"].Numbers();
    const std::size_t expected = static_cast<std::size_t>(planes + 1) * stack.Dimensions() * 3;
    if (values.size() != expected) {
      json["basis"].Fail(fmt::format("expected (nplanes + 1) x {} x 3 = {} values, got {}",
                                     stack.Dimensions(), expected, values.size()));
    }
    stack.basis_values.assign(values.begin(), values.end());
  }
  for (int jpeg = 0; jpeg < JpegCount(planes); ++jpeg) {
    ReadPlaneJpeg(PlaneFile(folder, jpeg), jpeg, stack);
  }
  return stack;
}

void WriteRelightWeb(const fs::path& folder, const RelightWebStack& stack) {
  nlohmann::ordered_json info;
  info["width"] = stack.width;
  info["height"] = stack.height;
  info["format"] = "jpg";
  info["type"] = ToString(stack.basis);
  if (stack.basis == RelightWebBasis::kBilinear) info["resolution"] = stack.resolution;
  info["colorspace"] = ToString(stack.colour_space);
  if (stack.basis == RelightWebBasis::kRbf) info["sigma"] = stack.sigma;
  if (!stack.lights.empty()) {
    nlohmann::json lights = nlohmann::json::array();
    for (const auto& l : stack.lights) {
      for (int k = 0; k < 3; ++k) lights.push_back(l[k]);
    }
    info["lights"] = lights;
  }
  info["nplanes"] = stack.PlaneCount();
  info["quality"] = stack.quality;
  info["colorprofile"] = stack.linear ? "RGB" : "sRGB";
  if (stack.colour_space == RelightWebColourSpace::kMrgb) info["basis"] = stack.basis_values;
  nlohmann::ordered_json material;
  if (stack.colour_space == RelightWebColourSpace::kMrgb) material["range"] = stack.range;
  material["scale"] = stack.scale;
  material["bias"] = stack.bias;
  info["materials"] = nlohmann::ordered_json::array({material});
  WriteFolderAtomically(folder, "info.json", "jpg", [&](const fs::path& temp) {
    WriteTextFileAtomically(temp / "info.json", info.dump(1) + "\n");
    for (int jpeg = 0; jpeg < JpegCount(stack.PlaneCount()); ++jpeg) {
      WritePlaneJpeg(PlaneFile(temp, jpeg), jpeg, stack);
    }
  });
}

// --- Reading as a representation ---

RelightWebLightBasis::RelightWebLightBasis(const RelightWebStack& stack)
    : basis_(stack.basis),
      planes_(stack.PlaneCount()),
      dimensions_(stack.Dimensions()),
      lights_(stack.lights),
      sigma_(stack.sigma),
      resolution_(stack.resolution) {
  if (basis_ != RelightWebBasis::kRbf && basis_ != RelightWebBasis::kBilinear) {
    throw Error("RelightWebLightBasis: only rbf and bilinear stacks have one");
  }
  functions_.resize(stack.basis_values.size());
  const std::size_t per_plane = static_cast<std::size_t>(dimensions_) * 3;
  for (std::size_t i = 0; i < functions_.size(); ++i) {
    const std::size_t plane = i / per_plane;
    const double stored = stack.basis_values[i];
    // relight's Rti::load: the mean as stored (codes), E_p = (stored - 127) / range_p.
    functions_[i] = plane == 0 ? stored / 255.0 : (stored - 127.0) / stack.range[plane - 1];
  }
}

std::vector<std::pair<int, double>> RelightWebLightBasis::DimensionWeights(
    const LightDirection& light) const {
  const double lx = light.x(), ly = light.y();
  const double lz = std::sqrt(std::max(0.0, 1.0 - lx * lx - ly * ly));
  std::vector<std::pair<int, double>> weights;
  if (basis_ == RelightWebBasis::kRbf) {
    // relight's Rti::lightWeightsRbf: normalised Gaussians, weights of 0.001 or less dropped, the
    // rest normalised again.
    const double radius = 1.0 / (sigma_ * sigma_);
    const Eigen::Vector3d n(lx, ly, lz);
    double total = 0;
    std::vector<double> all(lights_.size());
    for (std::size_t i = 0; i < lights_.size(); ++i) {
      all[i] = std::exp(-radius * (n - lights_[i]).squaredNorm());
      total += all[i];
    }
    double kept = 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
      const double w = all[i] / total;
      if (w > 0.001) {
        weights.emplace_back(static_cast<int>(i), w);
        kept += w;
      }
    }
    for (auto& w : weights) w.second /= kept;
    return weights;
  }
  // relight's Rti::lightWeightsBilinear: the octahedral map rotated by 45 degrees, read
  // bilinearly on the resolution^2 grid.
  const double s = std::abs(lx) + std::abs(ly) + lz;
  double x = ((lx + ly) / s + 1.0) / 2.0 * (resolution_ - 1.0);
  double y = ((ly - lx) / s + 1.0) / 2.0 * (resolution_ - 1.0);
  const int sx = std::clamp(static_cast<int>(std::floor(x)), 0, resolution_ - 2);
  const int sy = std::clamp(static_cast<int>(std::floor(y)), 0, resolution_ - 2);
  const double dx = x - sx, dy = y - sy;
  const auto node = [&](int i, int j) { return (sx + i) + (sy + j) * resolution_; };
  weights = {{node(0, 0), (1 - dx) * (1 - dy)},
             {node(1, 0), dx * (1 - dy)},
             {node(0, 1), (1 - dx) * dy},
             {node(1, 1), dx * dy}};
  return weights;
}

Eigen::VectorXd RelightWebLightBasis::Coefficients(const LightDirection& light) const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(size());
  for (const auto& [dimension, weight] : DimensionWeights(light)) {
    for (int p = 0; p <= planes_; ++p) {
      for (int k = 0; k < 3; ++k) {
        c[3 * p + k] +=
            weight * functions_[(static_cast<std::size_t>(p) * dimensions_ + dimension) * 3 + k];
      }
    }
  }
  return c;
}

nlohmann::json RelightWebLightBasis::ToJson() const {
  nlohmann::json lights = nlohmann::json::array();
  for (const auto& l : lights_) lights.push_back({l.x(), l.y(), l.z()});
  return {{"kind", "relight-web"},  {"type", ToString(basis_)}, {"planes", planes_},
          {"lights", lights},       {"sigma", sigma_},          {"resolution", resolution_},
          {"functions", functions_}};
}

namespace {

Representation PtmRepresentation(const RelightWebStack& stack) {
  const std::size_t pixels = static_cast<std::size_t>(stack.width) * stack.height;
  const bool lrgb = stack.colour_space == RelightWebColourSpace::kLrgb;
  const int terms = lrgb ? stack.PlaneCount() - 3 : stack.PlaneCount() / 3;
  const auto channels = OutputChannelNames(3);
  std::vector<std::string> names;
  if (lrgb) {
    for (int j = 0; j < 6; ++j) names.push_back(fmt::format("ptm.a{}", j));
    for (const auto& c : channels) names.push_back("rgb." + c);
  } else {
    names = CoefficientMapNames("ptm.a", 6, channels);
  }
  Image maps(stack.width, stack.height, names);
  for (int j = 0; j < terms; ++j) {
    const int term = kPtmTermToPhotomat[j];
    for (int c = 0; c < (lrgb ? 1 : 3); ++c) {
      const int plane = lrgb ? 3 + j : 3 * j + c;
      auto out = maps.plane(lrgb ? term : 3 * term + c);
      for (std::size_t p = 0; p < pixels; ++p) {
        out[p] = static_cast<float>(stack.Value(plane, p) / 255.0);
      }
    }
  }
  if (lrgb) {
    // relight's renderer multiplies the luminance by the chroma bytes as they are.
    for (int c = 0; c < 3; ++c) {
      auto out = maps.plane(6 + c);
      for (std::size_t p = 0; p < pixels; ++p) out[p] = stack.planes[c][p] / 255.0f;
    }
  }
  const MapLayout layout = lrgb ? MapLayout{6, false, true, 3} : MapLayout{6, true, false, 3};
  return Representation(
      lrgb ? "ptm-lrgb" : "ptm", std::move(maps), layout, std::make_shared<PtmLightBasis>(),
      {{"relight_web", {{"type", "ptm"}, {"colorspace", ToString(stack.colour_space)}}}});
}

Representation HshRepresentation(const RelightWebStack& stack) {
  const std::size_t pixels = static_cast<std::size_t>(stack.width) * stack.height;
  const int terms = stack.PlaneCount() / 3;
  Image maps(stack.width, stack.height, CoefficientMapNames("hsh.h", terms, OutputChannelNames(3)));
  for (int plane = 0; plane < stack.PlaneCount(); ++plane) {
    auto out = maps.plane(plane);
    for (std::size_t p = 0; p < pixels; ++p) {
      out[p] = static_cast<float>(stack.Value(plane, p) / 255.0);
    }
  }
  return Representation(fmt::format("hsh{}", terms), std::move(maps), {terms, true, false, 3},
                        std::make_shared<HshLightBasis>(terms),
                        {{"relight_web", {{"type", "hsh"}, {"colorspace", "rgb"}}}});
}

Representation MrgbRepresentation(const RelightWebStack& stack) {
  const std::size_t pixels = static_cast<std::size_t>(stack.width) * stack.height;
  const int planes = stack.PlaneCount();
  const int terms = 3 * (planes + 1);
  std::vector<std::string> names;
  for (int p = 0; p <= planes; ++p) {
    for (const char* from : {"R", "G", "B"}) {
      for (const char* to : {"R", "G", "B"}) {
        names.push_back(fmt::format("relight.p{}.{}.{}", p, from, to));
      }
    }
  }
  Image maps(stack.width, stack.height, names);  // zero-filled: only from == to is set
  for (int p = 0; p <= planes; ++p) {
    for (int k = 0; k < 3; ++k) {
      auto out = maps.plane((3 * p + k) * 3 + k);
      for (std::size_t i = 0; i < pixels; ++i) {
        out[i] = p == 0 ? 1.0f : static_cast<float>(stack.Value(p - 1, i) / 255.0);
      }
    }
  }
  nlohmann::json details = {
      {"relight_web",
       {{"type", ToString(stack.basis)}, {"colorspace", "mrgb"}, {"planes", planes}}}};
  return Representation(fmt::format("relight-{}", ToString(stack.basis)), std::move(maps),
                        {terms, true, false, 3}, std::make_shared<RelightWebLightBasis>(stack),
                        std::move(details));
}

}  // namespace

Representation RepresentationFromRelightWeb(const RelightWebStack& stack) {
  switch (stack.basis) {
    case RelightWebBasis::kPtm:
      return PtmRepresentation(stack);
    case RelightWebBasis::kHsh:
      return HshRepresentation(stack);
    case RelightWebBasis::kRbf:
    case RelightWebBasis::kBilinear:
      return MrgbRepresentation(stack);
  }
  throw Error("unknown relight basis");
}

// --- Writing from a stack ---

namespace {

// Per plane over all pixels: scale = (max - min) / 255, bias = -min / (max - min), bytes rounded,
// so every value is within scale / 2 of its byte's; with `quantile` < 1, min and max are the
// plane's (1 - quantile) and quantile quantiles and the values outside are clipped.
std::pair<double, double> PlaneRange(const std::vector<float>& values, double quantile) {
  if (quantile >= 1.0 || values.empty()) {
    const auto [low, high] = std::minmax_element(values.begin(), values.end());
    return {*low, *high};
  }
  std::vector<float> sorted = values;
  const auto at = [&](double q) {
    const auto index = static_cast<std::ptrdiff_t>(q * static_cast<double>(sorted.size() - 1));
    std::nth_element(sorted.begin(), sorted.begin() + index, sorted.end());
    return static_cast<double>(sorted[static_cast<std::size_t>(index)]);
  };
  return {at(1.0 - quantile), at(quantile)};
}

void QuantisePlanes(const std::vector<std::vector<float>>& values, double quantile,
                    RelightWebStack& stack) {
  const int planes = static_cast<int>(values.size());
  stack.planes.assign(planes, {});
  stack.scale.assign(planes, 1.0);
  stack.bias.assign(planes, 0.0);
  for (int p = 0; p < planes; ++p) {
    const auto [min, max] = PlaneRange(values[p], quantile);
    const double span = std::max(max - min, 1e-6);
    stack.scale[p] = static_cast<float>(span / 255.0);
    stack.bias[p] = static_cast<float>(-min / span);
    auto& bytes = stack.planes[p];
    bytes.resize(values[p].size());
    for (std::size_t i = 0; i < bytes.size(); ++i) {
      const double b = values[p][i] / stack.scale[p] + 255.0 * stack.bias[p];
      bytes[i] = static_cast<std::uint8_t>(std::clamp(std::lround(b), 0L, 255L));
    }
  }
}

RelightWebStack PolynomialFromStack(const LoadedStack& loaded, const RelightWebOptions& options) {
  const bool ptm = options.basis == RelightWebBasis::kPtm;
  int terms = ptm ? 6 : options.hsh_terms;
  if (!ptm &&
      (loaded.representation.method() == "hsh4" || loaded.representation.method() == "hsh9")) {
    terms = loaded.representation.basis().size();
  }
  if (!ptm && terms != 4 && terms != 9) {
    throw Error(fmt::format("relight's web format holds HSH of 4 or 9 terms, not {}", terms));
  }
  const Representation encoded =
      ConvertToEncoded(loaded, Method::Parse(ptm ? "ptm" : fmt::format("hsh{}", terms)));
  if (encoded.output_channels() != 3 || encoded.layout().has_gain) {
    throw Error(fmt::format("a {} representation with {} channel(s) is not an RGB {} fit",
                            encoded.method(), encoded.output_channels(), ptm ? "PTM" : "HSH"));
  }
  const std::size_t pixels = static_cast<std::size_t>(encoded.width()) * encoded.height();
  std::vector<std::vector<float>> values(3 * terms, std::vector<float>(pixels));
  for (int j = 0; j < terms; ++j) {
    const int source = ptm ? kPtmTermToPhotomat[j] : j;
    for (int c = 0; c < 3; ++c) {
      const auto in = encoded.maps().plane(3 * source + c);
      for (std::size_t p = 0; p < pixels; ++p) values[3 * j + c][p] = in[p] * 255.0f;
    }
  }
  RelightWebStack stack;
  stack.basis = options.basis;
  stack.colour_space = RelightWebColourSpace::kRgb;
  stack.width = encoded.width();
  stack.height = encoded.height();
  stack.quality = options.quality;
  for (const auto& light : loaded.provenance.capture_lights) stack.lights.push_back(light.vector());
  QuantisePlanes(values, options.range_quantile, stack);
  return stack;
}

// relight's fromOcta: grid node (x, y) of a resolution^2 octahedral grid as a unit direction.
Eigen::Vector3d OctahedralNode(int x, int y, int resolution) {
  const double ox = 2.0 * x / (resolution - 1) - 1.0;
  const double oy = 2.0 * y / (resolution - 1) - 1.0;
  const double X = (ox - oy) / 2.0, Y = (ox + oy) / 2.0;
  Eigen::Vector3d n(X, Y, std::max(0.0, 1.0 - std::abs(X) - std::abs(Y)));
  return n.normalized();
}

// The nodes of an mrgb stack: rbf interpolates between `lights` (the capture's), bilinear between
// the octahedral grid's directions.
std::vector<LightDirection> MrgbNodes(const RelightWebOptions& options,
                                      const std::vector<LightDirection>& lights,
                                      RelightWebStack& stack) {
  std::vector<LightDirection> nodes;
  if (options.basis == RelightWebBasis::kRbf) {
    nodes = lights;
    for (const auto& l : nodes) stack.lights.push_back(l.vector());
    return nodes;
  }
  if (options.resolution < 2) throw Error("the bilinear grid needs a side of at least 2");
  for (int y = 0; y < options.resolution; ++y) {
    for (int x = 0; x < options.resolution; ++x) {
      nodes.push_back(LightDirection::FromVector(OctahedralNode(x, y, options.resolution)));
    }
  }
  return nodes;
}

// The nodes' values of an mrgb construction, sRGB-encoded, band by band (RelightWebBands).
class MrgbNodeSource {
 public:
  virtual ~MrgbNodeSource() = default;
  virtual int width() const = 0;
  virtual int height() const = 0;
  // Bytes per pixel a band of the source holds while it is read (not counting the profiles).
  virtual std::size_t BandBytesPerPixel() const = 0;
  // Back to row 0, for the next pass.
  virtual void Rewind() = 0;
  // The next `rows` rows: `put(node, encoded)` for every node, from parallel threads, with the
  // band's sRGB-encoded values in [0, 1] at that node (3 channels, `rows` rows).
  virtual void ReadBand(int rows, const std::function<void(int, ConstImageView)>& put) = 0;
};

// Node values of a band of photographs: their values sRGB-encoded (the photographs are linear).
void PutEncodedPhotographs(std::span<const Image> band, int first, int rows,
                           const std::function<void(int, ConstImageView)>& put) {
  tbb::parallel_for(0, static_cast<int>(band.size()), [&](int i) {
    Image encoded(band[static_cast<std::size_t>(i)].Rows(first, rows));
    for (float& v : encoded.values()) v = static_cast<float>(LinearToSrgb(v));
    put(i, encoded);
  });
}

// Node values of a band of a representation: relit at every node, sRGB-encoded when linear.
void PutRelitNodes(const Representation& band, const std::vector<LightDirection>& nodes,
                   bool linear, const std::function<void(int, ConstImageView)>& put) {
  tbb::parallel_for(0, static_cast<int>(nodes.size()), [&](int i) {
    Image relit = band.Relight(nodes[static_cast<std::size_t>(i)]);
    if (linear) {
      for (float& v : relit.values()) v = static_cast<float>(LinearToSrgb(v));
    }
    put(i, relit);
  });
}

// A photometric set in memory (rbf from photographs: the photographs are the node values).
class SetNodes final : public MrgbNodeSource {
 public:
  explicit SetNodes(const PhotometricSet& set) : set_(set) {}
  int width() const override { return set_.width(); }
  int height() const override { return set_.height(); }
  std::size_t BandBytesPerPixel() const override { return 0; }
  void Rewind() override { next_ = 0; }
  void ReadBand(int rows, const std::function<void(int, ConstImageView)>& put) override {
    PutEncodedPhotographs(set_.images(), next_, rows, put);
    next_ += rows;
  }

 private:
  const PhotometricSet& set_;
  int next_ = 0;
};

// A photometric set read band by band (its photographs decoded a band at a time).
class StreamedSetNodes final : public MrgbNodeSource {
 public:
  explicit StreamedSetNodes(StreamedSet& set) : set_(set) {}
  int width() const override { return set_.width(); }
  int height() const override { return set_.height(); }
  // The band's images as floats (ReadBand).
  std::size_t BandBytesPerPixel() const override {
    return sizeof(float) * static_cast<std::size_t>(set_.size()) * set_.channels();
  }
  void Rewind() override {
    if (set_.next_row() != 0) set_.Rewind();
  }
  void ReadBand(int rows, const std::function<void(int, ConstImageView)>& put) override {
    const PhotometricSet band = set_.ReadBand(rows);
    PutEncodedPhotographs(band.images(), 0, rows, put);
  }

 private:
  StreamedSet& set_;
};

// A representation in memory relit at the nodes, a band of its maps at a time.
class RepresentationNodes final : public MrgbNodeSource {
 public:
  RepresentationNodes(const Representation& source, std::vector<LightDirection> nodes, bool linear)
      : source_(source), nodes_(std::move(nodes)), linear_(linear) {}
  int width() const override { return source_.width(); }
  int height() const override { return source_.height(); }
  // The band's copy of the maps.
  std::size_t BandBytesPerPixel() const override {
    return sizeof(float) * static_cast<std::size_t>(source_.maps().channels());
  }
  void Rewind() override { next_ = 0; }
  void ReadBand(int rows, const std::function<void(int, ConstImageView)>& put) override {
    Image maps(source_.maps().Rows(next_, rows));
    maps.set_channel_names(source_.maps().channel_names());
    PutRelitNodes(source_.WithMaps(std::move(maps)), nodes_, linear_, put);
    next_ += rows;
  }

 private:
  const Representation& source_;
  std::vector<LightDirection> nodes_;
  bool linear_;
  int next_ = 0;
};

// A map stack read band by band, relit at the nodes.
class StackNodes final : public MrgbNodeSource {
 public:
  StackNodes(StackBandReader& stack, std::vector<LightDirection> nodes, bool linear)
      : stack_(stack), nodes_(std::move(nodes)), linear_(linear) {}
  int width() const override { return stack_.width(); }
  int height() const override { return stack_.height(); }
  // The band of the file's channels.
  std::size_t BandBytesPerPixel() const override {
    return sizeof(float) * static_cast<std::size_t>(stack_.stored_channels());
  }
  void Rewind() override {
    if (stack_.next_row() != 0) stack_.Rewind();
  }
  void ReadBand(int rows, const std::function<void(int, ConstImageView)>& put) override {
    PutRelitNodes(stack_.ReadNext(rows).representation, nodes_, linear_, put);
  }

 private:
  StackBandReader& stack_;
  std::vector<LightDirection> nodes_;
  bool linear_;
};

// The band height of an mrgb construction: the band's profiles (a float per node and channel),
// their pixel indices (RowGram) and what the source holds, within the budget.
int MrgbBandRows(const MrgbNodeSource& source, int dimension, const RelightWebBands& bands) {
  const std::size_t pixel =
      sizeof(float) * dimension + sizeof(std::size_t) + source.BandBytesPerPixel();
  return BudgetedBandRows(bands.band_rows, bands.memory_bytes, kMinimumRelightWebMemory,
                          static_cast<std::size_t>(source.width()) * pixel, source.height());
}

// One pass over `source`: each band's profiles in codes, one row per pixel (y * width + x
// within the band), node i's R, G, B in columns 3 i + k (relight's layout), handed to
// `visit(first, profiles)`.
void ForEachProfileBand(MrgbNodeSource& source, int dimension, int band_rows, Progress& progress,
                        const std::string& phase,
                        const std::function<void(int, Eigen::MatrixXf&)>& visit) {
  source.Rewind();
  const int width = source.width();
  const int bands = (source.height() + band_rows - 1) / band_rows;
  progress.Start(phase, static_cast<std::size_t>(bands));
  Eigen::MatrixXf profiles;
  for (int first = 0; first < source.height(); first += band_rows) {
    const int rows = std::min(band_rows, source.height() - first);
    profiles.resize(static_cast<Eigen::Index>(rows) * width, dimension);
    source.ReadBand(rows, [&](int node, ConstImageView encoded) {
      for (int k = 0; k < 3; ++k) {
        for (int y = 0; y < rows; ++y) {
          const auto in = encoded.row(k, y);
          const Eigen::Index row0 = static_cast<Eigen::Index>(y) * width;
          for (int x = 0; x < width; ++x) profiles(row0 + x, 3 * node + k) = 255.0f * in[x];
        }
      }
    });
    visit(first, profiles);
    progress.Advance();
  }
  progress.Finish();
}

// (1) The mean profile: per image row a sum in double, in pixel order, the rows' sums added in
// row order (the same bits for any band height).
Eigen::VectorXd MeanProfile(MrgbNodeSource& source, int dimension, int band_rows,
                            Progress& progress) {
  const int width = source.width();
  Eigen::VectorXd sums = Eigen::VectorXd::Zero(dimension);
  ForEachProfileBand(source, dimension, band_rows, progress, "relight planes: mean",
                     [&](int, Eigen::MatrixXf& profiles) {
                       for (Eigen::Index row0 = 0; row0 < profiles.rows(); row0 += width) {
                         for (int d = 0; d < dimension; ++d) {
                           double sum = 0;
                           for (int x = 0; x < width; ++x) sum += profiles(row0 + x, d);
                           sums[d] += sum;
                         }
                       }
                     });
  return sums / (static_cast<double>(width) * source.height());
}

// (2) The `planes` principal axes of the covariance about `mean`: the Gram matrix of the centred
// profiles (RowGram: float products per image row, summed in double in row order), less the
// centred sums' outer product (what centring at the float mean left). Largest eigenvalues first;
// the sign is fixed so that each axis's largest entry is positive (a deterministic choice, the
// PCA itself does not fix it).
Eigen::MatrixXd PrincipalAxes(MrgbNodeSource& source, const Eigen::VectorXd& mean, int planes,
                              int band_rows, Progress& progress) {
  const auto dimension = static_cast<int>(mean.size());
  const double pixels = static_cast<double>(source.width()) * source.height();
  RowGram gram(dimension);
  const Eigen::RowVectorXf mean_f = mean.transpose().cast<float>();
  std::vector<std::size_t> indices;
  ForEachProfileBand(source, dimension, band_rows, progress, "relight planes: covariance",
                     [&](int, Eigen::MatrixXf& profiles) {
                       profiles.rowwise() -= mean_f;
                       indices.resize(static_cast<std::size_t>(profiles.rows()));
                       std::iota(indices.begin(), indices.end(), std::size_t{0});
                       gram.Add(profiles, indices, source.width(), 1);
                     });
  const Eigen::MatrixXd covariance =
      gram.gram() - gram.column_sums() * gram.column_sums().transpose() / pixels;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(covariance);
  Eigen::MatrixXd axes(dimension, planes);
  for (int p = 0; p < planes; ++p) {
    Eigen::VectorXd axis = eigen.eigenvectors().col(dimension - 1 - p);
    Eigen::Index largest;
    axis.cwiseAbs().maxCoeff(&largest);
    if (axis[largest] < 0) axis = -axis;
    axes.col(p) = axis;
  }
  return axes;
}

// relight's basis integers into `stack`: the mean in codes, each axis as 127 + range E with
// range = 127 / max |E|. IMPLEMENTER CHOICE: rounded (relight truncates), and the coefficients are
// then projected onto the axes as the reader reconstructs them, so the rounding of the basis is
// partly absorbed by the planes. Returns the stored mean and axes, as the reader decodes them.
std::pair<Eigen::VectorXd, Eigen::MatrixXd> StoreMrgbBasis(const Eigen::VectorXd& mean,
                                                           const Eigen::MatrixXd& axes,
                                                           RelightWebStack& stack) {
  const auto dimension = static_cast<int>(mean.size());
  const auto planes = static_cast<int>(axes.cols());
  stack.basis_values.resize(static_cast<std::size_t>(planes + 1) * dimension);
  stack.range.resize(planes);
  Eigen::VectorXd stored_mean(dimension);
  for (int d = 0; d < dimension; ++d) {
    const int code = static_cast<int>(std::clamp(std::lround(mean[d]), 0L, 255L));
    stack.basis_values[d] = code;
    stored_mean[d] = code;
  }
  Eigen::MatrixXd stored_axes(dimension, planes);
  for (int p = 0; p < planes; ++p) {
    const double range = 127.0 / std::max(axes.col(p).cwiseAbs().maxCoeff(), 1e-12);
    stack.range[p] = static_cast<float>(range);
    for (int d = 0; d < dimension; ++d) {
      const int code = static_cast<int>(std::lround(127.0 + range * axes(d, p)));
      stack.basis_values[static_cast<std::size_t>(p + 1) * dimension + d] = code;
      stored_axes(d, p) = (code - 127.0) / stack.range[p];
    }
  }
  return {stored_mean, stored_axes};
}

// (3) Least-squares coefficients against the stored axes: (A^T A)^-1 A^T (profile - mean), pixel
// by pixel (the same bits in any band); one plane of values per axis.
std::vector<std::vector<float>> ProjectOntoStoredAxes(MrgbNodeSource& source,
                                                      const Eigen::VectorXd& stored_mean,
                                                      const Eigen::MatrixXd& stored_axes,
                                                      int band_rows, Progress& progress) {
  const auto dimension = static_cast<int>(stored_mean.size());
  const auto planes = static_cast<int>(stored_axes.cols());
  const int width = source.width();
  const std::size_t pixels = static_cast<std::size_t>(width) * source.height();
  const Eigen::MatrixXd projection =
      (stored_axes.transpose() * stored_axes).ldlt().solve(stored_axes.transpose());
  std::vector<std::vector<float>> values(planes, std::vector<float>(pixels));
  const Eigen::MatrixXf projection_f = projection.cast<float>();
  const Eigen::RowVectorXf stored_mean_f = stored_mean.transpose().cast<float>();
  ForEachProfileBand(
      source, dimension, band_rows, progress, "relight planes: coefficients",
      [&](int first, Eigen::MatrixXf& profiles) {
        const std::size_t offset = static_cast<std::size_t>(first) * width;
        const auto count = static_cast<std::size_t>(profiles.rows());
        tbb::parallel_for(std::size_t{0}, count, std::size_t{1024}, [&](std::size_t begin) {
          const std::size_t end = std::min(count, begin + 1024);
          for (std::size_t p = begin; p < end; ++p) {
            const Eigen::VectorXf c =
                projection_f *
                (profiles.row(static_cast<Eigen::Index>(p)) - stored_mean_f).transpose();
            for (int k = 0; k < planes; ++k) values[k][offset + p] = c[k];
          }
        });
      });
  return values;
}

// relight's mrgb construction over `nodes` node values read from `source` in bands: three passes
// (the mean, the covariance, the coefficients).
RelightWebStack MrgbFromSource(MrgbNodeSource& source, int nodes, RelightWebStack stack,
                               const RelightWebOptions& options, const RelightWebBands& bands,
                               RelightWebBandsReport* report) {
  const int dimension = 3 * nodes;
  const int planes = std::min(options.planes, dimension);
  if (planes < 1 || planes > 255) throw Error(fmt::format("{} planes: expected 1..255", planes));
  const int band_rows = MrgbBandRows(source, dimension, bands);
  if (report) *report = {band_rows, 3};
  NullProgress none;
  Progress& progress = OrNull(bands.progress, none);
  const Eigen::VectorXd mean = MeanProfile(source, dimension, band_rows, progress);
  const Eigen::MatrixXd axes = PrincipalAxes(source, mean, planes, band_rows, progress);
  const auto [stored_mean, stored_axes] = StoreMrgbBasis(mean, axes, stack);
  const std::vector<std::vector<float>> values =
      ProjectOntoStoredAxes(source, stored_mean, stored_axes, band_rows, progress);
  QuantisePlanes(values, options.range_quantile, stack);
  return stack;
}

RelightWebStack EmptyStack(int width, int height, const RelightWebOptions& options) {
  RelightWebStack stack;
  stack.basis = options.basis;
  stack.colour_space = RelightWebColourSpace::kMrgb;
  stack.width = width;
  stack.height = height;
  stack.quality = options.quality;
  stack.sigma = options.sigma;
  stack.resolution = options.resolution;
  return stack;
}

// relight's mrgb planes of a stack, whose description `header` gives (the whole stack's, or a
// band reader's): the nodes, and whether its values are linear (then sRGB-encoded at the nodes).
// `make_source(nodes, linear)` reads its node values.
RelightWebStack MrgbFromStack(
    const LoadedStack& header, int width, int height, const RelightWebOptions& options,
    const RelightWebBands& bands, RelightWebBandsReport* report,
    const std::function<std::unique_ptr<MrgbNodeSource>(std::vector<LightDirection>, bool)>&
        make_source) {
  if (header.representation.output_channels() != 3) {
    throw Error(fmt::format("relight's mrgb planes need an RGB stack, not {} channel(s)",
                            header.representation.output_channels()));
  }
  RelightWebStack stack = EmptyStack(width, height, options);
  const auto& captured = header.provenance.capture_lights;
  std::vector<LightDirection> nodes =
      MrgbNodes(options, captured.empty() ? RefitLights() : captured, stack);
  const int count = static_cast<int>(nodes.size());
  const bool linear = StackValueEncoding(header.provenance) == ColourSpace::kLinear;
  const std::unique_ptr<MrgbNodeSource> source = make_source(std::move(nodes), linear);
  return MrgbFromSource(*source, count, std::move(stack), options, bands, report);
}

void CheckOptions(const RelightWebOptions& options) {
  if (options.quality < 1 || options.quality > 100) {
    throw Error(fmt::format("JPEG quality {} is not in 1..100", options.quality));
  }
  if (!(options.range_quantile > 0.5 && options.range_quantile <= 1.0)) {
    throw Error(fmt::format("range quantile {} is not in (0.5, 1]", options.range_quantile));
  }
}

// A pbr stack's shading is nonlinear: relight's bases cannot hold it.
void CheckLinearShading(const Representation& r) {
  if (r.shading()) {
    throw Error(fmt::format(
        "a {} representation is a nonlinear {} shading that relight's bases cannot hold: export "
        "its maps with `photomat export` instead",
        r.method(), r.shading()->kind()));
  }
}

bool IsMrgb(RelightWebBasis basis) {
  return basis == RelightWebBasis::kRbf || basis == RelightWebBasis::kBilinear;
}

// rbf from photographs: their encoded values are the node values, their lights the nodes.
RelightWebStack RbfFromPhotographs(MrgbNodeSource& source, int channels,
                                   const std::vector<LightDirection>& lights,
                                   const RelightWebOptions& options, const RelightWebBands& bands,
                                   RelightWebBandsReport* report) {
  if (channels != 3) {
    throw Error(
        fmt::format("relight's mrgb planes need RGB photographs, not {} channel(s)", channels));
  }
  RelightWebStack stack = EmptyStack(source.width(), source.height(), options);
  MrgbNodes(options, lights, stack);  // records the lights in the stack
  return MrgbFromSource(source, static_cast<int>(lights.size()), std::move(stack), options, bands,
                        report);
}

}  // namespace

std::optional<Method> RelightWebFitMethod(const RelightWebOptions& options) {
  CheckOptions(options);
  switch (options.basis) {
    case RelightWebBasis::kPtm:
      return Method::Parse("ptm");
    case RelightWebBasis::kHsh:
      if (options.hsh_terms != 4 && options.hsh_terms != 9) {
        throw Error(fmt::format("relight's web format holds HSH of 4 or 9 terms, not {}",
                                options.hsh_terms));
      }
      return Method::Parse(fmt::format("hsh{}", options.hsh_terms));
    case RelightWebBasis::kBilinear:
      return Method::Parse("bilinear");
    case RelightWebBasis::kRbf:
      return std::nullopt;
  }
  throw Error("unknown relight basis");
}

RelightWebStack RelightWebFromSet(const PhotometricSet& set, const RelightWebOptions& options,
                                  const RelightWebBands& bands, RelightWebBandsReport* report) {
  if (report) *report = {};
  const std::optional<Method> fit_method = RelightWebFitMethod(options);
  if (fit_method) {
    // ptm, hsh and bilinear: from the fit of the encoded photographs (bilinear: its grid's
    // values are the node values).
    const LoadedStack fit{FitEncoded(set, *fit_method),
                          StackProvenance(set.lights(), "srgb", set.source())};
    return RelightWebFromStack(fit, options, bands, report);
  }
  SetNodes source(set);
  return RbfFromPhotographs(source, set.channels(), set.lights(), options, bands, report);
}

RelightWebStack RelightWebFromSet(StreamedSet& set, const RelightWebOptions& options,
                                  const RelightWebBands& bands, RelightWebBandsReport* report) {
  if (const std::optional<Method> fit_method = RelightWebFitMethod(options)) {
    throw Error(fmt::format(
        "relight's {} planes from photographs are made from a {} fit of their encoded values: "
        "fit it into a stack first and make the planes from that",
        ToString(options.basis), fit_method->Name()));
  }
  StreamedSetNodes source(set);
  return RbfFromPhotographs(source, set.channels(), set.lights(), options, bands, report);
}

RelightWebStack RelightWebFromStack(const LoadedStack& stack, const RelightWebOptions& options,
                                    const RelightWebBands& bands, RelightWebBandsReport* report) {
  if (report) *report = {};
  const Representation& r = stack.representation;
  CheckLinearShading(r);
  CheckOptions(options);
  if (!IsMrgb(options.basis)) return PolynomialFromStack(stack, options);
  return MrgbFromStack(stack, r.width(), r.height(), options, bands, report,
                       [&](std::vector<LightDirection> nodes, bool linear) {
                         return std::make_unique<RepresentationNodes>(r, std::move(nodes), linear);
                       });
}

RelightWebStack RelightWebFromStack(StackBandReader& stack, const RelightWebOptions& options,
                                    const RelightWebBands& bands, RelightWebBandsReport* report) {
  if (report) *report = {};
  CheckLinearShading(stack.header().representation);
  CheckOptions(options);
  if (!IsMrgb(options.basis)) return PolynomialFromStack(LoadRepresentation(stack.path()), options);
  return MrgbFromStack(stack.header(), stack.width(), stack.height(), options, bands, report,
                       [&](std::vector<LightDirection> nodes, bool linear) {
                         return std::make_unique<StackNodes>(stack, std::move(nodes), linear);
                       });
}

}  // namespace photomat
