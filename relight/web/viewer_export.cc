#include "relight/web/viewer_export.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <numbers>

#include "core/atomic_file.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/memory_limits.h"
#include "relight/export/export.h"
#include "relight/render/display_image.h"
#include "relight/render/output_folder.h"
#include "relight/web/viewer_assets.h"
#include "relight/web/viewer_decoder.h"
#include "relight/web/viewer_display_pyramids.h"
#include "represent/model/neural_decoder.h"
#include "represent/stack/stack_band_reader.h"
#include "represent/surface/surface_integration.h"
#include "represent/surface/tiled_poisson.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr const char* kViewerFormat = "photomat-viewer";
constexpr const char* kViewerManifest = "viewer.json";
// Exact formulas are held to rounding: basis.js computes in double precision, as C++ does.
constexpr double kExactTolerance = 1e-9;

nlohmann::json Vector(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

nlohmann::json InterpolatedJson(const InterpolatedLightBasis& basis) {
  const LightInterpolator& interpolator = basis.interpolator();
  nlohmann::json nodes = nlohmann::json::array();
  for (const LightDirection& l : interpolator.nodes()) nodes.push_back({l.x(), l.y(), l.z()});
  nlohmann::json json = {{"kind", "interpolated"},
                         {"scheme", ToString(interpolator.scheme())},
                         {"nodes", std::move(nodes)},
                         {"values", MatrixToJson(basis.values().transpose())}};
  if (interpolator.scheme() == LightInterpolator::Scheme::kSlantRings) {
    nlohmann::json rings = nlohmann::json::array();
    for (const LightInterpolator::Ring& ring : interpolator.rings()) {
      nlohmann::json by_tilt = nlohmann::json::array();
      for (const auto& [tilt, node] : ring.by_tilt) by_tilt.push_back({tilt, node});
      rings.push_back({{"slant", ring.slant}, {"by_tilt", std::move(by_tilt)}});
    }
    json["rings"] = std::move(rings);
    json["pole_slant_deg"] = LightInterpolator::kPoleSlantDegrees;
  } else {
    json["projection_scale"] = LightInterpolator::kProjectionScale;
    json["projected"] = interpolator.projected();
    json["triangles"] = interpolator.triangles();
    json["boundary"] = interpolator.boundary();
  }
  return json;
}

// Golden-angle spiral: evenly spread over the disc of slant * (cos tilt, sin tilt), no randomness.
std::vector<LightDirection> SpiralLights(int count) {
  std::vector<LightDirection> lights;
  const double golden_angle = 180.0 * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < count; ++i) {
    const double slant = 89.5 * std::sqrt((i + 0.5) / count);
    lights.push_back(LightDirection::FromSlantTilt(slant, std::fmod(i * golden_angle, 360.0)));
  }
  return lights;
}

std::string FileStem(const std::string& method) {
  std::string stem;
  for (char c : method) {
    const bool safe = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '-' || c == '_';
    stem += safe ? c : '_';
  }
  return stem.empty() ? "method" : stem;
}

// The maps as ceil(n / 4) RGBA layers, layer-major, rows from the top (the texture's layout).
std::string MapLayers(const Image& maps) {
  const int n = maps.channels();
  const int layers = (n + 3) / 4;
  std::string bytes;
  bytes.reserve(static_cast<std::size_t>(layers) * maps.pixel_count() * 16);
  for (int layer = 0; layer < layers; ++layer) {
    for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
      const auto values = maps.pixel(p);
      for (int c = 0; c < 4; ++c) {
        const int map = 4 * layer + c;
        AppendFloat32(bytes, map < n ? values[map] : 0.0f);
      }
    }
  }
  return bytes;
}

// Pixels where the fit wrote anything: maps are 0 outside the capture's mask.
Mask FittedPixels(const Image& maps) {
  Mask mask(maps.width(), maps.height(), false);
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    const auto values = maps.pixel(p);
    mask.Set(p, std::any_of(values.begin(), values.end(), [](float v) { return v != 0.0f; }));
  }
  return mask;
}

