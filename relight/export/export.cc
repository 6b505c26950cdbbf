#include "relight/export/export.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "core/disk_space.h"
#include "core/error.h"
#include "core/image_band_io.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/memory_limits.h"
#include "relight/export/gltf_tile.h"
#include "relight/formats/stack_file.h"
#include "represent/model/shading.h"
#include "represent/stack/stack_band_writer.h"
#include "represent/surface/surface_integration.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

struct Range {
  double low = 0.0, high = 0.0;
};

Range HeightRange(const Image& height, const Mask& mask) {
  Range range{INFINITY, -INFINITY};
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    if (!mask[p]) continue;
    range.low = std::min(range.low, double{height.pixel(p)[0]});
    range.high = std::max(range.high, double{height.pixel(p)[0]});
  }
  return range;
}

// Height mapped to [0, 1] over its range (0.5 for a flat surface), 0 outside the mask.
Image NormalisedHeight(const Image& height, const Mask& mask, const Range& range) {
  Image out(height.width(), height.height(), 1);
  const double span = range.high - range.low;
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    if (!mask[p]) continue;
    out.pixel(p)[0] =
        span > 0.0 ? static_cast<float>((height.pixel(p)[0] - range.low) / span) : 0.5f;
  }
  return out;
}

// The derived layers the stack does not hold yet, for stack.exr.
// How the exports write their PNGs, in memory and streamed alike: 16-bit codes (normals, height,
// pbr maps), 8-bit sRGB (albedo), and the height's, with the range it was normalised over.
ImageWriteOptions Png16() {
  ImageWriteOptions png16;
  png16.sample_type = SampleType::kUint16;
  return png16;
}
ImageWriteOptions SrgbBytes() {
  ImageWriteOptions srgb8;
  srgb8.sample_type = SampleType::kUint8;
  srgb8.encoding = ColourSpace::kSrgb;
  return srgb8;
}
ImageWriteOptions HeightPngOptions(const Range& range) {
  ImageWriteOptions height16 = Png16();
  height16.attributes["photomat:height_min"] = fmt::format("{:.9g}", range.low);
  height16.attributes["photomat:height_max"] = fmt::format("{:.9g}", range.high);
  return height16;
}

Image ExtraLayers(const Representation& r, const MaterialMaps& maps) {
  std::vector<const Image*> parts;
  for (const Image* image : {&maps.normals, &maps.albedo}) {
    if (r.maps().FindChannel(image->channel_names().front()) < 0) parts.push_back(image);
  }
  parts.push_back(&maps.height);
  std::vector<std::string> names;
  for (const Image* part : parts) {
    names.insert(names.end(), part->channel_names().begin(), part->channel_names().end());
  }
  Image extra(r.width(), r.height(), names);
  auto out = extra.values().begin();  // planar: the parts' planes one after another
  for (const Image* part : parts)
    out = std::copy(part->values().begin(), part->values().end(), out);
  return extra;
}

// The glTF F0 of a dielectric is min(0.04 specularColor, 1) specular (KHR_materials_specular,
// default IOR 1.5); Blender's Principled "Specular" and Substance's "specular level" s give
// F0 = 0.08 s.
constexpr double kGltfDielectricF0 = 0.04;
constexpr double kSpecularLevelF0 = 0.08;

struct PbrFiles {
  std::string metallic_roughness;
  std::string specular;
  double specular_color_factor = 1.0;
  nlohmann::json description;
};

// The largest F0 of the masked pixels of microfacet `maps` (at least the glTF dielectric's): what
// the specular texture is scaled by. A band's, combined by max over the bands, is the whole map's.
double LargestF0(const Image& maps, const Mask& mask) {
  double largest_f0 = kGltfDielectricF0;
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    if (mask[p]) largest_f0 = std::max(largest_f0, double{maps.pixel(p)[MicrofacetShading::kF0]});
  }
  return largest_f0;
}

// The microfacet maps beyond normal and base colour, for glTF, Blender and Substance, over some
// rows of the map (each pixel's from its own maps and the whole map's largest F0).
struct PbrImages {
  Image roughness, f0, level, metallic_roughness, specular, base;
};

