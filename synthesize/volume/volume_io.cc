#include "synthesize/volume/volume_io.h"

#include <fmt/format.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cctype>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

constexpr const char* kVdbMetadataKey = "photomat:volume";
constexpr const char* kStackManifest = "volume.json";
constexpr const char* kStackFormat = "photomat-volume-slices";
constexpr const char* kBlenderColourGrid = "color";
constexpr const char* kBlenderDensityGrid = "density";

std::vector<std::string> CheckedChannelNames(const Image& volume,
                                             const std::filesystem::path& path) {
  std::vector<std::string> names = ChannelNamesOrDefault(volume);
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (name.empty()) throw Error(path, "a channel of the volume has an empty name");
    if (!seen.insert(name).second) {
      throw Error(path, fmt::format("channel name \"{}\" appears twice", name));
    }
  }
  return names;
}

nlohmann::json SizeJson(const ImageExtent& size) { return {size.width, size.height, size.depth}; }

ImageExtent SizeFromJson(const JsonReader& reader) {
  if (reader.ArraySize() != 3) reader.Fail("expected [x, y, z]");
  return {reader[0].Integer(), reader[1].Integer(), reader[2].Integer()};
}

// OpenVDB keeps a registry of grid types; registering twice is harmless, so every entry point
// calls this.
void InitialiseOpenVdb() { openvdb::initialize(); }

bool HasRgb(const Image& volume) {
  return volume.FindChannel("R") >= 0 && volume.FindChannel("G") >= 0 &&
         volume.FindChannel("B") >= 0;
}

}  // namespace

VolumeFormat VolumeFormatForPath(const std::filesystem::path& path) {
  return LowerExtension(path) == ".vdb" ? VolumeFormat::kOpenVdb : VolumeFormat::kExrSlices;
}

void WriteVolume(const std::filesystem::path& path, const Image& volume) {
  if (VolumeFormatForPath(path) == VolumeFormat::kOpenVdb) {
    WriteVolumeVdb(path, volume);
  } else {
    WriteExrSliceStack(path, volume);
  }
}

Image ReadVolume(const std::filesystem::path& path) {
  return VolumeFormatForPath(path) == VolumeFormat::kOpenVdb ? ReadVolumeVdb(path)
                                                             : ReadExrSliceStack(path);
}

void WriteVolumeVdb(const std::filesystem::path& path, const Image& volume,
                    const VdbWriteOptions& options) {
  if (volume.empty()) throw Error(path, "cannot write an empty volume");
  InitialiseOpenVdb();
  const std::vector<std::string> names = CheckedChannelNames(volume, path);
  const ImageExtent& size = volume.extent();
  openvdb::GridPtrVec grids;
  for (int c = 0; c < volume.channels(); ++c) {
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(names[static_cast<std::size_t>(c)]);
    auto accessor = grid->getAccessor();
    for (int z = 0; z < size.depth; ++z) {
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          accessor.setValue(openvdb::Coord(x, y, z), volume.at(x, y, z, c));
        }
      }
    }
    grid->pruneGrid(0.0f);  // lossless: only constant nodes become tiles
    grids.push_back(grid);
  }
  const bool blender = options.blender_grids && HasRgb(volume) &&
                       volume.FindChannel(kBlenderColourGrid) < 0 &&
                       volume.FindChannel(kBlenderDensityGrid) < 0;
  if (blender) {
    const int r = volume.FindChannel("R"), g = volume.FindChannel("G"), b = volume.FindChannel("B");
    openvdb::Vec3SGrid::Ptr colour = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
    colour->setName(kBlenderColourGrid);
    openvdb::FloatGrid::Ptr density = openvdb::FloatGrid::create(0.0f);
    density->setName(kBlenderDensityGrid);
    density->setGridClass(openvdb::GRID_FOG_VOLUME);
    density->fill(
        openvdb::CoordBBox(openvdb::Coord(0, 0, 0),
                           openvdb::Coord(size.width - 1, size.height - 1, size.depth - 1)),
        1.0f, true);
    auto accessor = colour->getAccessor();
    for (int z = 0; z < size.depth; ++z) {
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          accessor.setValue(
              openvdb::Coord(x, y, z),
              openvdb::Vec3s(volume.at(x, y, z, r), volume.at(x, y, z, g), volume.at(x, y, z, b)));
        }
      }
    }
    grids.push_back(colour);
    grids.push_back(density);
  }
  openvdb::MetaMap metadata;
  const nlohmann::json description = {
      {"format", "photomat-volume"}, {"version", 1}, {"size", SizeJson(size)}, {"channels", names}};
  metadata.insertMeta(kVdbMetadataKey, openvdb::StringMetadata(description.dump()));
  WriteFileAtomically(path, [&](const std::filesystem::path& temp) {
    try {
      openvdb::io::File file(temp.string());
      file.write(grids, metadata);
      file.close();
    } catch (const openvdb::Exception& error) {
      throw Error(path, fmt::format("cannot write OpenVDB file: {}", error.what()));
    }
  });
}