// Normal, albedo and height for looking at, from `source`: the normal map as (n + 1) / 2, the
// albedo as the relit colour with the light along each pixel's normal (exactly the albedo for
// Gradient, whose relighting is albedo * n.l), the height by Poisson integration of the normals
// over the fitted pixels, stretched to [0, 1] there.
nlohmann::json WriteDisplayMaps(const fs::path& folder, const Representation& source) {
  const std::optional<Image> normals = EstimateNormals(source);
  if (!normals) return nlohmann::json::array();
  const Mask mask = FittedPixels(source.maps());
  const int channels = source.output_channels();

  Image normal_colours(normals->width(), normals->height(), 3);
  Image albedo(normals->width(), normals->height(), std::min(channels, 3));
  tbb::parallel_for(std::size_t{0}, normals->pixel_count(), [&](std::size_t p) {
    const auto n = normals->pixel(p);
    for (int c = 0; c < 3; ++c) normal_colours.pixel(p)[c] = 0.5f * (n[c] + 1.0f);
    if (!mask[p]) return;
    const Eigen::VectorXf coefficients =
        source.basis().Coefficients(LightDirection::FromVector(n[0], n[1], n[2])).cast<float>();
    std::vector<float> out(channels);
    source.RelightPixel(source.maps().pixel(p), coefficients, out);
    for (int c = 0; c < albedo.channels(); ++c) albedo.pixel(p)[c] = std::max(out[c], 0.0f);
  });

  ImageWriteOptions srgb8;
  srgb8.sample_type = SampleType::kUint8;
  srgb8.encoding = ColourSpace::kSrgb;
  nlohmann::json views = nlohmann::json::array();
  const std::string from = source.method();
  WriteDisplayCodes(folder / "maps" / "normal.png", normal_colours);
  views.push_back({{"name", "normal"},
                   {"label", "Normal"},
                   {"file", "maps/normal.png"},
                   {"source", from},
                   {"encoding", "(n + 1) / 2"}});
  WriteImage(folder / "maps" / "albedo.png", albedo, srgb8);
  views.push_back({{"name", "albedo"},
                   {"label", "Albedo"},
                   {"file", "maps/albedo.png"},
                   {"source", from},
                   {"encoding", "sRGB"}});

  if (mask.CountSet() > 0) {
    const Image height = IntegratePoissonAnySize(GradientsFromNormals(*normals), mask);
    double low = INFINITY, high = -INFINITY;
    for (std::size_t p = 0; p < height.pixel_count(); ++p) {
      if (!mask[p]) continue;
      low = std::min(low, static_cast<double>(height.pixel(p)[0]));
      high = std::max(high, static_cast<double>(height.pixel(p)[0]));
    }
    Image grey(height.width(), height.height(), 1);
    for (std::size_t p = 0; p < height.pixel_count(); ++p) {
      if (!mask[p]) continue;
      grey.pixel(p)[0] =
          high > low ? static_cast<float>((height.pixel(p)[0] - low) / (high - low)) : 0.5f;
    }
    WriteDisplayCodes(folder / "maps" / "height.png", grey);
    views.push_back({{"name", "height"},
                     {"label", "Height"},
                     {"file", "maps/height.png"},
                     {"source", from},
                     {"encoding", "linear"},
                     {"range_pixels", {low, high}}});
  }
  return views;
}

// Gradient gives the most direct normals; then the other methods whose normals are defined.
// The index into `representations`, or nullopt.
std::optional<std::size_t> DisplayMapSource(
    const std::vector<const Representation*>& representations) {
  for (const char* preferred : {"gradient", "3i", "ptm", "ptm-lrgb"}) {
    for (std::size_t i = 0; i < representations.size(); ++i) {
      if (representations[i]->method() == preferred) return i;
    }
  }
  for (std::size_t i = 0; i < representations.size(); ++i) {
    if (GivesDisplayMaps(*representations[i])) return i;
  }
  return std::nullopt;
}