PbrImages PbrBand(const Image& maps, const Mask& mask, double largest_f0) {
  const int width = maps.width(), rows = maps.height();
  const std::vector<std::string> rgb = {"R", "G", "B"};
  PbrImages out{Image(width, rows, std::vector<std::string>{"roughness"}),
                Image(width, rows, std::vector<std::string>{"f0"}),
                Image(width, rows, std::vector<std::string>{"Y"}),
                Image(width, rows, rgb),
                Image(width, rows, rgb),
                Image(width, rows, rgb)};
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    if (!mask[p]) continue;
    const auto m = maps.pixel(p);
    out.roughness.pixel(p)[0] = m[MicrofacetShading::kRoughness];
    out.f0.pixel(p)[0] = m[MicrofacetShading::kF0];
    out.level.pixel(p)[0] = static_cast<float>(m[MicrofacetShading::kF0] / kSpecularLevelF0);
    // glTF: R unused (occlusion lives in its own texture), G roughness, B metallic (a dielectric).
    out.metallic_roughness.pixel(p)[0] = 1.0f;
    out.metallic_roughness.pixel(p)[1] = m[MicrofacetShading::kRoughness];
    for (int c = 0; c < 3; ++c) {
      out.specular.pixel(p)[c] = static_cast<float>(m[MicrofacetShading::kF0] / largest_f0);
    }
    for (int c = 0; c < 3; ++c) out.base.pixel(p)[c] = m[MicrofacetShading::kBase + c];
  }
  return out;
}

// The files of PbrImages, in its order, with their write options.
struct PbrFile {
  std::string name;
  Image PbrImages::*image;
  ImageWriteOptions options;
  std::vector<std::string> channels;  // as PbrBand names them
};

std::vector<PbrFile> PbrFileList(const ImageWriteOptions& png16) {
  ImageWriteOptions srgb16 = png16;
  srgb16.encoding = ColourSpace::kSrgb;
  const std::vector<std::string> rgb = {"R", "G", "B"};
  const ImageWriteOptions exr;
  return {{"roughness.exr", &PbrImages::roughness, exr, {"roughness"}},
          {"roughness.png", &PbrImages::roughness, png16, {"roughness"}},
          {"f0.exr", &PbrImages::f0, exr, {"f0"}},
          {"specular_level.png", &PbrImages::level, png16, {"Y"}},
          {"metallic_roughness.png", &PbrImages::metallic_roughness, png16, rgb},
          {"specular.png", &PbrImages::specular, srgb16, rgb},
          {"base_color.exr", &PbrImages::base, exr, rgb},
          {"base_color.png", &PbrImages::base, srgb16, rgb}};
}

PbrFiles PbrDescription(double largest_f0) {
  PbrFiles files;
  files.metallic_roughness = "metallic_roughness.png";
  files.specular = "specular.png";
  files.specular_color_factor = largest_f0 / kGltfDielectricF0;
  files.description = {
      {"model", "diffuse + GGX, Smith height-correlated, Schlick; alpha = roughness^2"},
      {"base_color",
       {{"exr", "base_color.exr"},
        {"png", "base_color.png"},
        {"encoding", "linear float / 16-bit sRGB"}}},
      {"roughness",
       {{"exr", "roughness.exr"},
        {"png", "roughness.png"},
        {"encoding", "perceptual roughness, linear"}}},
      {"f0", {{"exr", "f0.exr"}, {"encoding", "grey Fresnel reflectance at normal incidence"}}},
      {"specular_level",
       {{"png", "specular_level.png"},
        {"encoding",
         "F0 / 0.08, 16-bit linear (Blender Principled Specular, "
         "Substance specular level)"}}},
      {"metallic_roughness",
       {{"png", "metallic_roughness.png"},
        {"encoding", "glTF: G roughness, B metallic (0), 16-bit linear"}}},
      {"specular",
       {{"png", "specular.png"},
        {"encoding",
         "KHR_materials_specular specularColorTexture, 16-bit sRGB: "
         "grey F0 / (0.04 specularColorFactor)"},
        {"specular_color_factor", files.specular_color_factor}}}};
  return files;
}

// The microfacet maps of the whole map (in memory).
PbrFiles WritePbrMaps(const Representation& r, const Mask& mask, const fs::path& folder,
                      const ImageWriteOptions& png16) {
  const double largest_f0 = LargestF0(r.maps(), mask);
  const PbrImages images = PbrBand(r.maps(), mask, largest_f0);
  for (const PbrFile& file : PbrFileList(png16)) {
    WriteImage(folder / file.name, images.*file.image, file.options);
  }
  return PbrDescription(largest_f0);
}

