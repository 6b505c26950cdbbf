#include "represent/stack/map_stack.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "represent/stack/stack_band_writer.h"  // StackDescription

namespace photomat {
namespace {

namespace fs = std::filesystem;

MapLayout LayoutFromJson(const JsonReader& json) {
  MapLayout layout;
  layout.basis_size = json["basis_size"].Integer();
  layout.basis_per_channel = json["basis_per_channel"].Boolean();
  layout.has_gain = json["has_gain"].Boolean();
  layout.output_channels = json["output_channels"].Integer();
  if (json.Has("shading_maps")) {
    layout.shading_maps = json["shading_maps"].Integer();
    if (layout.shading_maps < 1 || layout.shading_maps > 1024) json.Fail("implausible shading");
  }
  if (layout.basis_size < 1 || layout.basis_size > 1024 || layout.output_channels < 1 ||
      layout.output_channels > 64) {
    json.Fail("implausible map layout");
  }
  return layout;
}

}  // namespace

nlohmann::json StackDescription(const Representation& representation,
                                const StackProvenance& provenance) {
  const Image& maps = representation.maps();
  nlohmann::json lights = nlohmann::json::array();
  for (const auto& l : provenance.capture_lights) lights.push_back({l.x(), l.y(), l.z()});
  nlohmann::json description = {
      {"format", kStackFormat},
      {"version", 1},
      {"method", representation.method()},
      {"layout", representation.layout().ToJson()},
      {"channels", maps.channel_names()},
      {"basis", representation.basis().ToJson()},
      {"details", representation.details()},
  };
  if (const PixelShading* shading = representation.shading()) {
    description["shading"] = shading->ToJson();
  }
  description["capture"] = {
      {"lights", lights}, {"colour_space", provenance.colour_space}, {"source", provenance.source}};
  if (!provenance.images.empty()) {
    nlohmann::json images = nlohmann::json::array();
    for (const ImageEncodingRecord& image : provenance.images) {
      images.push_back({{"file", image.file},
                        {"encoding", image.encoding},
                        {"decided_by", image.decided_by},
                        {"evidence", image.evidence}});
    }
    description["capture"]["images"] = std::move(images);
  }
  return description;
}

void SaveRepresentation(const fs::path& path, const Representation& representation,
                        const StackProvenance& provenance, ExrCompression compression) {
  SaveRepresentation(path, representation, provenance, Image(), compression);
}

void SaveRepresentation(const fs::path& path, const Representation& representation,
                        const StackProvenance& provenance, const Image& extra_layers,
                        ExrCompression compression) {
  const Image& maps = representation.maps();
  if (static_cast<int>(maps.channel_names().size()) != maps.channels()) {
    throw Error(path, "the maps have no channel names");
  }
  nlohmann::json description = StackDescription(representation, provenance);
  ImageWriteOptions options;
  options.exr_compression = compression;
  if (extra_layers.empty()) {
    options.attributes[kStackAttribute] = description.dump();
    WriteImage(path, maps, options);
    return;
  }
  if (extra_layers.width() != maps.width() || extra_layers.height() != maps.height() ||
      static_cast<int>(extra_layers.channel_names().size()) != extra_layers.channels()) {
    throw Error(path, "extra layers need names and the maps' size");
  }
  std::vector<std::string> names = maps.channel_names();
  for (const std::string& name : extra_layers.channel_names()) {
    if (maps.FindChannel(name) >= 0) {
      throw Error(path, fmt::format("extra layer \"{}\" repeats a map", name));
    }
    names.push_back(name);
  }
  description["extra_layers"] = extra_layers.channel_names();
  Image all(maps.width(), maps.height(), names);
  // Planar: the maps' planes, then the extra layers'.
  std::copy(extra_layers.values().begin(), extra_layers.values().end(),
            std::copy(maps.values().begin(), maps.values().end(), all.values().begin()));
  options.attributes[kStackAttribute] = description.dump();
  WriteImage(path, all, options);
}

namespace {

// The channels of `stored` named by the description's array `list`, in that order.
Image SelectChannels(const Image& stored, const JsonReader& list) {
  std::vector<std::string> names;
  std::vector<int> source_channel;
  for (std::size_t i = 0; i < list.ArraySize(); ++i) {
    names.push_back(list[i].String());
    source_channel.push_back(stored.FindChannel(names.back()));
    if (source_channel.back() < 0) {
      list[i].Fail(fmt::format("map \"{}\" is not in the file", names.back()));
    }
  }
  Image selected(stored.width(), stored.height(), names);
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::span<const float> in = stored.plane(source_channel[c]);
    std::copy(in.begin(), in.end(), selected.plane(static_cast<int>(c)).begin());
  }
  return selected;
}

}  // namespace

LoadedStack LoadRepresentation(const fs::path& path) {
  ImageReadOptions read;
  read.keep_alpha = true;
  LoadedImage loaded = ReadImage(path, read);
  const auto attribute = loaded.info.attributes.find(kStackAttribute);
  if (attribute == loaded.info.attributes.end()) {
    throw Error(path, fmt::format("not a photomat map stack (no \"{}\" header attribute)",
                                  kStackAttribute));
  }
  return StackFromDescription(attribute->second, loaded.image, path);
}