nlohmann::json CheckJson(const LightBasis& basis, const std::optional<CoefficientTable>& table) {
  nlohmann::json lights = nlohmann::json::array();
  nlohmann::json coefficients = nlohmann::json::array();
  for (const LightDirection& light : ViewerCheckLights(basis)) {
    lights.push_back({light.x(), light.y(), light.z()});
    coefficients.push_back(Vector(table ? table->Coefficients(light) : basis.Coefficients(light)));
  }
  // Against the table the viewer must match the C++ table to float rounding; against the basis
  // itself, to double rounding.
  return {{"lights", std::move(lights)},
          {"coefficients", std::move(coefficients)},
          {"tolerance", table ? 1e-7 : kExactTolerance}};
}

// `tiled`: the whole-texture limit does not apply.
void CheckSameSample(const std::vector<Representation>& representations, bool tiled) {
  if (representations.empty()) throw Error("no representation to export to the viewer");
  const Representation& first = representations.front();
  for (const Representation& r : representations) {
    if (r.width() != first.width() || r.height() != first.height()) {
      throw Error(fmt::format("{} is {}x{} but {} is {}x{}: a viewer shows one sample", r.method(),
                              r.width(), r.height(), first.method(), first.width(),
                              first.height()));
    }
    if (!tiled && (r.width() > 8192 || r.height() > 8192)) {
      throw Error(
          fmt::format("{} is {}x{}: the viewer's whole-image textures hold at most 8192 "
                      "pixels a side (export it as tiles: --viewer-tiles always)",
                      r.method(), r.width(), r.height()));
    }
  }
  for (std::size_t i = 0; i < representations.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (FileStem(representations[i].method()) == FileStem(representations[j].method())) {
        throw Error(fmt::format("method \"{}\" is given twice", representations[i].method()));
      }
    }
  }
}

// Of the nonlinear shadings the viewer evaluates the neural decoder (viewer_decoder.h); pbr's
// microfacet BRDF has no place in its shaders yet.
void CheckViewable(const Representation& r) {
  if (r.shading() && !dynamic_cast<const NeuralShading*>(r.shading())) {
    throw Error(
        fmt::format("the viewer has no {} shading: leave {} out of the viewer (its "
                    "maps export with `photomat export`)",
                    r.shading()->kind(), r.method()));
  }
}

void WriteViewerFiles(const fs::path& temp) {
  for (const ViewerAsset& asset : ViewerAssets()) {
    WriteTextFileAtomically(temp / asset.path, asset.contents);
  }
  fs::create_directories(temp / "maps");
}

std::string PyramidFolder(const std::string& stem) { return fmt::format("maps/{}/levels", stem); }

nlohmann::json PyramidJson(const std::string& stem, const PyramidLayout& layout) {
  nlohmann::json json = layout.ToJson();
  json["folder"] = PyramidFolder(stem);
  return json;
}

// The capture's lights, when the options give none: an interpolated basis's nodes.
void AddCaptureLights(std::vector<LightDirection>& capture_lights, const Representation& r) {
  if (const auto* interpolated = dynamic_cast<const InterpolatedLightBasis*>(&r.basis());
      interpolated && capture_lights.empty()) {
    capture_lights = interpolated->interpolator().nodes();
  }
}