// The normal map in glTF's convention (+Y up) when another one is asked.
constexpr const char* kGltfNormalFile = "normal_gltf.png";

// export.json's description of the maps (without "pbr" and "gltf").
nlohmann::json ExportDescription(const LoadedStack& stack, int width, int height,
                                 const std::string& normals_source, const Range& range,
                                 const ExportOptions& options) {
  return {
      {"format", "photomat-export"},
      {"version", 1},
      {"method", stack.representation.method()},
      {"source", stack.provenance.source},
      {"width", width},
      {"height", height},
      {"normals",
       {{"file", "normal.png"},
        {"convention", ToString(options.normal_convention)},
        {"encoding", "16-bit linear, (n + 1) / 2 per component"},
        {"source", normals_source}}},
      {"albedo", {{"file", "albedo.png"}, {"encoding", "8-bit sRGB"}}},
      // Not "height" (the image's, above): a second key of that name was dropped by the JSON
      // object, so the height map went undescribed until 2026-12-06.
      {"height_map",
       {{"file", "height.exr"},
        {"png", "height.png"},
        {"units", "pixels"},
        {"integrator", ToString(options.height)},
        {"min", range.low},
        {"max", range.high}}},
      {"stack", "stack.exr"},
  };
}

// The glTF tile over the written textures, and its entry in `description`.
void WriteTile(const fs::path& folder, int width, int height, const Range& range,
               const PbrFiles& pbr, const ExportOptions& options, nlohmann::json& description) {
  GltfTile tile;
  tile.aspect = static_cast<double>(height) / width;
  tile.base_color_uri = "albedo.png";
  tile.normal_uri =
      options.normal_convention != NormalConvention::kOpenGl ? kGltfNormalFile : "normal.png";
  tile.height_uri = "height.png";
  tile.metallic_roughness_uri = pbr.metallic_roughness;
  tile.specular_uri = pbr.specular;
  tile.specular_color_factor = pbr.specular_color_factor;
  // Height in pixels, one pixel = tile.width / image width scene units.
  const double pixel = tile.width / width;
  tile.displacement_scale = (range.high - range.low) * pixel;
  tile.displacement_offset = range.low * pixel;
  WriteGltfTile(folder / "tile.gltf", tile);
  description["gltf"] = {{"file", "tile.gltf"},
                         {"width", tile.width},
                         {"displacement_scale", tile.displacement_scale},
                         {"displacement_offset", tile.displacement_offset}};
}

}  // namespace

nlohmann::json ExportMaps(const LoadedStack& stack, const fs::path& folder,
                          const ExportOptions& options, Progress* progress) {
  NullProgress no_progress;
  Progress& report = OrNull(progress, no_progress);
  const Representation& r = stack.representation;
  report.Start("export", (options.gltf ? 7 : 6) + (IsMicrofacet(r.shading()) ? 1 : 0));
  MaterialMapOptions map_options;
  map_options.height = options.height;
  map_options.values = StackValueEncoding(stack.provenance);
  map_options.sample_lights = stack.provenance.capture_lights;
  const MaterialMaps maps = ExtractMaterialMaps(r, map_options);
  report.Advance();

  const ImageWriteOptions png16 = Png16();
  WriteImage(folder / "normal.png", EncodeNormalMap(maps.normals, options.normal_convention),
             png16);
  report.Advance();

  WriteImage(folder / "albedo.png", maps.albedo, SrgbBytes());
  report.Advance();

  const Range range = HeightRange(maps.height, maps.mask);
  WriteImage(folder / "height.exr", maps.height);
  WriteImage(folder / "height.png", NormalisedHeight(maps.height, maps.mask, range),
             HeightPngOptions(range));
  report.Advance();

  SaveRepresentation(folder / "stack.exr", r, stack.provenance, ExtraLayers(r, maps));
  report.Advance();

  nlohmann::json description =
      ExportDescription(stack, r.width(), r.height(), maps.normals_source, range, options);
  PbrFiles pbr;
  if (IsMicrofacet(r.shading())) {
    pbr = WritePbrMaps(r, maps.mask, folder, png16);
    description["pbr"] = pbr.description;
    report.Advance();
  }
  if (options.gltf) {
    if (options.normal_convention != NormalConvention::kOpenGl) {
      // glTF defines normal textures with +Y up.
      WriteImage(folder / kGltfNormalFile, EncodeNormalMap(maps.normals, NormalConvention::kOpenGl),
                 png16);
    }
    WriteTile(folder, r.width(), r.height(), range, pbr, options, description);
    report.Advance();
  }
  WriteJsonFile(folder / "export.json", description);
  report.Advance();
  report.Finish();
  return description;
}

