#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// One line of a light-position (.lp) file: an image and the direction of its light.
struct LightFileEntry {
  std::string image;  // as written in the file
  LightDirection light;
  int line = 0;  // 1-based line number, for messages
};

// Reads a .lp file (RTIBuilder, PTMfitter, relight): `filename x y z` per image, in photomat's
// light frame (x right, y up, z toward the camera). What is accepted (each case is tested):
//   - an optional first line holding only the image count; when present it must match;
//   - file names with spaces (the last three tokens are the vector) or in double quotes;
//   - LF or CRLF line ends, a UTF-8 byte-order mark, blank lines and '#' comment lines;
//   - decimal commas ("0,5") when a number has no decimal point;
//   - vectors of any length: they are normalised.
// Rejected with an Error naming the file and line: a missing file name, a number that is not a
// number, a wrong count of numbers, a zero-length or non-finite vector, a light below the sample
// plane (z < 0), a count line that disagrees with the lines that follow, and a file with no light.
std::vector<LightFileEntry> ReadLpFile(const std::filesystem::path& path);

// The same, from text already in memory; `path` is only used in messages.
std::vector<LightFileEntry> ParseLpText(const std::string& text, const std::filesystem::path& path);

// Writes a .lp file with the count line and 17 significant digits (atomically).
void WriteLpFile(const std::filesystem::path& path, const std::vector<std::string>& images,
                 const std::vector<LightDirection>& lights);

// Resolves an image named in a light file: relative names against `folder`; names that do not
// exist as given (absolute paths from another machine, Windows paths) by their base name in
// `folder`. Returns the first candidate that exists, or the plain `folder / name` if none does.
std::filesystem::path ResolveImagePath(const std::filesystem::path& folder,
                                       const std::string& name);

}  // namespace photomat
