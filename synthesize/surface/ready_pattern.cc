#include "synthesize/surface/ready_pattern.h"

#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <pugixml.hpp>
#include <sstream>
#include <string>

#include "core/error.h"

namespace photomat {
namespace {

double ParseNumber(const std::filesystem::path& path, const std::string& name, std::string text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  if (first == std::string::npos) throw Error(path, fmt::format("parameter {} is empty", name));
  text = text.substr(first, last - first + 1);
  double value = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc() || end != text.data() + text.size() || !std::isfinite(value)) {
    throw Error(path, fmt::format("parameter {} is not a number: \"{}\"", name, text));
  }
  return value;
}

}  // namespace

ReadyGrayScottPattern ReadReadyGrayScott(const std::filesystem::path& path) {
  if (!std::filesystem::exists(path)) throw Error(path, "no such file");
  pugi::xml_document document;
  const pugi::xml_parse_result parsed = document.load_file(path.c_str());
  if (!parsed) {
    throw Error(path, fmt::format("not XML: {} at byte {}", parsed.description(), parsed.offset));
  }
  const pugi::xml_node vtk = document.child("VTKFile");
  const pugi::xml_node rd = vtk.child("RD");
  const pugi::xml_node rule = rd.child("rule");
  if (!vtk || !rd || !rule) throw Error(path, "not a Ready pattern file (no VTKFile/RD/rule)");
  const std::string rule_name = rule.attribute("name").as_string();
  if (rule_name != "Gray-Scott") {
    throw Error(path, fmt::format("the rule is \"{}\", not Gray-Scott", rule_name));
  }
  auto parameter = [&](const char* name) {
    const pugi::xml_node node = rule.find_child_by_attribute("param", "name", name);
    if (!node) throw Error(path, fmt::format("the rule has no parameter {}", name));
    return ParseNumber(path, name, node.child_value());
  };
  ReadyGrayScottPattern pattern;
  pattern.time_step = parameter("timestep");
  pattern.dx = parameter("dx");
  pattern.parameters.d_a = parameter("D_a");
  pattern.parameters.d_b = parameter("D_b");
  pattern.parameters.k = parameter("K");
  pattern.parameters.f = parameter("F");
  pattern.wrap = rule.attribute("wrap").as_int(0) == 1;

  // The seed: the first overlay restricted to a rectangle (Pearson's central square).
  for (const pugi::xml_node overlay : rd.child("initial_pattern_generator").children("overlay")) {
    const pugi::xml_node rectangle = overlay.child("rectangle");
    if (!rectangle) continue;
    const auto corners = rectangle.children("point3D");
    auto it = corners.begin();
    if (it == corners.end()) break;
    const double low = it->attribute("x").as_double();
    if (++it == corners.end()) break;
    const double high = it->attribute("x").as_double();
    if (high > low) pattern.parameters.seed_size = high - low;
    break;
  }

  std::istringstream extent(vtk.child("ImageData").attribute("WholeExtent").as_string());
  int x0 = 0, x1 = -1, y0 = 0, y1 = -1;
  if (!(extent >> x0 >> x1 >> y0 >> y1) || x1 < x0 || y1 < y0) {
    throw Error(path, "ImageData has no valid WholeExtent");
  }
  pattern.width = x1 - x0 + 1;
  pattern.height = y1 - y0 + 1;
  if (!(pattern.dx > 0.0) || !(pattern.time_step > 0.0)) {
    throw Error(path, "dx and timestep must be positive");
  }
  return pattern;
}

}  // namespace photomat
