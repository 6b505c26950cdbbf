#include "capture/live/light_plan.h"

#include <fmt/format.h>

#include <filesystem>
#include <sstream>

#include "capture/io/load_photometric_set.h"
#include "core/error.h"

namespace photomat {
namespace {

LightDirection ParseEntry(const std::string& entry, int index) {
  std::string text = entry;
  for (char& c : text) {
    if (c == ',') c = ' ';
  }
  std::istringstream in(text);
  double slant = 0.0, tilt = 0.0;
  std::string extra;
  if (!(in >> slant >> tilt) || (in >> extra)) {
    throw Error(
        fmt::format("light list entry {} \"{}\": expected SLANT,TILT in degrees", index, entry));
  }
  if (slant < 0.0 || slant > 90.0) {
    throw Error(
        fmt::format("light list entry {} \"{}\": slant must be in [0, 90] degrees", index, entry));
  }
  return LightDirection::FromSlantTilt(slant, tilt);
}

}  // namespace

LightPlan ReadLightPlan(const std::string& spec) {
  if (spec == "thesis") return {ThesisLightGrid(), "thesis"};
  if (!std::filesystem::exists(spec) && spec.find(',') != std::string::npos) {
    LightPlan plan{{}, "list"};
    std::istringstream in(spec);
    std::string entry;
    while (std::getline(in, entry, ';')) {
      if (entry.find_first_not_of(" \t") == std::string::npos) continue;
      plan.lights.push_back(ParseEntry(entry, static_cast<int>(plan.lights.size()) + 1));
    }
    if (plan.lights.empty()) throw Error("empty light list");
    return plan;
  }
  if (!std::filesystem::exists(spec)) {
    throw Error(spec,
                "no such light plan: expected \"thesis\", a list \"SLANT,TILT;...\" or a "
                "light file (.lp, manifest.json, light_directions.txt)");
  }
  LightPlan plan{ReadLightDirections(spec), spec};
  for (std::size_t i = 0; i < plan.lights.size(); ++i) {
    if (plan.lights[i].z() < 0.0) {
      throw Error(spec, fmt::format("light {} is below the sample plane", i + 1));
    }
  }
  if (plan.lights.empty()) throw Error(spec, "no light in the plan");
  return plan;
}

bool SameLights(const std::vector<LightDirection>& a, const std::vector<LightDirection>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].AngleToDegrees(b[i]) > 1e-6) return false;
  }
  return true;
}

}  // namespace photomat
