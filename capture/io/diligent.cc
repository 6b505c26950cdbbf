#include "capture/io/diligent.h"

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

struct NumberRow {
  std::vector<double> values;
  int line;
};

// Non-blank lines of `path`, each parsed as exactly `width` numbers.
std::vector<NumberRow> ReadNumberRows(const fs::path& path, int width) {
  std::vector<NumberRow> rows;
  const auto lines = SplitLines(ReadTextFile(path));
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (IsBlankOrComment(lines[i])) continue;
    const int line = static_cast<int>(i) + 1;
    const auto tokens = SplitWhitespace(lines[i]);
    if (static_cast<int>(tokens.size()) != width) {
      throw Error(path,
                  fmt::format("line {}: expected {} numbers, found \"{}\"", line, width, lines[i]));
    }
    NumberRow row{{}, line};
    for (auto token : tokens) {
      const auto value = ParseNumber(token);
      if (!value) throw Error(path, fmt::format("line {}: \"{}\" is not a number", line, token));
      row.values.push_back(*value);
    }
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw Error(path, "file is empty");
  return rows;
}

void CheckCount(const fs::path& file, std::size_t rows, const fs::path& names, std::size_t count) {
  if (rows != count) {
    throw Error(file, fmt::format("{} rows, but {} lists {} images", rows,
                                  names.filename().string(), count));
  }
}

}  // namespace

DiligentFiles ReadDiligentFiles(const fs::path& folder) {
  DiligentFiles files;
  const fs::path names_file = folder / "filenames.txt";
  for (const std::string& line : SplitLines(ReadTextFile(names_file))) {
    if (IsBlankOrComment(line)) continue;
    const auto first = line.find_first_not_of(" \t");
    const auto last = line.find_last_not_of(" \t");
    files.images.push_back(folder / line.substr(first, last - first + 1));
  }
  if (files.images.empty()) throw Error(names_file, "lists no image");

  const fs::path directions_file = folder / "light_directions.txt";
  const auto directions = ReadNumberRows(directions_file, 3);
  CheckCount(directions_file, directions.size(), names_file, files.images.size());
  for (const NumberRow& row : directions) {
    const Eigen::Vector3d v(row.values[0], row.values[1], row.values[2]);
    if (v.z() < 0.0) {
      throw Error(directions_file,
                  fmt::format("line {}: light below the sample plane (z < 0)", row.line));
    }
    try {
      files.lights.push_back(LightDirection::FromVector(v));
    } catch (const Error& error) {
      throw Error(directions_file, fmt::format("line {}: {}", row.line, error.fault()));
    }
  }

  std::error_code ec;
  const fs::path intensities_file = folder / "light_intensities.txt";
  if (fs::exists(intensities_file, ec)) {
    const auto intensities = ReadNumberRows(intensities_file, 3);
    CheckCount(intensities_file, intensities.size(), names_file, files.images.size());
    for (const NumberRow& row : intensities) {
      std::vector<float> rgb;
      for (double v : row.values) {
        if (v <= 0.0) {
          throw Error(intensities_file,
                      fmt::format("line {}: intensities must be positive", row.line));
        }
        rgb.push_back(static_cast<float>(v));
      }
      files.intensities.push_back(std::move(rgb));
    }
  }
  for (const auto& image : files.images) {
    if (!fs::exists(image, ec)) {
      throw Error(names_file, fmt::format("image \"{}\" not found", image.filename().string()));
    }
  }
  if (fs::exists(folder / "mask.png", ec)) files.mask = folder / "mask.png";
  if (fs::exists(folder / "gt_normals.exr", ec)) {
    files.ground_truth_normals = folder / "gt_normals.exr";
  }
  return files;
}

}  // namespace photomat