namespace {

// Scratch files of a streamed export, removed however the export ends.
class ScratchFiles {
 public:
  ~ScratchFiles() {
    std::error_code ignored;
    for (const fs::path& path : paths_) fs::remove(path, ignored);
  }
  const fs::path& Add(fs::path path) { return paths_.emplace_back(std::move(path)); }

 private:
  std::vector<fs::path> paths_;
};

// The file channel named `name` of a scratch file.
int ChannelOf(const ImageBandReader& reader, const std::string& name) {
  const auto& names = reader.channel_names();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) throw Error(reader.path(), fmt::format("no channel \"{}\"", name));
  return static_cast<int>(it - names.begin());
}

// `count` channels of `stored` from `first` of `channels`, named `names`.
Image Channels(const Image& stored, const std::vector<int>& channels,
               const std::vector<std::string>& names) {
  Image out(stored.width(), stored.height(), names);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const auto in = stored.plane(channels[c]);
    std::copy(in.begin(), in.end(), out.plane(static_cast<int>(c)).begin());
  }
  return out;
}

std::vector<int> ChannelsOf(const ImageBandReader& reader, const std::vector<std::string>& names) {
  std::vector<int> channels;
  for (const std::string& name : names) channels.push_back(ChannelOf(reader, name));
  return channels;
}

// The surface scratch file's channels: the gradients and the mask (tiled Poisson's input), then
// the normals and albedo (for stack.exr's extra layers).
std::vector<std::string> SurfaceChannels(int albedo_channels) {
  std::vector<std::string> names = {"p", "q", "mask", "normal.X", "normal.Y", "normal.Z"};
  for (const auto& c : OutputChannelNames(albedo_channels)) names.push_back("albedo." + c);
  return names;
}

// Scratch files are written once and read back: no compression, for speed.
ImageWriteOptions ScratchFileOptions() {
  ImageWriteOptions options;
  options.exr_compression = ExrCompression::kNone;
  return options;
}

// The height a streamed export integrated (pass 2): what pass 3 subtracts and the range over the
// mask after that.
struct HeightSummary {
  double mean = 0.0;
  Range range;
};

// The gradients and mask of the surface scratch file, `count` rows from where `surface` is.
Image ReadGradientRows(ImageBandReader& surface, const std::vector<int>& channels, int width,
                       int count) {
  Image stored(width, count, surface.channels());
  surface.ReadNext(stored.View());
  return Channels(stored, channels, {"p", "q", "mask"});
}

// Pass 2 by tiled Poisson (two reads of the gradients): the height zero-mean over the mask, as the
// in-memory Poisson.
HeightSummary TiledPoissonHeight(const fs::path& surface_path, const fs::path& height_path,
                                 int width, int height, const StreamedExportOptions& options,
                                 Progress& progress) {
  double sum = 0.0, covered = 0.0;
  Range raw{INFINITY, -INFINITY};
  ImageBandReader surface(surface_path, {});
  const std::vector<int> gradient_channels = ChannelsOf(surface, {"p", "q", "mask"});
  GradientRows rows;
  rows.rewind = [&] { surface = ImageBandReader(surface_path, {}); };
  rows.next = [&](int count) {
    return ReadGradientRows(surface, gradient_channels, width,
                            std::min(count, height - surface.next_row()));
  };
  ImageBandWriter height_file(height_path, width, height, {"height"}, ScratchFileOptions());
  const int tile_rows = (height + options.poisson.tile - 1) / options.poisson.tile;
  progress.Start("export: height (tiled Poisson)", static_cast<std::size_t>(tile_rows));
  IntegrateTiledPoisson(
      width, height, rows,
      [&](ConstImageView band) {
        for (int y = 0; y < band.height(); ++y) {
          const auto h = band.row(0, y);
          const auto m = band.row(1, y);
          for (int x = 0; x < width; ++x) {
            if (m[x] < 0.5f) continue;
            sum += h[x];
            covered += 1.0;
            raw.low = std::min(raw.low, double{h[x]});
            raw.high = std::max(raw.high, double{h[x]});
          }
        }
        height_file.WriteNext(band.ChannelRange(0, 1));
        progress.Advance();
      },
      options.poisson);
  progress.Finish();
  height_file.Commit();
  const double mean = sum / covered;
  return {mean, {raw.low - mean, raw.high - mean}};
}