// viewer.json's description of method `r` whose maps are `data`; writes the coefficient table
// into `temp` when the method reads one.
nlohmann::json MethodJson(const fs::path& temp, const Representation& r,
                          const ViewerExportOptions& options, nlohmann::json data) {
  const std::string stem = FileStem(r.method());
  const bool table =
      options.table_methods.contains(r.method()) || !ViewerEvaluatesExactly(r.basis());
  nlohmann::json basis;
  std::optional<CoefficientTable> coefficient_table;
  if (table) {
    coefficient_table.emplace(r.basis());
    const std::string file = fmt::format("maps/{}.coefficients.f32", stem);
    std::string bytes;
    for (float v : coefficient_table->values()) AppendFloat32(bytes, v);
    WriteTextFileAtomically(temp / file, bytes);
    basis = coefficient_table->ToJson();
    basis["source_kind"] = r.basis().kind();
    basis["file"] = file;
  } else {
    basis = ViewerBasisJson(r.basis());
  }
  const auto encoding = options.value_encodings.find(r.method());
  nlohmann::json json = {
      {"name", r.method()},
      {"label", MethodLabel(r.method())},
      {"layout", r.layout().ToJson()},
      {"values", ToString(encoding == options.value_encodings.end() ? ColourSpace::kLinear
                                                                    : encoding->second)},
      {"channels", r.maps().channel_names()},
      {"data", std::move(data)},
      {"basis", std::move(basis)},
      {"check", CheckJson(r.basis(), coefficient_table)}};
  if (const auto* neural = dynamic_cast<const NeuralShading*>(r.shading())) {
    const std::string file = fmt::format("maps/{}.decoder.f32", stem);
    WriteTextFileAtomically(temp / file, ViewerDecoderTexture(neural->decoder()));
    json["shading"] = ViewerDecoderJson(neural->decoder(), file);
  }
  return json;
}

void WriteManifest(const fs::path& temp, const ViewerExportOptions& options, int width, int height,
                   const std::vector<LightDirection>& capture_lights, nlohmann::json methods,
                   nlohmann::json views) {
  nlohmann::json lights = nlohmann::json::array();
  for (const LightDirection& l : capture_lights) lights.push_back({l.x(), l.y(), l.z()});
  WriteJsonFile(temp / kViewerManifest, {{"format", kViewerFormat},
                                         {"version", 1},
                                         {"title", options.title},
                                         {"width", width},
                                         {"height", height},
                                         {"capture_lights", std::move(lights)},
                                         {"methods", std::move(methods)},
                                         {"views", std::move(views)}});
}

// Rows per band of `stack` the budget leaves beside the pyramid's buffers: per row, the decoded
// stored channels and the gathered maps (4 bytes each). Throws Error naming the stack when not
// even one row fits.
int ViewerBandRows(std::size_t budget, const StackBandReader& stack, const PyramidLayout& layout) {
  const int maps = stack.header().representation.maps().channels();
  const std::size_t pyramid = PyramidWriter::BufferBytes(layout, maps);
  const std::size_t row_bytes = static_cast<std::size_t>(stack.width()) * 4 *
                                (static_cast<std::size_t>(stack.stored_channels()) + maps);
  if (budget < pyramid + row_bytes) {
    throw Error(
        stack.path(),
        fmt::format("the viewer's tile pyramid needs at least {:.1f} MB of memory ({:.1f} MB "
                    "given): raise --memory or make the tiles smaller",
                    static_cast<double>(pyramid + row_bytes) / (1 << 20),
                    static_cast<double>(budget) / (1 << 20)));
  }
  return static_cast<int>(std::min<std::size_t>((budget - pyramid) / row_bytes,
                                                static_cast<std::size_t>(stack.height())));
}

}  // namespace

std::string MethodLabel(const std::string& method) {
  if (method == "3i") return "3I";
  if (method == "gradient") return "Gradient";
  if (method == "ptm") return "PTM";
  if (method == "ptm-lrgb") return "PTM LRGB";
  // fmt rather than "literal" + std::string: GCC 12 warns falsely (-Wrestrict) on the latter.
  if (method.starts_with("eigen")) return fmt::format("Eigen-{}", method.substr(5));
  if (method.starts_with("hsh")) {
    return method.size() > 3 ? fmt::format("HSH {}", method.substr(3)) : std::string("HSH");
  }
  std::string label = method;
  for (char& c : label) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return label;
}

