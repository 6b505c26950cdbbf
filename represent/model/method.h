#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace photomat {

// A representation method by name, as the command line and the JSON outputs spell it.
struct Method {
  enum class Kind {
    kThreeImage,  // "3i": Shashua's three-image basis (thesis 4.4.2)
    kGradient,    // "gradient": least-squares photometric stereo, normal + albedo (4.4.3)
    kPtm,         // "ptm": polynomial texture map per colour channel (4.4.4)
    kPtmLrgb,     // "ptm-lrgb": one luminance polynomial times an RGB chroma (PTM files' LRGB)
    kEigen,       // "eigenK": the first K SVD basis images, "eigen3" and "eigen6" (4.4.5)
    kHsh,         // "hsh4", "hsh9", "hsh16": hemispherical harmonics per colour channel (.rti)
    kPbr,         // "pbr": diffuse + GGX microfacet maps per pixel (represent/model/shading.h)
  };
  Kind kind = Kind::kGradient;
  int eigen_k = 0;    // for kEigen
  int hsh_terms = 0;  // for kHsh: 4, 9 or 16

  std::string Name() const;
  // Fewest images a fit needs.
  int MinimumImages() const;
  // Throws Error naming the valid methods.
  static Method Parse(std::string_view name);

  bool operator==(const Method&) const = default;
};

// "all" (AllMethods) or a comma-separated list of names.
std::vector<Method> ParseMethodList(std::string_view list);
// 3i, gradient, ptm, ptm-lrgb, eigen3, eigen6: the thesis's five and PTM's LRGB form (not pbr, a
// nonlinear fit that needs Ceres and takes far longer).
std::vector<Method> AllMethods();

}  // namespace photomat
