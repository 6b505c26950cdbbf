#include "represent/model/light_interpolation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace photomat {
namespace {

constexpr double kRingToleranceDegrees = 0.5;
// cv::Subdiv2D works in float on an integer bounding rectangle: radians are scaled to this.
constexpr double kProjectionScale = LightInterpolator::kProjectionScale;

std::array<double, 2> Project(const LightDirection& light) {
  const double slant = light.SlantDegrees() * std::numbers::pi / 180.0;
  const double tilt = light.TiltDegrees() * std::numbers::pi / 180.0;
  return {slant * std::cos(tilt) * kProjectionScale, slant * std::sin(tilt) * kProjectionScale};
}

}  // namespace

std::string_view ToString(LightInterpolator::Scheme scheme) {
  return scheme == LightInterpolator::Scheme::kSlantRings ? "slant-rings" : "triangulation";
}

LightInterpolator::LightInterpolator(std::vector<LightDirection> nodes,
                                     std::optional<Scheme> scheme)
    : nodes_(std::move(nodes)) {
  if (nodes_.empty()) throw Error("no lights to interpolate between");
  const bool rings = (!scheme || *scheme == Scheme::kSlantRings) && BuildRings();
  if (rings) {
    scheme_ = Scheme::kSlantRings;
    return;
  }
  if (scheme == Scheme::kSlantRings) {
    throw Error("the lights do not lie on rings of equal slant (3 or more lights per ring)");
  }
  scheme_ = Scheme::kTriangulation;
  BuildTriangulation();
}

bool LightInterpolator::BuildRings() {
  std::vector<int> order(nodes_.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return nodes_[a].SlantDegrees() < nodes_[b].SlantDegrees(); });
  rings_.clear();
  for (int node : order) {
    const double slant = nodes_[node].SlantDegrees();
    if (rings_.empty() || slant - rings_.back().slant > kRingToleranceDegrees) {
      rings_.push_back({slant, {}});
    }
    rings_.back().by_tilt.emplace_back(nodes_[node].TiltDegrees(), node);
  }
  for (Ring& ring : rings_) {
    double sum = 0.0;
    for (const auto& [tilt, node] : ring.by_tilt) sum += nodes_[node].SlantDegrees();
    ring.slant = sum / ring.by_tilt.size();
    std::sort(ring.by_tilt.begin(), ring.by_tilt.end());
    const bool pole = ring.slant < LightInterpolator::kPoleSlantDegrees;
    if (!pole && ring.by_tilt.size() < 3) return false;
    for (std::size_t i = 1; !pole && i < ring.by_tilt.size(); ++i) {
      if (ring.by_tilt[i].first - ring.by_tilt[i - 1].first < 1e-6) return false;
    }
  }
  return true;
}

void LightInterpolator::BuildTriangulation() {
  for (const LightDirection& node : nodes_) projected_.push_back(Project(node));
  const int bound = static_cast<int>(std::ceil(std::numbers::pi * kProjectionScale)) + 10;
  cv::Subdiv2D subdivision(cv::Rect(-bound, -bound, 2 * bound, 2 * bound));
  for (const auto& p : projected_) {
    subdivision.insert(cv::Point2f(static_cast<float>(p[0]), static_cast<float>(p[1])));
  }
  std::vector<cv::Vec6f> triangles;
  subdivision.getTriangleList(triangles);
  const auto node_at = [&](float x, float y) {
    int best = 0;
    double best_distance = INFINITY;
    for (std::size_t i = 0; i < projected_.size(); ++i) {
      const double d = std::hypot(projected_[i][0] - x, projected_[i][1] - y);
      if (d < best_distance) best_distance = d, best = static_cast<int>(i);
    }
    return best;
  };
  std::map<std::pair<int, int>, int> edge_uses;
  for (const cv::Vec6f& t : triangles) {
    const std::array<int, 3> tri = {node_at(t[0], t[1]), node_at(t[2], t[3]), node_at(t[4], t[5])};
    const auto& a = projected_[tri[0]];
    const auto& b = projected_[tri[1]];
    const auto& c = projected_[tri[2]];
    const double area = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
    if (std::abs(area) < 1e-9) continue;
    triangles_.push_back(tri);
    for (int e = 0; e < 3; ++e) {
      const int u = tri[e], v = tri[(e + 1) % 3];
      ++edge_uses[{std::min(u, v), std::max(u, v)}];
    }
  }
  if (triangles_.empty()) {
    throw Error(fmt::format(
        "cannot interpolate between {} light(s): need 3 or more lights not all on one line",
        nodes_.size()));
  }
  for (const auto& [edge, uses] : edge_uses) {
    if (uses == 1) boundary_.push_back({edge.first, edge.second});
  }
}