CoefficientTable::CoefficientTable(const LightBasis& basis, double step_degrees)
    : terms_(basis.size()), step_(step_degrees) {
  const double slant_cells = 90.0 / step_, tilt_cells = 360.0 / step_;
  if (!(step_ > 0.0) || std::abs(slant_cells - std::round(slant_cells)) > 1e-9 ||
      std::abs(tilt_cells - std::round(tilt_cells)) > 1e-9) {
    throw Error(fmt::format("coefficient table step {} must divide 90 degrees", step_degrees));
  }
  slant_steps_ = static_cast<int>(std::round(slant_cells)) + 1;
  tilt_steps_ = static_cast<int>(std::round(tilt_cells)) + 1;
  values_.resize(static_cast<std::size_t>(slant_steps_) * tilt_steps_ * terms_);
  tbb::parallel_for(0, slant_steps_, [&](int s) {
    for (int t = 0; t < tilt_steps_; ++t) {
      // Tilt 360 is tilt 0 (the wrap column); at slant 0 every tilt is the same light.
      const Eigen::VectorXd c = basis.Coefficients(
          LightDirection::FromSlantTilt(s * step_, t + 1 == tilt_steps_ ? 0.0 : t * step_));
      for (int j = 0; j < terms_; ++j) {
        values_[(static_cast<std::size_t>(s) * tilt_steps_ + t) * terms_ + j] =
            static_cast<float>(c[j]);
      }
    }
  });
  // Bilinear interpolation errs most inside cells: measure at every cell's centre and midpoints.
  std::vector<double> worst(slant_steps_ - 1, 0.0);
  tbb::parallel_for(0, slant_steps_ - 1, [&](int s) {
    for (int t = 0; t + 1 < tilt_steps_; ++t) {
      for (const auto& [ds, dt] : {std::pair{0.5, 0.0}, std::pair{0.0, 0.5}, std::pair{0.5, 0.5}}) {
        const LightDirection light =
            LightDirection::FromSlantTilt((s + ds) * step_, (t + dt) * step_);
        const double error =
            (Coefficients(light) - basis.Coefficients(light)).cwiseAbs().maxCoeff();
        worst[s] = std::max(worst[s], error);
      }
    }
  });
  max_error_ = *std::max_element(worst.begin(), worst.end());
}

Eigen::VectorXd CoefficientTable::Coefficients(const LightDirection& light) const {
  const double s = std::clamp(light.SlantDegrees() / step_, 0.0, slant_steps_ - 1.0);
  const double t = std::clamp(light.TiltDegrees() / step_, 0.0, tilt_steps_ - 1.0);
  const int s0 = std::min(static_cast<int>(s), slant_steps_ - 2);
  const int t0 = std::min(static_cast<int>(t), tilt_steps_ - 2);
  const double fs = s - s0, ft = t - t0;
  const auto at = [&](int si, int ti, int j) {
    return static_cast<double>(
        values_[(static_cast<std::size_t>(si) * tilt_steps_ + ti) * terms_ + j]);
  };
  Eigen::VectorXd c(terms_);
  for (int j = 0; j < terms_; ++j) {
    c[j] = (1.0 - fs) * ((1.0 - ft) * at(s0, t0, j) + ft * at(s0, t0 + 1, j)) +
           fs * ((1.0 - ft) * at(s0 + 1, t0, j) + ft * at(s0 + 1, t0 + 1, j));
  }
  return c;
}

nlohmann::json CoefficientTable::ToJson() const {
  return {{"kind", "table"},           {"terms", terms_},
          {"step_deg", step_},         {"slant_steps", slant_steps_},
          {"tilt_steps", tilt_steps_}, {"max_error", max_error_}};
}

std::vector<LightDirection> ViewerCheckLights(const LightBasis& basis, int spiral_count) {
  std::vector<LightDirection> lights = SpiralLights(spiral_count);
  lights.push_back(LightDirection::FromVector(0.0, 0.0, 1.0));
  if (const auto* interpolated = dynamic_cast<const InterpolatedLightBasis*>(&basis)) {
    for (const LightDirection& node : interpolated->interpolator().nodes()) {
      if (node.z() >= 0.0) lights.push_back(node);
    }
  }
  return lights;
}

