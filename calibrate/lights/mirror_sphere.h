#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/light_direction.h"
#include "core/progress.h"

namespace photomat {

// Light directions from a mirror (chrome) sphere photographed under each light.
//
// Image coordinates here are continuous pixel coordinates: x to the right, y down, the centre of
// pixel (column c, row r) at (c + 0.5, r + 0.5). Light directions are in photomat's frame (x right,
// y up, z toward the camera).
//
// Pipeline (CalibrateLightsFromMirrorSphere):
//   1. the sphere's outline: from a given mask (sub-pixel edge points where an anti-aliased or
//      binary mask crosses one half) or, without a mask, by OpenCV's Hough circle detection on the
//      median of every pixel over the images, refined with sub-pixel edge points along
//      radial profiles;
//   2. per image, the specular highlight: the brightest smoothed pixel inside the sphere, its blob
//      (connected pixels above half of the peak over the sphere's median) and the blob's
//      intensity-weighted centroid, with a clear error for a highlight that is too weak, a large
//      saturated blob (its centre is not measurable), or one at the sphere's rim;
//   3. Ceres refines the sphere (centre and radius, or its 3-D centre for a perspective camera)
//      from the edge points (Huber loss) jointly with one unit light direction per image whose
//      predicted highlight must land on the measured one. In this single-sphere problem each
//      direction is free, so the highlight residuals vanish at the optimum and the sphere is set
//      by its outline; the lights follow the refined sphere in one consistent solve
//      (mirror_sphere_refinement.h; a build without Ceres keeps the unrefined estimate, and the
//      outlines of steps 1 and 3 are Kasa's algebraic circle fits);
//   4. the direction is the reflection of the view vector about the sphere's normal at the
//      highlight: orthographic camera by default (view vector +z), or perspective with known
//      intrinsics (the view ray through the highlight pixel).

struct SphereCircle {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();  // continuous pixel coordinates
  double radius = 0.0;                               // pixels
};

// Pinhole intrinsics in OpenCV's convention (pixel centres at integer coordinates; DiLiGenT's
// K.txt, OpenCV's calibrateCamera): u = fx X / Z + cx, v = fy Y / Z + cy.
struct CameraIntrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
};
// Reads a 3 x 3 matrix "fx 0 cx / 0 fy cy / 0 0 1" (whitespace separated, 9 numbers).
CameraIntrinsics ReadCameraIntrinsics(const std::filesystem::path& path);

// The sphere outline from a mask image read as linear coverage (any channel; values in [0, 1]):
// sub-pixel edge points where the coverage crosses 0.5 along rows and columns, fitted by a circle
// (algebraic start, Ceres geometric refinement with a Huber loss; the algebraic fit alone in a
// build without Ceres). Throws Error naming `source` when the mask holds no circle-like region.
SphereCircle FitSphereToMask(const Image& mask, const std::filesystem::path& source = {});

// Sub-pixel edge points of the mask (where coverage crosses 0.5), for the joint refinement.
std::vector<Eigen::Vector2d> MaskEdgePoints(const Image& mask);

// Finds the sphere in the images without a mask: Hough circles (OpenCV) on the per-pixel median
// over all images (the sphere's body and outline without the moving highlights), refined by
// sub-pixel gradient maxima along radial profiles. `edge_points` receives those points. Throws
// Error naming `source` when no circle is found.
SphereCircle DetectSphere(const std::vector<Image>& images, const std::filesystem::path& source,
                          std::vector<Eigen::Vector2d>* edge_points = nullptr);

struct HighlightOptions {
  // The peak must exceed this (absolute, linear full scale = 1) ...
  double minimum_peak = 0.02;
  // ... and this multiple of the sphere's median value.
  double minimum_contrast = 4.0;
  // A blob with clipped pixels is rejected when its equivalent radius exceeds this fraction of
  // the sphere's radius: the centre of a large flat plateau is not the mirror point.
  double maximum_saturated_radius = 0.06;
  // A value at or above this (linear, full scale 1) is clipped.
  double saturation_level = 0.999;
  // The highlight must lie within this fraction of the radius from the centre (near the rim the
  // normal changes too fast for the direction to be reliable).
  double maximum_radius_fraction = 0.97;
};

struct Highlight {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();  // sub-pixel, continuous coordinates
  double peak = 0.0;
  int blob_pixels = 0;
  int saturated_pixels = 0;
};

// The specular highlight of one image of the sphere. Throws Error naming `image_name` and the
// fault (too weak, saturated blob, at the rim).
Highlight LocateHighlight(const Image& image, const SphereCircle& sphere,
                          const HighlightOptions& options, const std::string& image_name);

// The light direction whose mirror reflection lands at `highlight` (orthographic camera).
LightDirection LightFromHighlight(const SphereCircle& sphere, const Eigen::Vector2d& highlight);
// The same for a perspective camera: the sphere's 3-D centre (camera frame, units of its radius)
// follows from the outline and the intrinsics.
LightDirection LightFromHighlight(const SphereCircle& sphere, const Eigen::Vector2d& highlight,
                                  const CameraIntrinsics& camera);
// Inverse of the orthographic LightFromHighlight: where the highlight of `light` appears.
Eigen::Vector2d HighlightFromLight(const SphereCircle& sphere, const LightDirection& light);

struct MirrorSphereOptions {
  HighlightOptions highlight;
  std::optional<CameraIntrinsics> camera;  // unset: orthographic
  // The Ceres joint refinement (step 3). In a build without Ceres, true is an Error
  // (MirrorSphereRefinementAvailable() in mirror_sphere_refinement.h).
  bool refine = true;
  Progress* progress = nullptr;
};

struct MirrorSphereCalibration {
  SphereCircle sphere;   // as refined
  SphereCircle initial;  // before refinement
  std::vector<Highlight> highlights;
  std::vector<LightDirection> lights;
  double edge_rms_pixels = 0.0;  // RMS distance of the edge points from the refined outline
  int edge_points = 0;
  bool perspective = false;
};

// The whole pipeline. `mask` (coverage in [0, 1]) selects the sphere when given; otherwise it is
// detected. `names` name the images in messages. Every image's highlight is located; if any
// fails, one Error lists every failing image with its fault.
MirrorSphereCalibration CalibrateLightsFromMirrorSphere(const std::vector<Image>& images,
                                                        const std::vector<std::string>& names,
                                                        const std::optional<Image>& mask,
                                                        const MirrorSphereOptions& options,
                                                        const std::filesystem::path& source = {});

}  // namespace photomat