std::vector<std::pair<int, double>> LightInterpolator::Weights(const LightDirection& light) const {
  return scheme_ == Scheme::kSlantRings ? RingWeights(light) : TriangulationWeights(light);
}

void LightInterpolator::AddRingWeights(const Ring& ring, double tilt, double scale,
                                       std::vector<std::pair<int, double>>& weights) const {
  const auto& nodes = ring.by_tilt;
  if (ring.slant < LightInterpolator::kPoleSlantDegrees) {
    for (const auto& [node_tilt, node] : nodes) weights.emplace_back(node, scale / nodes.size());
    return;
  }
  const auto upper_it = std::upper_bound(nodes.begin(), nodes.end(),
                                         std::make_pair(tilt, std::numeric_limits<int>::max()));
  const std::size_t upper = upper_it == nodes.end() ? 0 : upper_it - nodes.begin();
  const std::size_t lower =
      upper_it == nodes.begin() ? nodes.size() - 1 : (upper_it - nodes.begin()) - 1;
  double low_tilt = nodes[lower].first, high_tilt = nodes[upper].first;
  if (low_tilt > tilt) low_tilt -= 360.0;     // wrapped below 0
  if (high_tilt <= tilt) high_tilt += 360.0;  // wrapped past 360
  const double f = (tilt - low_tilt) / (high_tilt - low_tilt);
  weights.emplace_back(nodes[lower].second, scale * (1.0 - f));
  weights.emplace_back(nodes[upper].second, scale * f);
}

std::vector<std::pair<int, double>> LightInterpolator::RingWeights(
    const LightDirection& light) const {
  const double slant = light.SlantDegrees(), tilt = light.TiltDegrees();
  std::vector<std::pair<int, double>> weights;
  if (slant <= rings_.front().slant) {
    AddRingWeights(rings_.front(), tilt, 1.0, weights);
  } else if (slant >= rings_.back().slant) {
    AddRingWeights(rings_.back(), tilt, 1.0, weights);
  } else {
    std::size_t upper = 1;
    while (rings_[upper].slant < slant) ++upper;
    const Ring& below = rings_[upper - 1];
    const Ring& above = rings_[upper];
    const double t = (slant - below.slant) / (above.slant - below.slant);
    AddRingWeights(below, tilt, 1.0 - t, weights);
    AddRingWeights(above, tilt, t, weights);
  }
  // Drop rounding-level weights (a node's own slant averaged into its ring differs in the last
  // bits), so that a node is reproduced from itself alone.
  std::erase_if(weights, [](const auto& w) { return w.second <= 1e-12; });
  double total = 0.0;
  for (const auto& w : weights) total += w.second;
  for (auto& w : weights) w.second /= total;
  return weights;
}

std::vector<std::pair<int, double>> LightInterpolator::TriangulationWeights(
    const LightDirection& light) const {
  const auto q = Project(light);
  for (const auto& tri : triangles_) {
    const auto& a = projected_[tri[0]];
    const auto& b = projected_[tri[1]];
    const auto& c = projected_[tri[2]];
    const double det = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
    const double wa = ((b[1] - c[1]) * (q[0] - c[0]) + (c[0] - b[0]) * (q[1] - c[1])) / det;
    const double wb = ((c[1] - a[1]) * (q[0] - c[0]) + (a[0] - c[0]) * (q[1] - c[1])) / det;
    const double wc = 1.0 - wa - wb;
    constexpr double kInside = -1e-9;
    if (wa >= kInside && wb >= kInside && wc >= kInside) {
      std::vector<std::pair<int, double>> weights;
      const double total = std::max(wa, 0.0) + std::max(wb, 0.0) + std::max(wc, 0.0);
      for (auto [node, w] : {std::pair{tri[0], wa}, std::pair{tri[1], wb}, std::pair{tri[2], wc}}) {
        if (w > 0.0) weights.emplace_back(node, w / total);
      }
      return weights;
    }
  }
  // Outside the triangulated area: the nearest point of its boundary.
  double best_distance = INFINITY;
  std::vector<std::pair<int, double>> best;
  for (const auto& [u, v] : boundary_) {
    const auto& a = projected_[u];
    const auto& b = projected_[v];
    const double dx = b[0] - a[0], dy = b[1] - a[1];
    const double t =
        std::clamp(((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / (dx * dx + dy * dy), 0.0, 1.0);
    const double distance = std::hypot(a[0] + t * dx - q[0], a[1] + t * dy - q[1]);
    if (distance < best_distance) {
      best_distance = distance;
      best.clear();
      if (t < 1.0) best.emplace_back(u, 1.0 - t);
      if (t > 0.0) best.emplace_back(v, t);
    }
  }
  return best;
}

}  // namespace photomat
