#include "represent/model/method.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>

#include "core/error.h"

namespace photomat {

std::string Method::Name() const {
  switch (kind) {
    case Kind::kThreeImage:
      return "3i";
    case Kind::kGradient:
      return "gradient";
    case Kind::kPtm:
      return "ptm";
    case Kind::kPtmLrgb:
      return "ptm-lrgb";
    case Kind::kHsh:
      return fmt::format("hsh{}", hsh_terms);
    case Kind::kPbr:
      return "pbr";
    case Kind::kRbf:
      return "rbf";
    case Kind::kBilinear:
      return "bilinear";
    case Kind::kNeural:
      return "neural";
    case Kind::kEigen:
      break;
  }
  return fmt::format("eigen{}", eigen_k);
}

int Method::MinimumImages() const {
  switch (kind) {
    case Kind::kThreeImage:
    case Kind::kGradient:
      return 3;
    case Kind::kPtm:
    case Kind::kPtmLrgb:
      return 6;
    case Kind::kHsh:
      return hsh_terms;
    case Kind::kPbr:
      // Eight parameters per pixel (base colour 3, roughness, F0, normal 2) from 3 channels
      // per image; the robust start needs a few more than its 3.
      return 6;
    case Kind::kRbf:
    case Kind::kBilinear:
      // The affine tail of the interpolation and a leave-one-out choice need a few lights.
      return 4;
    case Kind::kNeural:
      // The encoder's input is the pixel's profile; below 6 lights PTM's 6 terms would already
      // interpolate them exactly.
      return 6;
    case Kind::kEigen:
      break;
  }
  return eigen_k;
}

Method Method::Parse(std::string_view name) {
  for (Kind kind : {Kind::kThreeImage, Kind::kGradient, Kind::kPtm, Kind::kPtmLrgb, Kind::kPbr,
                    Kind::kRbf, Kind::kBilinear, Kind::kNeural}) {
    if (name == Method{kind}.Name()) return {kind};
  }
  if (name.starts_with("eigen")) {
    const std::string_view digits = name.substr(5);
    int k = 0;
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), k);
    if (ec == std::errc() && end == digits.data() + digits.size() && k >= 1 && k <= 64) {
      return {Kind::kEigen, k};
    }
  }
  if (name == "hsh4" || name == "hsh9" || name == "hsh16") {
    Method hsh{Kind::kHsh};
    hsh.hsh_terms = name == "hsh4" ? 4 : name == "hsh9" ? 9 : 16;
    return hsh;
  }
  throw Error(fmt::format(
      "unknown method \"{}\": expected 3i, gradient, ptm, ptm-lrgb, eigenK (K = 1..64, e.g. "
      "eigen3, eigen6), hsh4, hsh9, hsh16, pbr, rbf, bilinear or neural, or all",
      name));
}

std::string NeuralIsTrainedApart() {
  return "neural is trained on its own, by `photomat fit --method neural` (the photomat-neural "
         "program, which links libtorch); fit the other methods in a separate run";
}

std::vector<Method> ParseMethodList(std::string_view list) {
  if (list == "all") return AllMethods();
  std::vector<Method> methods;
  while (!list.empty()) {
    const auto comma = list.find(',');
    const std::string_view name = list.substr(0, comma);
    if (!name.empty()) methods.push_back(Method::Parse(name));
    if (comma == std::string_view::npos) break;
    list.remove_prefix(comma + 1);
  }
  if (methods.empty()) throw Error("no method named");
  return methods;
}

std::vector<Method> AllMethods() {
  using K = Method::Kind;
  return {{K::kThreeImage}, {K::kGradient}, {K::kPtm},
          {K::kPtmLrgb},    {K::kEigen, 3}, {K::kEigen, 6}};
}

int StackMapCount(const Method& method, int images, int channels) {
  switch (method.kind) {
    case Method::Kind::kThreeImage:
      return 3 * channels;
    case Method::Kind::kGradient:
      return 3 + channels;
    case Method::Kind::kPtm:
      return 6 * channels;
    case Method::Kind::kPtmLrgb:
      return 6 + channels;
    case Method::Kind::kHsh:
      return method.hsh_terms * channels;
    case Method::Kind::kEigen:
      return method.eigen_k * channels;
    case Method::Kind::kRbf:
      return (method.profile.planes > 0 ? std::min(method.profile.planes, images) : images) *
             channels;  // kChoosePlanes: at most images, as no PCA
    case Method::Kind::kBilinear:
      return (method.profile.planes > 0 ? std::min(method.profile.planes, images)
                                        : method.profile.grid_size * method.profile.grid_size) *
             channels;
    case Method::Kind::kNeural:
      return 9;  // NeuralRTI's default coefficients (the decoder travels in the description)
    case Method::Kind::kPbr:
      break;
  }
  return 8 + 2 * channels;
}

}  // namespace photomat