// Pass 2 by Frankot-Chellappa: a whole-map FFT, so the gradient field is read whole (8 bytes per
// pixel, and the transforms' spectra: about 50 bytes per pixel in all, 2.4 GB at 48 MP, against
// the stack relit at every capture light that the in-memory export's normals and albedo may need).
// The same gradients as in memory (GradientsFromNormals is per pixel, stored as float), so the
// same height: zero-mean over the whole map (the transform's), 0 outside the mask (pass 3), its
// range over the mask.
HeightSummary FrankotChellappaHeight(const fs::path& surface_path, const fs::path& height_path,
                                     int width, int height, Progress& progress) {
  // The field read in bands of the scratch file (whose rows hold every surface channel).
  constexpr int kReadRows = 64;
  const int bands = (height + kReadRows - 1) / kReadRows;
  progress.Start("export: height (Frankot-Chellappa)", static_cast<std::size_t>(bands) + 1);
  ImageBandReader surface(surface_path, {});
  const std::vector<int> channels = ChannelsOf(surface, {"p", "q", "mask"});
  Image field(width, height, std::vector<std::string>{"p", "q"});
  Mask mask(width, height, false);
  for (int first = 0; first < height; first += kReadRows) {
    const Image rows =
        ReadGradientRows(surface, channels, width, std::min(kReadRows, height - first));
    const std::size_t offset = static_cast<std::size_t>(first) * width;
    for (int c = 0; c < 2; ++c) {
      const auto in = rows.plane(c);
      std::copy(in.begin(), in.end(), field.plane(c).begin() + static_cast<std::ptrdiff_t>(offset));
    }
    const auto in_mask = rows.plane(2);
    for (std::size_t p = 0; p < in_mask.size(); ++p) mask.Set(offset + p, in_mask[p] >= 0.5f);
    progress.Advance();
  }
  const Image integrated = IntegrateFrankotChellappa(field);
  field = Image();
  ImageBandWriter height_file(height_path, width, height, {"height"}, ScratchFileOptions());
  height_file.WriteNext(integrated);
  height_file.Commit();
  progress.Advance();
  progress.Finish();
  return {0.0, HeightRange(integrated, mask)};
}

// Pass 1's outputs, written band by band. Every output of a streamed export stays pending until
// all passes are done, so that a fault anywhere leaves none of them.
struct SurfaceOutputs {
  SurfaceOutputs(const fs::path& folder, int width, int height, int channels,
                 const ExportOptions& maps)
      : normal_png(folder / "normal.png", width, height, {"R", "G", "B"}, Png16()),
        albedo_png(folder / "albedo.png", width, height, OutputChannelNames(channels),
                   SrgbBytes()) {
    if (maps.gltf && maps.normal_convention != NormalConvention::kOpenGl) {
      gltf_normal_png.emplace(folder / kGltfNormalFile, width, height,
                              std::vector<std::string>{"R", "G", "B"}, Png16());
    }
  }
  void Commit() {
    normal_png.Commit();
    if (gltf_normal_png) gltf_normal_png->Commit();
    albedo_png.Commit();
  }

  ImageBandWriter normal_png;
  std::optional<ImageBandWriter> gltf_normal_png;
  ImageBandWriter albedo_png;
};

// What pass 1 learns about the whole stack.
struct SurfaceSummary {
  std::string normals_source;
  // A pbr stack's specular texture is scaled by the largest F0 of the whole map.
  double largest_f0 = kGltfDielectricF0;
};

