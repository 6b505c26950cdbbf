#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace photomat {

// Small helpers shared by the plain-text light-file readers (.lp, DiLiGenT).

// The lines of a text file, with a UTF-8 byte-order mark and CR line ends removed.
std::vector<std::string> SplitLines(std::string_view text);

// Whitespace-separated tokens (spaces and tabs).
std::vector<std::string_view> SplitWhitespace(std::string_view line);

// A finite decimal number. Accepts a decimal comma when the token has no point ("0,5"), as light
// files exported with some locales have; rejects anything else that is not wholly a number.
std::optional<double> ParseNumber(std::string_view token);

// `text` in ASCII lower case (names, extensions and keywords compare case-insensitively).
std::string ToLower(std::string_view text);
// The extension of `path` with its dot, in lower case (".png"; empty when there is none).
std::string LowerExtension(const std::filesystem::path& path);

// True for lines that carry nothing: empty, whitespace only, or a '#' comment.
bool IsBlankOrComment(std::string_view line);

// A line of numbers of a text file: its number (from 1) and its numbers.
struct NumberLine {
  int line = 0;
  std::vector<double> numbers;
};
// The lines of the file at `path` that are not blank or a comment, each split at whitespace into
// numbers (ParseNumber). Throws Error naming the file and the line for a token that is not a
// number ("line 3: 'x' is not a number") and for a file that cannot be read.
std::vector<NumberLine> ReadNumberLines(const std::filesystem::path& path);

}  // namespace photomat
