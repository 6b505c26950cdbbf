#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "calibrate/lights/mirror_sphere.h"

namespace photomat {

// The Ceres parts of the mirror-sphere calibration (mirror_sphere.h, steps 1 and 4), built with
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

// What one sphere shows: its outline's edge points and its highlight in each image (continuous
// pixel coordinates).
struct MirrorSphereObservations {
  std::vector<Eigen::Vector2d> edge_points;
  std::vector<Eigen::Vector2d> highlights;  // one per image
};

// The unknowns of the joint problem (mirror_sphere.h, step 4), orthographic camera: every
// sphere's circle and one light per image, a unit direction (photomat frame) for distant lights
// or the lamp's position (sample frame of near_light.h, pixel units) for near ones.
struct MirrorSphereEstimate {
  std::vector<SphereCircle> spheres;
  std::vector<Eigen::Vector3d> lights;
};

struct MirrorSphereRefinement {
  MirrorSphereEstimate estimate;  // refined; the start when not usable
  bool usable = false;            // converged, finite, every radius positive
  std::string status;             // "converged" or why the solve is not usable
  int iterations = 0;
  std::vector<double> light_sigma_degrees;  // expected RMS angular error per light (NaN: unknown)
  double highlight_sigma_pixels = 0.0;
  bool highlight_sigma_measured = false;
};

// Step 4: the joint refinement of `start` from every sphere's observations (same image count for
// each sphere), in two passes: the first weighs the highlights with the outline's noise, the
// second with the highlight noise the first pass measured (when two or more spheres give the
// highlights redundancy). `max_iterations` bounds each pass.
MirrorSphereRefinement RefineMirrorSpheres(const std::vector<MirrorSphereObservations>& spheres,
                                           LightModel model, const MirrorSphereEstimate& start,
                                           int width, int height, int max_iterations);

// Step 4, perspective camera, one sphere: the sphere's 3-D centre (camera frame, OpenCV axes, units
// of its radius) from the viewing rays of its edge points (residuals in pixels at `focal_length`),
// jointly with one unit light per image (camera frame) whose highlight must project to
// highlights[i] (OpenCV pixel coordinates). `centre` and `lights` are refined in place.
// Returns "converged" or why the solve is not usable (then `centre` and `lights` keep the start).
std::string RefinePerspectiveSphere(const std::vector<Eigen::Vector3d>& edge_rays,
                                    double focal_length,
                                    const std::vector<Eigen::Vector2d>& highlights,
                                    const CameraIntrinsics& camera, int max_iterations,
                                    Eigen::Vector3d* centre, std::vector<Eigen::Vector3d>* lights);

}  // namespace photomat