// Pass 1 over the stack: normals and albedo into their files, and gradients, mask, normals and
// albedo into the surface scratch file (SurfaceChannels), band by band.
SurfaceSummary WriteSurfacePass(StackBandReader& stack, int band_rows,
                                const StreamedExportOptions& options, const fs::path& surface_path,
                                SurfaceOutputs& outputs, Progress& progress) {
  const LoadedStack& header = stack.header();
  const Representation& r = header.representation;
  const int width = stack.width(), height = stack.height();
  const bool pbr = IsMicrofacet(r.shading());
  MaterialMapOptions map_options;
  map_options.values = StackValueEncoding(header.provenance);
  map_options.sample_lights = header.provenance.capture_lights;
  const std::vector<std::string> surface_names = SurfaceChannels(r.output_channels());
  ImageBandWriter surface(surface_path, width, height, surface_names, ScratchFileOptions());
  SurfaceSummary summary;
  std::size_t covered = 0;
  if (stack.next_row() != 0) stack.Rewind();
  const int bands = (height + band_rows - 1) / band_rows;
  progress.Start("export: normals and albedo", static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    const LoadedStack band = stack.ReadNext(band_rows);
    const MaterialMaps maps = ExtractSurfaceMaps(band.representation, map_options);
    summary.normals_source = maps.normals_source;
    covered += maps.mask.CountSet();
    if (pbr) {
      summary.largest_f0 =
          std::max(summary.largest_f0, LargestF0(band.representation.maps(), maps.mask));
    }
    outputs.normal_png.WriteNext(EncodeNormalMap(maps.normals, options.maps.normal_convention));
    if (outputs.gltf_normal_png) {
      outputs.gltf_normal_png->WriteNext(EncodeNormalMap(maps.normals, NormalConvention::kOpenGl));
    }
    outputs.albedo_png.WriteNext(maps.albedo);
    const Image gradients = GradientsFromNormals(maps.normals);
    Image rows(width, band.representation.height(), surface_names);
    auto out = rows.values().begin();  // planar, in surface_names' order
    out = std::copy(gradients.values().begin(), gradients.values().end(), out);
    for (std::size_t p = 0; p < maps.mask.pixel_count(); ++p) *out++ = maps.mask[p] ? 1.0f : 0.0f;
    out = std::copy(maps.normals.values().begin(), maps.normals.values().end(), out);
    std::copy(maps.albedo.values().begin(), maps.albedo.values().end(), out);
    surface.WriteNext(rows);
    progress.Advance();
  }
  progress.Finish();
  if (covered == 0) throw Error(stack.path(), fmt::format("{}: every map is zero", r.method()));
  surface.Commit();
  return summary;
}

// stack.exr's layers: the maps, then the derived normals and albedo the stack lacks, then height.
struct StackExrLayers {
  std::vector<std::string> extra;    // after the maps
  std::vector<std::string> all;      // the maps and `extra`
  std::vector<std::string> derived;  // what the surface scratch file gives: extra but height, mask
};

StackExrLayers StackExrLayersOf(const Representation& r) {
  std::vector<std::string> albedo_names;
  for (const auto& c : OutputChannelNames(r.output_channels())) {
    albedo_names.push_back("albedo." + c);
  }
  StackExrLayers layers;
  if (r.maps().FindChannel("normal.X") < 0) {
    layers.extra.insert(layers.extra.end(), {"normal.X", "normal.Y", "normal.Z"});
  }
  if (r.maps().FindChannel(albedo_names.front()) < 0) {
    layers.extra.insert(layers.extra.end(), albedo_names.begin(), albedo_names.end());
  }
  layers.derived = layers.extra;
  layers.derived.push_back("mask");
  layers.extra.push_back("height");
  layers.all = r.maps().channel_names();
  layers.all.insert(layers.all.end(), layers.extra.begin(), layers.extra.end());
  return layers;
}

// Pass 3's outputs: the height files, stack.exr and a pbr stack's material files.
struct HeightOutputs {
  HeightOutputs(const fs::path& folder, const StackBandReader& stack, const StackExrLayers& layers,
                const Range& range)
      : height_exr(folder / "height.exr", stack.width(), stack.height(), {"height"}),
        height_png(folder / "height.png", stack.width(), stack.height(), {"Y"},
                   HeightPngOptions(range)),
        stack_exr(folder / "stack.exr", StackExrDescription(stack.header(), layers), layers.all,
                  stack.width(), stack.height()) {
    if (!IsMicrofacet(stack.header().representation.shading())) return;
    pbr_files = PbrFileList(Png16());
    for (const PbrFile& file : pbr_files) {
      pbr_writers.push_back(std::make_unique<ImageBandWriter>(
          folder / file.name, stack.width(), stack.height(), file.channels, file.options));
    }
  }
  static nlohmann::json StackExrDescription(const LoadedStack& header,
                                            const StackExrLayers& layers) {
    nlohmann::json description = StackDescription(header.representation, header.provenance);
    description["extra_layers"] = layers.extra;
    return description;
  }
  void Commit() {
    height_exr.Commit();
    height_png.Commit();
    stack_exr.Commit();
    for (const auto& writer : pbr_writers) writer->Commit();
  }