bool ViewerEvaluatesExactly(const LightBasis& basis) {
  return dynamic_cast<const LinearLightBasis*>(&basis) ||
         dynamic_cast<const PtmLightBasis*>(&basis) ||
         dynamic_cast<const InterpolatedLightBasis*>(&basis) ||
         dynamic_cast<const DirectionLightBasis*>(&basis) ||
         (basis.kind() == "hsh" && basis.ToJson().contains("terms"));
}

nlohmann::json ViewerBasisJson(const LightBasis& basis) {
  if (const auto* linear = dynamic_cast<const LinearLightBasis*>(&basis)) {
    return {{"kind", "linear"}, {"matrix", MatrixToJson(*linear->LinearInLight())}};
  }
  if (dynamic_cast<const PtmLightBasis*>(&basis)) return {{"kind", "ptm"}};
  // c = l: the light input of the neural decoder.
  if (dynamic_cast<const DirectionLightBasis*>(&basis)) return {{"kind", "direction"}};
  if (const auto* interpolated = dynamic_cast<const InterpolatedLightBasis*>(&basis)) {
    return InterpolatedJson(*interpolated);
  }
  // Hemispherical harmonics: their own description, {"kind": "hsh", "terms": N}, is all basis.js
  // needs (by kind, so that this module needs no HSH class).
  if (ViewerEvaluatesExactly(basis)) return basis.ToJson();
  throw Error(
      fmt::format("the viewer has no formula for light bases of kind \"{}\"", basis.kind()));
}

void ExportViewer(const fs::path& folder, const std::vector<Representation>& representations,
                  const ViewerExportOptions& options) {
  const bool tiled =
      !representations.empty() && UsesViewerTiles(options.tiling, representations.front().width(),
                                                  representations.front().height());
  CheckSameSample(representations, tiled);
  for (const Representation& r : representations) CheckViewable(r);
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  WriteFolderAtomically(folder, kViewerManifest, kViewerFormat, [&](const fs::path& temp) {
    progress.Start("viewer", representations.size() + 1);
    WriteViewerFiles(temp);
    nlohmann::json methods = nlohmann::json::array();
    std::vector<LightDirection> capture_lights = options.capture_lights;
    for (const Representation& r : representations) {
      const std::string stem = FileStem(r.method());
      const int layers = (r.maps().channels() + 3) / 4;
      nlohmann::json data = {{"type", "float32"}, {"layers", layers}};
      if (tiled) {
        const PyramidLayout layout(r.width(), r.height(), options.tile_size);
        PyramidWriter writer(temp / PyramidFolder(stem), layout, r.maps().channels());
        writer.AddRows(r.maps());
        writer.Finish();
        data["pyramid"] = PyramidJson(stem, layout);
      } else {
        data["file"] = fmt::format("maps/{}.f32", stem);
        WriteTextFileAtomically(temp / data["file"].get<std::string>(), MapLayers(r.maps()));
      }
      methods.push_back(MethodJson(temp, r, options, std::move(data)));
      AddCaptureLights(capture_lights, r);
      progress.Advance();
    }
    nlohmann::json views = nlohmann::json::array();
    if (options.display_maps && !tiled) {
      std::vector<const Representation*> all;
      for (const Representation& r : representations) all.push_back(&r);
      if (const std::optional<std::size_t> source = DisplayMapSource(all)) {
        views = WriteDisplayMaps(temp, representations[*source]);
      }
    }
    WriteManifest(temp, options, representations.front().width(), representations.front().height(),
                  capture_lights, std::move(methods), std::move(views));
    progress.Advance();
    progress.Finish();
  });
}