namespace {

Image ReadVdbGrids(const std::filesystem::path& path, openvdb::io::File& file) {
  openvdb::MetaMap::Ptr metadata = file.getMetadata();
  const openvdb::GridPtrVecPtr all = file.getGrids();
  std::vector<openvdb::FloatGrid::Ptr> channels;
  std::vector<std::string> names;
  ImageExtent size;
  openvdb::Coord origin(0, 0, 0);
  const auto described = metadata ? (*metadata)[kVdbMetadataKey] : openvdb::Metadata::Ptr();
  if (described) {
    nlohmann::json json;
    try {
      json = nlohmann::json::parse(described->str());
    } catch (const nlohmann::json::exception& error) {
      throw Error(path, fmt::format("malformed {} metadata: {}", kVdbMetadataKey, error.what()));
    }
    const JsonReader reader(json, path, kVdbMetadataKey);
    size = SizeFromJson(reader["size"]);
    const JsonReader channel_list = reader["channels"];
    for (std::size_t c = 0; c < channel_list.ArraySize(); ++c) {
      names.push_back(channel_list[c].String());
    }
    for (const std::string& name : names) {
      openvdb::FloatGrid::Ptr grid;
      for (const auto& base : *all) {
        if (base->getName() == name) grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
      }
      if (!grid) throw Error(path, fmt::format("no float grid named \"{}\"", name));
      channels.push_back(grid);
    }
  } else {
    openvdb::CoordBBox box;
    for (const auto& base : *all) {
      openvdb::FloatGrid::Ptr grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
      if (!grid) continue;
      channels.push_back(grid);
      names.push_back(grid->getName().empty() ? fmt::format("channel{}", names.size())
                                              : grid->getName());
      box.expand(grid->evalActiveVoxelBoundingBox());
    }
    if (channels.empty()) throw Error(path, "no float grid in the file");
    if (box.empty()) throw Error(path, "the float grids have no active voxels");
    origin = box.min();
    const openvdb::Coord extent = box.dim();
    size = {extent.x(), extent.y(), extent.z()};
  }
  if (channels.empty()) throw Error(path, "the volume has no channels");
  Image volume(size, names);
  for (std::size_t c = 0; c < channels.size(); ++c) {
    const auto accessor = channels[c]->getConstAccessor();
    for (int z = 0; z < size.depth; ++z) {
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          const float value = accessor.getValue(origin.offsetBy(x, y, z));
          if (!std::isfinite(value)) {
            throw Error(path, fmt::format("non-finite value in grid \"{}\" at ({}, {}, {})",
                                          names[c], x, y, z));
          }
          volume.at(x, y, z, static_cast<int>(c)) = value;
        }
      }
    }
  }
  return volume;
}

}  // namespace

Image ReadVolumeVdb(const std::filesystem::path& path) {
  InitialiseOpenVdb();
  if (!std::filesystem::is_regular_file(path)) throw Error(path, "no such file");
  try {
    openvdb::io::File file(path.string());
    file.open();
    Image volume = ReadVdbGrids(path, file);
    file.close();
    return volume;
  } catch (const openvdb::Exception& error) {
    throw Error(path, fmt::format("not a readable OpenVDB file: {}", error.what()));
  } catch (const std::ios_base::failure& error) {
    throw Error(path, fmt::format("not a readable OpenVDB file: {}", error.what()));
  }
}

void WriteExrSliceStack(const std::filesystem::path& folder, const Image& volume) {
  if (volume.empty()) throw Error(folder, "cannot write an empty volume");
  const std::vector<std::string> names = CheckedChannelNames(volume, folder);
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw Error(folder, fmt::format("cannot create folder: {}", error.message()));
  // A stale manifest must not describe slices that are about to be replaced.
  std::filesystem::remove(folder / kStackManifest, error);
  nlohmann::json files = nlohmann::json::array();
  for (int z = 0; z < volume.depth(); ++z) {
    const std::string name = fmt::format("slice_{:04d}.exr", z);
    Image slice(volume.SliceXY(z));
    slice.set_channel_names(names);
    WriteImage(folder / name, slice);
    files.push_back(name);
  }
  WriteJsonFile(folder / kStackManifest, {{"format", kStackFormat},
                                          {"version", 1},
                                          {"size", SizeJson(volume.extent())},
                                          {"channels", names},
                                          {"plane", "xy"},
                                          {"slices", files}});
}