  ImageBandWriter height_exr;
  ImageBandWriter height_png;
  StackBandWriter stack_exr;
  std::vector<PbrFile> pbr_files;
  std::vector<std::unique_ptr<ImageBandWriter>> pbr_writers;
};

// Pass 3 over the stack: the height (its mean over the mask taken out) into its files, stack.exr
// with its extra layers, and a pbr stack's material files.
void WriteHeightAndStackPass(StackBandReader& stack, int band_rows, const fs::path& surface_path,
                             const fs::path& height_path, const HeightSummary& height_summary,
                             const StackExrLayers& layers, double largest_f0,
                             HeightOutputs& outputs, Progress& progress) {
  const int width = stack.width();
  stack.Rewind();
  ImageBandReader surface(surface_path, {});
  ImageBandReader height_file(height_path, {});
  const std::vector<int> derived_channels = ChannelsOf(surface, layers.derived);
  const int bands = (stack.height() + band_rows - 1) / band_rows;
  progress.Start("export: height and stack", static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    const LoadedStack band = stack.ReadNext(band_rows);
    const int rows = band.representation.height();
    Image stored(width, rows, surface.channels());
    surface.ReadNext(stored.View());
    const Image derived = Channels(stored, derived_channels, layers.derived);
    Image height_band(width, rows, std::vector<std::string>{"height"});
    height_file.ReadNext(height_band.View());
    Mask mask(width, rows, false);
    const auto mask_plane = derived.plane(derived.channels() - 1);
    for (std::size_t p = 0; p < mask.pixel_count(); ++p) {
      mask.Set(p, mask_plane[p] >= 0.5f);
      height_band.pixel(p)[0] =
          mask[p] ? static_cast<float>(height_band.pixel(p)[0] - height_summary.mean) : 0.0f;
    }
    outputs.height_exr.WriteNext(height_band);
    outputs.height_png.WriteNext(NormalisedHeight(height_band, mask, height_summary.range));
    Image stack_layers(width, rows, layers.all);
    auto out = stack_layers.values().begin();  // planar: maps, derived layers, height
    const auto& maps = band.representation.maps().values();
    out = std::copy(maps.begin(), maps.end(), out);
    const auto derived_values = derived.values();
    out = std::copy(derived_values.begin(),
                    derived_values.end() - static_cast<std::ptrdiff_t>(mask.pixel_count()), out);
    std::copy(height_band.values().begin(), height_band.values().end(), out);
    outputs.stack_exr.Write(stack_layers);
    if (!outputs.pbr_files.empty()) {
      const PbrImages images = PbrBand(band.representation.maps(), mask, largest_f0);
      for (std::size_t f = 0; f < outputs.pbr_files.size(); ++f) {
        outputs.pbr_writers[f]->WriteNext(images.*outputs.pbr_files[f].image);
      }
    }
    progress.Advance();
  }
  progress.Finish();
}

int StreamedBandRows(const StackBandReader& stack, const StreamedExportOptions& options) {
  return BudgetedBandRows(
      options.band_rows, options.memory_bytes, kMinimumExportMemory,
      static_cast<std::size_t>(stack.width()) * StreamedExportBytesPerPixel(stack), stack.height());
}

}  // namespace

std::size_t RelitLightsBound(const StackBandReader& stack) {
  return std::max<std::size_t>(stack.header().provenance.capture_lights.size(), 193);
}

std::size_t StreamedExportBytesPerPixel(const StackBandReader& stack) {
  const Representation& r = stack.header().representation;
  const std::size_t maps = static_cast<std::size_t>(r.maps().channels());
  const std::size_t stored = static_cast<std::size_t>(stack.stored_channels());
  const std::size_t channels = static_cast<std::size_t>(r.output_channels());
  // The stack's band as stored and gathered (4 bytes per channel each), the relit images of the
  // Lambertian fit (the capture's lights, or the 193-light dome, x channels x 4 bytes), the
  // surface maps and their scratch copy (gradients, mask, normals, albedo: 6 + C floats, twice),
  // and stack.exr's band (maps and extra layers).
  const std::size_t lights = RelitLightsBound(stack);
  // A pbr stack adds its 12 channels of pbr maps (in pass 3), and their writers' copies.
  const std::size_t pbr = IsMicrofacet(r.shading()) ? 8 * 12 : 0;
  return 4 * (stored + maps) + 4 * lights * channels + 8 * (6 + channels) +
         4 * (maps + 4 + channels) + pbr;
}

