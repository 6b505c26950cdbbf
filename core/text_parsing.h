#pragma once

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

// True for lines that carry nothing: empty, whitespace only, or a '#' comment.
bool IsBlankOrComment(std::string_view line);

}  // namespace photomat
