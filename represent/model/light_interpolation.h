#pragma once

#include <array>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "core/light_direction.h"

namespace photomat {

// Interpolates values known at some light directions (the nodes) to any other light, as a convex
// combination of at most four nodes: value(l) = sum_i weight_i(l) * value_i. Eigen-k relighting
// uses it to turn a light into coefficients (thesis eq. 4.4.16).
//
// Two schemes; Create() picks the first that applies (IMPLEMENTER CHOICE, README "Eigen-k"):
//  - kSlantRings, when the lights lie on rings of equal slant (the thesis's tilt x slant grid,
//    most domes): within a ring, linear in tilt between the two neighbouring nodes with
//    wrap-around (330 -> 360 = 0); between rings, linear in slant. On a complete grid this is
//    exactly the thesis's bilinear interpolation; with a node missing (leave-one-out) it uses the
//    neighbouring nodes that remain. Slants outside the rings' range clamp to the nearest ring.
//    Applies when every light is within 0.5 degree of the slant of a ring of at least 3 lights,
//    or is the only light of its ring and overhead (slant < 0.5 degree, where tilt is undefined).
//  - kTriangulation, for irregular sets (DiLiGenT's LED grid, hand-held lamps): barycentric
//    weights in the Delaunay triangulation of the lights in the azimuthal-equidistant projection
//    (slant * (cos tilt, sin tilt)), which keeps slant and tilt distances undistorted near the
//    pole; a light outside the triangulated area takes the nearest point on its boundary.
//    Needs 3 lights not all on one line.
// Both reproduce node values exactly at the nodes.
class LightInterpolator {
 public:
  enum class Scheme { kSlantRings, kTriangulation };

  // Throws Error when no scheme applies (fewer than 3 lights, or all on one line and not rings).
  explicit LightInterpolator(std::vector<LightDirection> nodes,
                             std::optional<Scheme> scheme = std::nullopt);

  // A ring of the kSlantRings scheme.
  struct Ring {
    double slant;                                 // degrees
    std::vector<std::pair<double, int>> by_tilt;  // (tilt degrees, node), sorted
  };
  // Rings within this slant of the camera axis hold one overhead light and no tilt order.
  static constexpr double kPoleSlantDegrees = 0.5;
  // The triangulation works on slant * (cos tilt, sin tilt) in radians times this scale.
  static constexpr double kProjectionScale = 1000.0;

  Scheme scheme() const { return scheme_; }
  const std::vector<LightDirection>& nodes() const { return nodes_; }

  // (node index, weight) pairs with positive weights summing to 1.
  std::vector<std::pair<int, double>> Weights(const LightDirection& light) const;

  // The structure Weights() evaluates, for code that re-implements it elsewhere (the web viewer's
  // JavaScript, relight/viewer_export.h). kSlantRings: the rings by increasing slant.
  // kTriangulation: the nodes' projected coordinates, the triangles and the hull edges.
  const std::vector<Ring>& rings() const { return rings_; }
  const std::vector<std::array<double, 2>>& projected() const { return projected_; }
  const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }
  const std::vector<std::array<int, 2>>& boundary() const { return boundary_; }

 private:
  bool BuildRings();
  void BuildTriangulation();
  void AddRingWeights(const Ring& ring, double tilt, double scale,
                      std::vector<std::pair<int, double>>& weights) const;
  std::vector<std::pair<int, double>> RingWeights(const LightDirection& light) const;
  std::vector<std::pair<int, double>> TriangulationWeights(const LightDirection& light) const;

  std::vector<LightDirection> nodes_;
  Scheme scheme_ = Scheme::kSlantRings;
  std::vector<Ring> rings_;                       // by increasing slant
  std::vector<std::array<double, 2>> projected_;  // triangulation coordinates of the nodes
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::array<int, 2>> boundary_;  // hull edges
};

std::string_view ToString(LightInterpolator::Scheme scheme);

}  // namespace photomat
