#include "calibrate/lights/light_list.h"

#include <fmt/format.h>

#include "capture/io/load_photometric_set.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {

namespace fs = std::filesystem;

std::vector<LightDirection> ReadLightList(const fs::path& path) {
  if (fs::is_directory(path) || path.extension() == ".lp" || path.extension() == ".json" ||
      path.filename() == "light_directions.txt" || path.filename() == "filenames.txt") {
    return ReadLightDirections(path);
  }
  std::vector<LightDirection> lights;
  std::optional<int> count;
  for (const auto& [line_number, numbers] : ReadNumberLines(path)) {
    if (numbers.size() == 1 && lights.empty() && !count) {
      if (numbers[0] < 1 || numbers[0] != static_cast<int>(numbers[0])) {
        throw Error(path,
                    fmt::format("line {}: the count must be a positive integer", line_number));
      }
      count = static_cast<int>(numbers[0]);
      continue;
    }
    if (numbers.size() != 3) {
      throw Error(path, fmt::format("line {}: expected 3 numbers \"x y z\", found {}", line_number,
                                    numbers.size()));
    }
    try {
      lights.push_back(LightDirection::FromVector(numbers[0], numbers[1], numbers[2]));
    } catch (const Error& error) {
      throw Error(path, fmt::format("line {}: {}", line_number, error.fault()));
    }
  }
  if (lights.empty()) throw Error(path, "no light directions");
  if (count && *count != static_cast<int>(lights.size())) {
    throw Error(path,
                fmt::format("the first line says {} lights but {} follow", *count, lights.size()));
  }
  return lights;
}

std::vector<std::vector<float>> ReadLightIntensities(const fs::path& path) {
  std::vector<std::vector<float>> rows;
  for (const auto& [line_number, numbers] : ReadNumberLines(path)) {
    std::vector<float> row;
    for (const double value : numbers) {
      if (!(value > 0.0)) {
        throw Error(path,
                    fmt::format("line {}: '{}' is not a positive number", line_number, value));
      }
      row.push_back(static_cast<float>(value));
    }
    if (!rows.empty() && row.size() != rows.front().size()) {
      throw Error(path, fmt::format("line {}: {} values, but the first line has {}", line_number,
                                    row.size(), rows.front().size()));
    }
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw Error(path, "no intensities");
  return rows;
}

void WriteLightIntensities(const fs::path& path,
                           const std::vector<std::vector<float>>& intensities) {
  std::string text;
  for (const auto& row : intensities) {
    for (std::size_t c = 0; c < row.size(); ++c)
      text += fmt::format("{}{:.9g}", c ? " " : "", row[c]);
    text += "\n";
  }
  WriteTextFileAtomically(path, text);
}

}  // namespace photomat
