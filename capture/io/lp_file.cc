#include "capture/io/lp_file.h"

#include <fmt/format.h>

#include <cmath>
#include <span>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// More lights than this is a corrupt count line, not a dome (the largest domes have a few
// hundred lights).
constexpr long kMaxLights = 100000;

[[noreturn]] void FailAt(const fs::path& path, int line, const std::string& fault) {
  throw Error(path, fmt::format("line {}: {}", line, fault));
}

// Splits "name with spaces x y z" into the name and the three vector tokens.
LightFileEntry ParseLightLine(const fs::path& path, const std::string& line, int number) {
  std::string_view rest = line;
  std::string name;
  const auto first = rest.find_first_not_of(" \t");
  rest.remove_prefix(first);
  if (rest.front() == '"') {
    const auto close = rest.find('"', 1);
    if (close == std::string_view::npos) FailAt(path, number, "unterminated quoted file name");
    name = std::string(rest.substr(1, close - 1));
    rest.remove_prefix(close + 1);
  }
  const std::vector<std::string_view> tokens = SplitWhitespace(rest);
  const std::size_t name_tokens = name.empty() ? 1 : 0;
  if (tokens.size() < 3 + name_tokens) {
    FailAt(path, number, fmt::format("expected \"filename x y z\", found \"{}\"", line));
  }
  const auto vector_tokens = std::span(tokens).last(3);
  if (name.empty()) {
    // Keep the name exactly as written, inner spaces included.
    const std::size_t name_end = static_cast<std::size_t>(vector_tokens[0].data() - rest.data());
    name = std::string(rest.substr(0, name_end));
    while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.pop_back();
  } else if (tokens.size() != 3) {
    FailAt(path, number, fmt::format("expected three numbers after the file name in \"{}\"", line));
  }
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const auto value = ParseNumber(vector_tokens[i]);
    if (!value) {
      FailAt(path, number, fmt::format("\"{}\" is not a number", vector_tokens[i]));
    }
    v[i] = *value;
  }
  if (v.z() < 0.0) {
    FailAt(path, number,
           fmt::format("light below the sample plane (z = {}); the frame is x right, y up, z "
                       "toward the camera",
                       v.z()));
  }
  try {
    return {name, LightDirection::FromVector(v), number};
  } catch (const Error& error) {
    FailAt(path, number, error.fault());
  }
}

}  // namespace

std::vector<LightFileEntry> ParseLpText(const std::string& text, const fs::path& path) {
  const std::vector<std::string> lines = SplitLines(text);
  std::vector<LightFileEntry> entries;
  long declared_count = -1;
  int count_line = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    const int number = static_cast<int>(i) + 1;
    if (IsBlankOrComment(line)) continue;
    const auto tokens = SplitWhitespace(line);
    if (entries.empty() && declared_count < 0 && tokens.size() == 1) {
      const auto count = ParseNumber(tokens[0]);
      // Range first: converting a number beyond long's range to long is undefined (found by
      // tests/fuzz).
      if (!count || *count < 1 || *count > kMaxLights || *count != std::floor(*count)) {
        FailAt(path, number,
               fmt::format("expected the image count (1 to {}) or \"filename x y z\", found \"{}\"",
                           kMaxLights, line));
      }
      declared_count = static_cast<long>(*count);
      count_line = number;
      continue;
    }
    entries.push_back(ParseLightLine(path, line, number));
  }
  if (entries.empty()) throw Error(path, "no light lines (expected \"filename x y z\" per image)");
  if (declared_count >= 0 && declared_count != static_cast<long>(entries.size())) {
    throw Error(path, fmt::format("line {} gives the count {} but {} light lines follow",
                                  count_line, declared_count, entries.size()));
  }
  return entries;
}

std::vector<LightFileEntry> ReadLpFile(const fs::path& path) {
  return ParseLpText(ReadTextFile(path), path);
}

void WriteLpFile(const fs::path& path, const std::vector<std::string>& images,
                 const std::vector<LightDirection>& lights) {
  if (images.size() != lights.size()) {
    throw Error(path, fmt::format("{} images but {} lights", images.size(), lights.size()));
  }
  std::string text = fmt::format("{}\n", images.size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    const bool quote = images[i].find_first_of(" \t") != std::string::npos;
    text += fmt::format("{}{}{} {:.17g} {:.17g} {:.17g}\n", quote ? "\"" : "", images[i],
                        quote ? "\"" : "", lights[i].x(), lights[i].y(), lights[i].z());
  }
  WriteTextFileAtomically(path, text);
}

fs::path ResolveImagePath(const fs::path& folder, const std::string& name) {
  std::error_code ec;
  const fs::path as_given = folder / name;
  if (fs::exists(as_given, ec)) return as_given;
  std::string portable = name;
  for (char& c : portable) {
    if (c == '\\') c = '/';
  }
  const fs::path base = folder / fs::path(portable).filename();
  if (fs::exists(base, ec)) return base;
  return as_given;
}

}  // namespace photomat