Image ReadExrSliceStack(const std::filesystem::path& folder) {
  const std::filesystem::path manifest = folder / kStackManifest;
  if (!std::filesystem::is_regular_file(manifest)) {
    throw Error(folder, fmt::format("not a volume: no {} (an OpenVDB file must end in .vdb)",
                                    kStackManifest));
  }
  const nlohmann::json json = ReadJsonFile(manifest);
  const JsonReader reader(json, manifest);
  if (reader["format"].String() != kStackFormat) {
    reader["format"].Fail(fmt::format("expected \"{}\"", kStackFormat));
  }
  const ImageExtent size = SizeFromJson(reader["size"]);
  std::vector<std::string> names;
  for (std::size_t c = 0; c < reader["channels"].ArraySize(); ++c) {
    names.push_back(reader["channels"][c].String());
  }
  if (names.empty()) reader["channels"].Fail("no channels");
  const JsonReader slices = reader["slices"];
  if (static_cast<int>(slices.ArraySize()) != size.depth) {
    slices.Fail(fmt::format("{} slices for a depth of {}", slices.ArraySize(), size.depth));
  }
  Image volume(size, names);
  for (int z = 0; z < size.depth; ++z) {
    const std::filesystem::path file = folder / slices[static_cast<std::size_t>(z)].String();
    ImageReadOptions options;
    options.keep_alpha = true;
    Image slice = ReadImage(file, options).image;
    if (slice.width() != size.width || slice.height() != size.height ||
        slice.channels() != static_cast<int>(names.size())) {
      throw Error(file, fmt::format("slice is {}x{} with {} channels; the stack is {}x{} with {}",
                                    slice.width(), slice.height(), slice.channels(), size.width,
                                    size.height, names.size()));
    }
    CopyPixels(slice, volume.SliceXY(z));
  }
  return volume;
}

std::vector<int> DisplayChannels(const Image& volume) {
  if (HasRgb(volume)) {
    return {volume.FindChannel("R"), volume.FindChannel("G"), volume.FindChannel("B")};
  }
  if (volume.channels() >= 3) return {0, 1, 2};
  return {0};
}

void WriteSliceImage(const std::filesystem::path& path, const Image& volume, SlicePlane plane,
                     int index, const SliceDisplay& display) {
  const std::vector<int> channels = DisplayChannels(volume);
  float low = 0.0f, high = 1.0f;
  if (display.normalise) {
    low = std::numeric_limits<float>::max();
    high = std::numeric_limits<float>::lowest();
    for (int c : channels) {
      const std::span<const float> values = volume.plane(c);
      const auto [plane_low, plane_high] = std::minmax_element(values.begin(), values.end());
      low = std::min(low, *plane_low);
      high = std::max(high, *plane_high);
    }
    if (!(high > low)) high = low + 1.0f;
  }
  const Image slice = ExtractSlice(volume, plane, index);
  Image picture(slice.width(), slice.height(), static_cast<int>(channels.size()));
  for (int y = 0; y < slice.height(); ++y) {
    for (int x = 0; x < slice.width(); ++x) {
      for (std::size_t c = 0; c < channels.size(); ++c) {
        const float value = (slice.at(x, y, channels[c]) - low) / (high - low);
        picture.at(x, y, static_cast<int>(c)) = std::clamp(value, 0.0f, 1.0f);
      }
    }
  }
  ImageWriteOptions options;
  options.sample_type = SampleType::kUint8;
  options.encoding = ColourSpace::kSrgb;
  WriteImage(path, picture, options);
}

std::vector<std::filesystem::path> WriteCentralSlices(const std::filesystem::path& folder,
                                                      const std::string& prefix,
                                                      const Image& volume,
                                                      const SliceDisplay& display) {
  std::error_code error;
  std::filesystem::create_directories(folder, error);
  if (error) throw Error(folder, fmt::format("cannot create folder: {}", error.message()));
  std::vector<std::filesystem::path> written;
  for (SlicePlane plane : kAllSlicePlanes) {
    const std::filesystem::path path =
        folder / fmt::format("{}{}.png", prefix, std::string(ToString(plane)));
    WriteSliceImage(path, volume, plane, SliceCount(volume.extent(), plane) / 2, display);
    written.push_back(path);
  }
  return written;
}

}  // namespace photomat
