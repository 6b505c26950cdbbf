#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "calibrate/lights/mirror_sphere.h"

namespace photomat {

// The Ceres parts of the mirror-sphere calibration (mirror_sphere.h, steps 1 and 3), built with
// PHOTOMAT_WITH_CERES. A build without Ceres compiles mirror_sphere_without_ceres.cc instead:
// MirrorSphereRefinementAvailable() is false, the outline is Kasa's algebraic circle fit and each
// function here throws an Error saying that this build has no Ceres.

// Whether this build has the refinement (Ceres), and, when it has not, why: "this photomat was
// built without the Ceres mirror-sphere refinement (PHOTOMAT_WITH_CERES=OFF: Ceres not found)"
// (empty with Ceres).
bool MirrorSphereRefinementAvailable();
std::string MirrorSphereRefinementAbsence();

// The geometric circle fit of outline edge points from `start`, with a Huber loss against stray
// points.
SphereCircle RefineCircle(const SphereCircle& start, const std::vector<Eigen::Vector2d>& points);

// Step 3, orthographic camera: the circle from its edge points (Huber loss) jointly with one unit
// light per image (photomat frame) whose mirror highlight must land on highlights[i] (continuous
// pixel coordinates). `circle` and `lights` hold the unrefined estimate and receive the refined.
void RefineOrthographicSphere(const std::vector<Eigen::Vector2d>& edge_points,
                              const std::vector<Eigen::Vector2d>& highlights, SphereCircle* circle,
                              std::vector<Eigen::Vector3d>* lights);

// Step 3, perspective camera: the sphere's 3-D centre (camera frame, OpenCV axes, units of its
// radius) from the viewing rays of its edge points (residuals in pixels at `focal_length`),
// jointly with one unit light per image (camera frame) whose highlight must project to
// highlights[i] (OpenCV pixel coordinates). `centre` and `lights` are refined in place.
void RefinePerspectiveSphere(const std::vector<Eigen::Vector3d>& edge_rays, double focal_length,
                             const std::vector<Eigen::Vector2d>& highlights,
                             const CameraIntrinsics& camera, Eigen::Vector3d* centre,
                             std::vector<Eigen::Vector3d>* lights);

}  // namespace photomat
