#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace photomat {

// The low-order part of an RBF interpolant (represent/model/light_profile_basis.h): the terms it
// reproduces exactly, the Gaussians interpolating what they leave.
enum class RbfTail {
  kAffine,     // 1, lx, ly, lz
  kQuadratic,  // 1, lx, ly, lz, lx^2, ly^2, lx ly: PTM's terms and lz, a base under the RBF
};

// How the light-profile fits score their candidate parameters on the capture's own lights
// (represent/fitting/light_profile_fit.h).
enum class LeaveOut {
  kOne,    // each light left out alone
  kBlock,  // every 8th light left out at once (8 folds), as a held-out test leaves lights out
  kEdge,   // each light on the boundary of the lights' hull in (lx, ly) left out alone:
           // extrapolation, as predicting lights beyond the captured ones
  kSide,   // each side of that hull (its lights on one border row or column) left out at once:
           // extrapolation one grid step beyond the lights, as a held-out edge row
};

// Whether every fold of `scheme` leaves out one light (the closed-form leave-one-out weights).
inline bool OneLightFolds(LeaveOut scheme) {
  return scheme == LeaveOut::kOne || scheme == LeaveOut::kEdge;
}

// Options of the light-profile methods, `rbf` and `bilinear`
// (represent/model/light_profile_basis.h, README "RBF and bilinear"): not part of the name.
struct LightProfileOptions {
  // Gaussian kernel width (degrees) and regularisation of the RBF (the bilinear grid's resampling
  // uses neither); unset: chosen by leave-one-out on the capture.
  std::optional<double> rbf_width_degrees;
  std::optional<double> rbf_regularisation;
  // PCA planes per output channel (capped at the rank available); 0: no PCA, every captured light
  // (rbf) or grid node (bilinear) is a plane; kChoosePlanes: the count of best leave-one-out score
  // on the capture, 1 to kMaxChosenPlanes (represent/fitting/light_profile_fit.h; not the default:
  // on DiLiGenT ball it chose 16 planes where 9 predict held-out lights 0.9 dB better).
  static constexpr int kDefaultPlanes = 9;
  static constexpr int kChoosePlanes = -1;
  static constexpr int kMaxChosenPlanes = 16;
  int planes = kDefaultPlanes;
  // Weight of the bilinear grid's curvature term (light_profile_fit.h); unset: chosen by
  // leave-one-out on the capture. 0 reproduces the captured lights as closely as the grid can.
  std::optional<double> bilinear_smoothness;
  // Nodes per side of the bilinear light grid.
  static constexpr int kDefaultGridSize = 24;
  int grid_size = kDefaultGridSize;
  // The RBF's tail (a fixed option: on DiLiGenT the quadratic one, chosen by leave-one-out when
  // searched, predicted held-out lights worse on cat and ball; README "RBF and bilinear").
  RbfTail rbf_tail = RbfTail::kAffine;
  // The score every unset parameter is chosen by.
  LeaveOut leave_out = LeaveOut::kOne;

  bool operator==(const LightProfileOptions&) const = default;
};

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
    kRbf,         // "rbf": Gaussian RBF interpolation of each pixel's light profile, PCA planes
    kBilinear,    // "bilinear": the light profile resampled on an (lx, ly) grid, PCA planes
    kNeural,      // "neural": a learned per-pixel encoder and shared decoder (NeuralRTI); trained
                  // by represent/neural (libtorch) in the photomat-neural program only
  };
  Kind kind = Kind::kGradient;
  int eigen_k = 0;                   // for kEigen
  int hsh_terms = 0;                 // for kHsh: 4, 9 or 16
  LightProfileOptions profile = {};  // for kRbf and kBilinear

  std::string Name() const;
  // Fewest images a fit needs.
  int MinimumImages() const;
  // Throws Error naming the valid methods.
  static Method Parse(std::string_view name);

  bool operator==(const Method&) const = default;
};

// Why the in-memory, robust and streamed fits refuse `neural`: its training links libtorch, which
// only the photomat-neural program loads (`photomat fit --method neural`, represent/neural).
std::string NeuralIsTrainedApart();

// The maps of `method`'s stack fitted to `images` images of `channels` channels (pbr: an upper
// bound; neural: its default 9 coefficients): what memory and disk estimates count per pixel.
int StackMapCount(const Method& method, int images, int channels);

// "all" (AllMethods) or a comma-separated list of names.
std::vector<Method> ParseMethodList(std::string_view list);
// 3i, gradient, ptm, ptm-lrgb, eigen3, eigen6: the thesis's five and PTM's LRGB form (not pbr, a
// nonlinear fit that needs Ceres and takes far longer).
std::vector<Method> AllMethods();

}  // namespace photomat
