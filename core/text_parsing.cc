#include "core/text_parsing.h"

#include <fmt/format.h>

#include <cctype>
#include <charconv>
#include <cmath>

#include "core/atomic_file.h"
#include "core/error.h"

namespace photomat {

std::vector<std::string> SplitLines(std::string_view text) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (line.ends_with('\r')) line.remove_suffix(1);
    lines.emplace_back(line);
    if (end == text.size()) break;
    start = end + 1;
  }
  return lines;
}

std::vector<std::string_view> SplitWhitespace(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

std::optional<double> ParseNumber(std::string_view token) {
  std::string text(token);
  if (text.find('.') == std::string::npos) {
    if (const auto comma = text.find(','); comma != std::string::npos) {
      if (text.find(',', comma + 1) != std::string::npos) return std::nullopt;
      text[comma] = '.';
    }
  }
  if (!text.empty() && text.front() == '+') text.erase(0, 1);
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

bool IsBlankOrComment(std::string_view line) {
  const auto first = line.find_first_not_of(" \t");
  return first == std::string_view::npos || line[first] == '#';
}

std::string ToLower(std::string_view text) {
  std::string lower(text);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower;
}

std::string LowerExtension(const std::filesystem::path& path) {
  return ToLower(path.extension().string());
}

std::vector<NumberLine> ReadNumberLines(const std::filesystem::path& path) {
  std::vector<NumberLine> lines;
  int number = 0;
  for (const std::string& line : SplitLines(ReadTextFile(path))) {
    ++number;
    if (IsBlankOrComment(line)) continue;
    NumberLine parsed{number, {}};
    for (std::string_view token : SplitWhitespace(line)) {
      const auto value = ParseNumber(token);
      if (!value) throw Error(path, fmt::format("line {}: '{}' is not a number", number, token));
      parsed.numbers.push_back(*value);
    }
    lines.push_back(std::move(parsed));
  }
  return lines;
}

}  // namespace photomat
