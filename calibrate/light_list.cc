#include "calibrate/light_list.h"

#include <fmt/format.h>

#include "capture/load_photometric_set.h"
#include "capture/text_parsing.h"
#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat {

namespace fs = std::filesystem;

std::vector<LightDirection> ReadLightList(const fs::path& path) {
  if (fs::is_directory(path) || path.extension() == ".lp" || path.extension() == ".json" ||
      path.filename() == "light_directions.txt" || path.filename() == "filenames.txt") {
    return ReadLightDirections(path);
  }
  const std::string text = ReadTextFile(path);
  std::vector<LightDirection> lights;
  std::optional<int> count;
  int line_number = 0;
  for (const std::string& line : SplitLines(text)) {
    ++line_number;
    if (IsBlankOrComment(line)) continue;
    const auto tokens = SplitWhitespace(line);
    std::vector<double> numbers;
    for (std::string_view token : tokens) {
      const auto value = ParseNumber(token);
      if (!value) {
        throw Error(path, fmt::format("line {}: '{}' is not a number (expected \"x y z\")",
                                      line_number, token));
      }
      numbers.push_back(*value);
    }
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

}  // namespace photomat
