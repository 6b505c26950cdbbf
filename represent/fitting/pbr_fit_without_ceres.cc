// The pbr fit in a build without Ceres (PHOTOMAT_WITH_CERES=OFF): asking for it is an Error that
// says why it is missing.
#include <string>

#include "core/error.h"
#include "represent/fitting/pbr_fit.h"

namespace photomat {

Representation FitPbr(const Observations&, const std::vector<LightDirection>&, const NearLighting*,
                      std::span<const int>, const Eigen::Matrix3Xf&, const Eigen::MatrixXf&,
                      std::span<const Mask>, const PbrFitOptions&, nlohmann::json,
                      const std::filesystem::path& source, Progress*) {
  // PHOTOMAT_WITHOUT_CERES: "the Ceres ... (PHOTOMAT_WITH_CERES=OFF: why)", from CMake.
  throw Error(source, std::string("pbr needs Ceres: this photomat was built without ") +
                          PHOTOMAT_WITHOUT_CERES);
}

}  // namespace photomat
