#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "synthesize/volume/volume.h"

namespace photomat {

// Solid textures on disk, in two formats:
//
// - OpenVDB (`.vdb`): one float grid per channel, named by the channel, voxel (x, y, z) at
//   coordinate (x, y, z) with unit voxel size, and a file metadata string "photomat:volume" (JSON:
//   size and channel order) so a volume reads back exactly. For Blender, a colour volume (channels
//   R, G, B) also carries a vector grid "color" and a constant float grid "density" (the names its
//   volume shader reads); they are skipped on reading. A VDB written elsewhere (no photomat
//   metadata) reads as its float grids over the bounding box of their active voxels.
// - An EXR slice stack (any other path, a folder): `slice_0000.exr`, ... one float EXR per z (the
//   xy slices, x along columns, y along rows) with named channels, and `volume.json` listing them.
//   The manifest is written last, so a stack whose writing failed has none and does not load.
//
// Errors name the file and the fault; outputs are written atomically (each file whole or not at
// all; a stack's manifest only after all of its slices).

enum class VolumeFormat { kOpenVdb, kExrSlices };
// kOpenVdb for a path ending in ".vdb" (any case), kExrSlices otherwise.
VolumeFormat VolumeFormatForPath(const std::filesystem::path& path);

void WriteVolume(const std::filesystem::path& path, const Image& volume);
Image ReadVolume(const std::filesystem::path& path);

struct VdbWriteOptions {
  // Adds the "color" and "density" grids Blender's volume shader reads, when there are R, G, B.
  bool blender_grids = true;
};
void WriteVolumeVdb(const std::filesystem::path& path, const Image& volume,
                    const VdbWriteOptions& options = {});
Image ReadVolumeVdb(const std::filesystem::path& path);

void WriteExrSliceStack(const std::filesystem::path& folder, const Image& volume);
Image ReadExrSliceStack(const std::filesystem::path& folder);

// How a slice becomes a picture.
struct SliceDisplay {
  // Stretch the volume's [min, max] over the display range (for non-colour channels such as
  // normals or PTM terms); otherwise values are linear colour, clamped to [0, 1].
  bool normalise = false;
};
// The channels a picture of the volume shows: R, G, B when the volume names them, else the first
// three, else the first one (grey).
std::vector<int> DisplayChannels(const Image& volume);
// Slice `index` of `plane` as an 8-bit sRGB PNG (or any format by extension).
void WriteSliceImage(const std::filesystem::path& path, const Image& volume, SlicePlane plane,
                     int index, const SliceDisplay& display = {});
// The three central slices (xy at z = size.z / 2, and so on) as `<prefix>xy.png`, `<prefix>xz.png`,
// `<prefix>yz.png` in `folder` (created). Returns the paths written.
std::vector<std::filesystem::path> WriteCentralSlices(const std::filesystem::path& folder,
                                                      const std::string& prefix,
                                                      const Image& volume,
                                                      const SliceDisplay& display = {});

}  // namespace photomat