void ExportViewerStreamed(const fs::path& folder, const std::vector<fs::path>& stacks,
                          const ViewerExportOptions& options) {
  if (stacks.empty()) throw Error(folder, "no stack to export to the viewer");
  // Opened (and their descriptions checked) before anything is written.
  std::vector<std::unique_ptr<StackBandReader>> readers;
  for (const fs::path& path : stacks) {
    readers.push_back(std::make_unique<StackBandReader>(path));
    const StackBandReader& first = *readers.front();
    const StackBandReader& reader = *readers.back();
    if (reader.width() != first.width() || reader.height() != first.height()) {
      throw Error(
          path, fmt::format("is {}x{} but {} is {}x{}: a viewer shows one sample", reader.width(),
                            reader.height(), first.path().string(), first.width(), first.height()));
    }
    CheckViewable(reader.header().representation);
  }
  const PyramidLayout layout(readers.front()->width(), readers.front()->height(),
                             options.tile_size);
  // Every stack's bands are sized before anything is written; by default (DefaultBandBudget)
  // the bands get the streamed steps' band size beyond the pyramid's buffers.
  std::vector<int> band_rows;
  std::size_t tile_bytes = 0;
  for (const auto& reader : readers) {
    const std::size_t budget =
        options.memory_bytes > 0
            ? options.memory_bytes
            : DefaultBandBudget(kMinimumViewerMemory,
                                PyramidWriter::BufferBytes(
                                    layout, reader->header().representation.maps().channels()));
    band_rows.push_back(ViewerBandRows(budget, *reader, layout));
    tile_bytes += layout.FileBytes(reader->header().representation.maps().channels());
  }
  // The display maps' source: a stack that gives normals, exported (streamed) beside the tiles.
  std::optional<std::size_t> display_source;
  if (options.display_maps) {
    std::vector<const Representation*> all;
    for (const auto& reader : readers) all.push_back(&reader->header().representation);
    display_source = DisplayMapSource(all);
  }
  if (display_source) {
    const StackBandReader& source = *readers[*display_source];
    const Representation& r = source.header().representation;
    tile_bytes += 3 * layout.FileBytes(3) + ExportOutputBytes(source.width(), source.height(),
                                                              r.maps().channels(),
                                                              r.output_channels(), false);
  }
  CheckDiskSpace(folder.parent_path().empty() ? fs::path(".") : folder.parent_path(), tile_bytes,
                 "the viewer's tiles");
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  WriteFolderAtomically(folder, kViewerManifest, kViewerFormat, [&](const fs::path& temp) {
    WriteViewerFiles(temp);
    nlohmann::json methods = nlohmann::json::array();
    std::vector<LightDirection> capture_lights = options.capture_lights;
    for (std::size_t i = 0; i < readers.size(); ++i) {
      StackBandReader& reader = *readers[i];
      const Representation& r = reader.header().representation;
      const std::string stem = FileStem(r.method());
      const int maps = r.maps().channels();
      PyramidWriter writer(temp / PyramidFolder(stem), layout, maps);
      const int bands = (reader.height() + band_rows[i] - 1) / band_rows[i];
      progress.Start(fmt::format("viewer tiles: {}", r.method()), static_cast<std::size_t>(bands));
      for (int b = 0; b < bands; ++b) {
        writer.AddRows(reader.ReadNext(band_rows[i]).representation.maps());
        progress.Advance();
      }
      progress.Finish();
      writer.Finish();
      methods.push_back(MethodJson(temp, r, options,
                                   {{"type", "float32"},
                                    {"layers", (maps + 3) / 4},
                                    {"pyramid", PyramidJson(stem, layout)}}));
      AddCaptureLights(capture_lights, r);
    }
    nlohmann::json views = nlohmann::json::array();
    if (display_source) {
      // A fresh reader: the display maps' export makes its own passes over the stack.
      StackBandReader source(readers[*display_source]->path());
      views = WriteDisplayPyramids(temp, source, layout, options.memory_bytes, options.progress);
    }
    WriteManifest(temp, options, readers.front()->width(), readers.front()->height(),
                  capture_lights, std::move(methods), std::move(views));
  });
}

std::size_t InMemoryViewerBytes(std::size_t pixels, int maps) {
  return pixels * (50 + 10 * static_cast<std::size_t>(std::max(maps, 0)));
}

}  // namespace photomat