std::size_t InMemoryExportBytes(int width, int height, int maps, int channels) {
  const std::size_t pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  // The stack (twice: read and written with its extra layers), the relit images, normals, albedo
  // and height, and the Poisson solve (IntegratePoissonAnySize): up to kDirectPoissonUnknowns its
  // factorised normal equations (measured: 187 MB of peak for 262,000 unknowns, so 720 bytes per
  // unknown); above it the tiled solve, which needs less than the 200 bytes per unknown the whole
  // field's conjugate gradients did (its window and result, plus at most about 0.5 GB for the
  // coarse grid): 200 is kept as a conservative bound.
  const std::size_t poisson = pixels <= kDirectPoissonUnknowns ? 720 : 200;
  return pixels * (8 * static_cast<std::size_t>(maps) +
                   4 * 193 * static_cast<std::size_t>(channels) + poisson);
}

std::size_t ExportOutputBytes(int width, int height, int maps, int channels, bool gltf) {
  // normal.png (16-bit RGB), albedo.png (8-bit), height.exr, height.png (16-bit), stack.exr (the
  // maps, derived normals and albedo, height), normal_gltf.png at most, and the scratch files of a
  // streamed export (gradients, mask, normals, albedo; the height).
  std::size_t bytes =
      ImageFileBytes(width, height, 3, 2) + ImageFileBytes(width, height, channels, 1) +
      ImageFileBytes(width, height, 1, 4) + ImageFileBytes(width, height, 1, 2) +
      ImageFileBytes(width, height, maps + 4 + channels, 4) +
      ImageFileBytes(width, height, 6 + channels, 4) + ImageFileBytes(width, height, 1, 4);
  if (gltf) bytes += ImageFileBytes(width, height, 3, 2);
  return bytes;
}

nlohmann::json ExportMapsStreamed(StackBandReader& stack, const fs::path& folder,
                                  const StreamedExportOptions& options,
                                  StreamedExportReport* report) {
  const LoadedStack& header = stack.header();
  const int width = stack.width(), height = stack.height();
  const int band_rows = StreamedBandRows(stack, options);
  NullProgress none;
  Progress& progress = OrNull(options.progress, none);
  ScratchFiles scratch;
  const fs::path surface_path = scratch.Add(folder / ".export-surface.exr");
  const fs::path height_path = scratch.Add(folder / ".export-height.exr");

  SurfaceOutputs surface(folder, width, height, header.representation.output_channels(),
                         options.maps);
  const SurfaceSummary surface_summary =
      WriteSurfacePass(stack, band_rows, options, surface_path, surface, progress);

  // Pass 2: the height into its scratch file, its mean and range over the mask.
  const HeightSummary height_summary =
      options.maps.height == HeightIntegrator::kPoisson
          ? TiledPoissonHeight(surface_path, height_path, width, height, options, progress)
          : FrankotChellappaHeight(surface_path, height_path, width, height, progress);

  const StackExrLayers layers = StackExrLayersOf(header.representation);
  HeightOutputs height_outputs(folder, stack, layers, height_summary.range);
  WriteHeightAndStackPass(stack, band_rows, surface_path, height_path, height_summary, layers,
                          surface_summary.largest_f0, height_outputs, progress);

  nlohmann::json description = ExportDescription(
      header, width, height, surface_summary.normals_source, height_summary.range, options.maps);
  description["streamed"] = {{"band_rows", band_rows}};
  if (options.maps.height == HeightIntegrator::kPoisson) {
    description["streamed"]["tile"] = options.poisson.tile;
    description["streamed"]["overlap"] = options.poisson.overlap;
    description["streamed"]["coarse_factor"] = CoarseFactor(width, height, options.poisson);
  }
  surface.Commit();
  height_outputs.Commit();
  PbrFiles pbr_description;
  if (IsMicrofacet(header.representation.shading())) {
    pbr_description = PbrDescription(surface_summary.largest_f0);
    description["pbr"] = pbr_description.description;
  }
  if (options.maps.gltf) {
    WriteTile(folder, width, height, height_summary.range, pbr_description, options.maps,
              description);
  }
  WriteJsonFile(folder / "export.json", description);
  if (report) {
    report->band_rows = band_rows;
    report->passes = 3;
  }
  return description;
}

}  // namespace photomat
