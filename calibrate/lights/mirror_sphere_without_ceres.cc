// The mirror-sphere refinement in a build without Ceres (PHOTOMAT_WITH_CERES=OFF): the calibration
// keeps its unrefined estimate (mirror_sphere_refinement.h); asking for the refinement is an
// Error that says why it is missing.
#include <string>

#include "calibrate/lights/mirror_sphere_refinement.h"
#include "core/error.h"

namespace photomat {
namespace {

// PHOTOMAT_WITHOUT_CERES: "the Ceres mirror-sphere refinement (PHOTOMAT_WITH_CERES=OFF: why)",
// from calibrate/lights/CMakeLists.txt.
[[noreturn]] void ThrowWithoutCeres() {
  throw Error(MirrorSphereRefinementAbsence() +
              ": calibrate the lights without it (the unrefined sphere: --no-refine)");
}

}  // namespace

bool MirrorSphereRefinementAvailable() { return false; }

std::string MirrorSphereRefinementAbsence() {
  return std::string("this photomat was built without ") + PHOTOMAT_WITHOUT_CERES;
}

SphereCircle RefineCircle(const SphereCircle&, const std::vector<Eigen::Vector2d>&) {
  ThrowWithoutCeres();
}

MirrorSphereRefinement RefineMirrorSpheres(const std::vector<MirrorSphereObservations>&, LightModel,
                                           const MirrorSphereEstimate&, int, int, int) {
  ThrowWithoutCeres();
}

std::string RefinePerspectiveSphere(const std::vector<Eigen::Vector3d>&, double,
                                    const std::vector<Eigen::Vector2d>&, const CameraIntrinsics&,
                                    int, Eigen::Vector3d*, std::vector<Eigen::Vector3d>*) {
  ThrowWithoutCeres();
}

}  // namespace photomat
