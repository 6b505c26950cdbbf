#pragma once

#include <string>

namespace photomat {

// Escapes &, <, >, " and ' so that `text` can stand in HTML or SVG (XML) text and in quoted
// attribute values. The reports (calibration, evaluation) write file names and titles through it.
std::string EscapeMarkup(const std::string& text);

}  // namespace photomat
