#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "capture/io/load_photometric_set.h"

namespace photomat::testing {

// Writes a small set in each on-disk layout photomat reads, so that tests of malformed input can
// break one thing at a time in every layout.
struct LayoutWriter {
  InputKind kind;
  // Writes the light file(s) for images `names` with light vectors as text ("x y z"); `count` is
  // the number of images the layout declares (the .lp count line, DiLiGenT's filenames.txt; for a
  // manifest, a count other than lights.size() gives each image a 2-value intensity).
  std::function<void(const std::filesystem::path& dir, const std::vector<std::string>& names,
                     const std::vector<std::string>& lights, int count)>
      write_lights;
  std::filesystem::path light_file;  // relative to the folder
};

// The .lp, DiLiGenT and manifest writers, in that order.
std::vector<LayoutWriter> Layouts();

// 16-bit RGB PNGs `names` of `width` x `height` with varied values in `dir`.
void WriteImages(const std::filesystem::path& dir, const std::vector<std::string>& names,
                 int width = 6, int height = 4);

// A Lambertian capture of `width` x `height` on the thesis grid (slants 30, 45, 60 x 12 tilts),
// written image by image (never the whole set in this process) as half-float EXR without
// compression (quick to write and read back), with its .lp file, whose path it returns: for tests
// of streamed steps under a memory limit.
std::filesystem::path WriteLargeLambertianCapture(const std::filesystem::path& folder, int width,
                                                  int height);

}  // namespace photomat::testing
