#pragma once

#include <string>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// The lights of a capture, in the order they are taken. Light n of the plan (1-based) is what a
// light controller is asked to switch on and what image n - 1 of the set is taken under.
struct LightPlan {
  std::vector<LightDirection> lights;
  std::string source;  // "thesis", a file name, or "list"
};

// A plan from its command-line form:
//   "thesis"                       the thesis grid (12 tilts x slants 30, 45, 60; 36 lights)
//   "SLANT,TILT;SLANT,TILT;..."    a custom list in degrees
//   a file or folder               any light file photomat reads: a dome's .lp file, a
//                                  manifest.json, DiLiGenT's light_directions.txt
// Throws Error naming the file or the faulty list entry; lights below the sample plane are
// refused.
LightPlan ReadLightPlan(const std::string& spec);

// Whether two plans have the same lights in the same order (within 1e-6 degree).
bool SameLights(const std::vector<LightDirection>& a, const std::vector<LightDirection>& b);

}  // namespace photomat