LoadedStack StackFromDescription(const std::string& text, const Image& stored,
                                 const fs::path& path) {
  nlohmann::json description;
  try {
    description = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception&) {
    throw Error(path,
                fmt::format("the \"{}\" header attribute is not valid JSON", kStackAttribute));
  }
  const JsonReader json(description, path, kStackAttribute);
  if (!description.is_object() || json["format"].String() != kStackFormat) {
    json.Fail(fmt::format("expected format \"{}\"", kStackFormat));
  }
  if (json["version"].Integer() != 1) json["version"].Fail("unsupported version");
  const MapLayout layout = LayoutFromJson(json["layout"]);
  const JsonReader channels = json["channels"];
  if (static_cast<int>(channels.ArraySize()) != layout.MapCount()) {
    channels.Fail(
        fmt::format("{} names for a layout of {} maps", channels.ArraySize(), layout.MapCount()));
  }
  // OpenEXR keeps channels sorted by name: put them back in layout order.
  Image maps = SelectChannels(stored, channels);
  Image extra_layers;
  if (json.Has("extra_layers") && json["extra_layers"].ArraySize() > 0) {
    extra_layers = SelectChannels(stored, json["extra_layers"]);
  }
  StackProvenance provenance;
  if (json.Has("capture")) {
    const JsonReader capture = json["capture"];
    if (capture.Has("lights")) {
      const JsonReader lights = capture["lights"];
      for (std::size_t i = 0; i < lights.ArraySize(); ++i) {
        const auto v = lights[i].Numbers();
        if (v.size() != 3) lights[i].Fail("expected 3 numbers");
        try {
          provenance.capture_lights.push_back(LightDirection::FromVector(v[0], v[1], v[2]));
        } catch (const Error& error) {
          lights[i].Fail(error.fault());
        }
      }
    }
    if (capture.Has("colour_space")) provenance.colour_space = capture["colour_space"].String();
    if (capture.Has("source")) provenance.source = capture["source"].String();
    if (capture.Has("images")) {
      const JsonReader images = capture["images"];
      for (std::size_t i = 0; i < images.ArraySize(); ++i) {
        const JsonReader image = images[i];
        provenance.images.push_back({image["file"].String(), image["encoding"].String(),
                                     image["decided_by"].String(), image["evidence"].String()});
      }
    }
  }
  try {
    nlohmann::json details = description.value("details", nlohmann::json::object());
    if (layout.shading_maps > 0) {
      if (!json.Has("shading")) json["layout"].Fail("shading maps but no \"shading\"");
      std::shared_ptr<const PixelShading> shading = PixelShadingFromJson(json["shading"]);
      if (shading->map_count() != layout.shading_maps) {
        json["shading"].Fail(fmt::format("{} shading needs {} maps, the layout has {}",
                                         shading->kind(), shading->map_count(),
                                         layout.shading_maps));
      }
      return {Representation(json["method"].String(), std::move(maps), std::move(shading),
                             std::move(details)),
              std::move(provenance), std::move(extra_layers)};
    }
    return {Representation(json["method"].String(), std::move(maps), layout,
                           LightBasisFromJson(json["basis"]), std::move(details)),
            std::move(provenance), std::move(extra_layers)};
  } catch (const Error& error) {
    throw error.InFile(path);
  }
}

void WriteFitManifest(const fs::path& folder, const std::string& input,
                      const std::map<std::string, std::string>& stacks) {
  WriteJsonFile(folder / kFitManifestName,
                {{"format", "photomat-fit"}, {"version", 1}, {"input", input}, {"stacks", stacks}});
}

std::map<std::string, fs::path> ReadFitManifest(const fs::path& folder) {
  const fs::path path = folder / kFitManifestName;
  const nlohmann::json document = ReadJsonFile(path);
  const JsonReader json(document, path);
  if (json["format"].String() != "photomat-fit") json["format"].Fail("expected \"photomat-fit\"");
  std::map<std::string, fs::path> stacks;
  const JsonReader entries = json["stacks"];
  if (!entries.value().is_object()) entries.Fail("expected an object");
  for (const auto& [method, file] : entries.value().items()) {
    stacks[method] = folder / entries[method].String();
  }
  return stacks;
}

fs::path ResolveStack(const fs::path& path, const std::optional<std::string>& method) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) {
    if (!fs::exists(path, ec)) throw Error(path, "no such map stack");
    return path;
  }
  const auto stacks = ReadFitManifest(path);
  std::string available;
  for (const auto& [name, file] : stacks) available += (available.empty() ? "" : ", ") + name;
  if (method) {
    const auto it = stacks.find(*method);
    if (it == stacks.end()) {
      throw Error(path, fmt::format("no \"{}\" stack here; available: {}", *method, available));
    }
    return it->second;
  }
  if (stacks.size() == 1) return stacks.begin()->second;
  throw Error(path, fmt::format("holds several stacks ({}); choose one with --method", available));
}

}  // namespace photomat
