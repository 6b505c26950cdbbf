#include "calibrate/lights/mirror_sphere.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <queue>

#include "calibrate/lights/mirror_sphere_refinement.h"
#include "core/enum_names.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

constexpr std::array<NamedValue<LightModel>, 2> kLightModelNames = {{
    {LightModel::kDistant, "distant"},
    {LightModel::kNear, "near"},
}};

constexpr double kPi = std::numbers::pi;
// Radial profiles sampled around a detected circle to refine it.
constexpr int kRadialProfiles = 360;
// Too few edge points cannot pin down a circle (three would, but not robustly).
constexpr int kMinimumEdgePoints = 12;
// A detected outline whose points lie further than this from the fitted circle (pixels, or
// fraction of the radius, whichever is larger) is not a sphere's outline.
constexpr double kMaximumDetectedRms = 1.0;
constexpr double kMaximumDetectedRelativeRms = 0.01;

// The mean of an image's channels at every pixel, as an OpenCV float matrix.
cv::Mat GreyMat(const Image& image) {
  cv::Mat grey = cv::Mat::zeros(image.height(), image.width(), CV_32F);
  for (int y = 0; y < image.height(); ++y) {
    auto* row = grey.ptr<float>(y);
    for (int c = 0; c < image.channels(); ++c) {
      const float* values = image.row(c, y).data();
      for (int x = 0; x < image.width(); ++x) row[x] += values[x];
    }
    for (int x = 0; x < image.width(); ++x) row[x] /= static_cast<float>(image.channels());
  }
  return grey;
}

// Kasa's algebraic circle fit: minimises sum (x^2 + y^2 + D x + E y + F)^2.
std::optional<SphereCircle> AlgebraicCircle(const std::vector<Eigen::Vector2d>& points) {
  if (points.size() < 3) return std::nullopt;
  Eigen::MatrixXd a(points.size(), 3);
  Eigen::VectorXd b(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    a.row(static_cast<Eigen::Index>(i)) << points[i].x(), points[i].y(), 1.0;
    b[static_cast<Eigen::Index>(i)] = -points[i].squaredNorm();
  }
  const Eigen::Vector3d def = a.colPivHouseholderQr().solve(b);
  SphereCircle circle;
  circle.centre = Eigen::Vector2d(-def[0] / 2, -def[1] / 2);
  const double r2 = circle.centre.squaredNorm() - def[2];
  if (!(r2 > 0.0) || !std::isfinite(r2)) return std::nullopt;
  circle.radius = std::sqrt(r2);
  return circle;
}

// OpenCV pixel coordinates (centres at integers) of a continuous coordinate.
Eigen::Vector2d ToOpenCvPixel(const Eigen::Vector2d& p) { return p - Eigen::Vector2d(0.5, 0.5); }

Eigen::Vector3d CameraRay(const CameraIntrinsics& k, const Eigen::Vector2d& continuous) {
  const Eigen::Vector2d p = ToOpenCvPixel(continuous);
  return Eigen::Vector3d((p.x() - k.cx) / k.fx, (p.y() - k.cy) / k.fy, 1.0).normalized();
}

double MeanFocal(const CameraIntrinsics& k) { return 0.5 * (k.fx + k.fy); }

// The sphere's 3-D centre (camera frame, radius 1) from its image outline.
Eigen::Vector3d SphereCentreFromCircle(const SphereCircle& sphere, const CameraIntrinsics& k) {
  const Eigen::Vector3d direction = CameraRay(k, sphere.centre);
  const double half_angle = std::atan(sphere.radius / MeanFocal(k));
  return direction / std::sin(half_angle);
}

// Photomat frame (y up, z toward the camera) <-> OpenCV camera frame (y down, z forward).
Eigen::Vector3d CameraToPhotomat(const Eigen::Vector3d& v) { return {v.x(), -v.y(), -v.z()}; }
Eigen::Vector3d PhotomatToCamera(const Eigen::Vector3d& v) { return {v.x(), -v.y(), -v.z()}; }

LightDirection PerspectiveLight(const Eigen::Vector3d& centre, const Eigen::Vector2d& highlight,
                                const CameraIntrinsics& camera) {
  const Eigen::Vector3d u = CameraRay(camera, highlight);
  const double uc = u.dot(centre);
  const double discriminant = std::max(0.0, uc * uc - centre.squaredNorm() + 1.0);
  const Eigen::Vector3d point = (uc - std::sqrt(discriminant)) * u;
  const Eigen::Vector3d normal = (point - centre).normalized();
  const Eigen::Vector3d view = -u;
  const Eigen::Vector3d light = 2.0 * normal.dot(view) * normal - view;
  return LightDirection::FromVector(CameraToPhotomat(light));
}

double Bilinear(const cv::Mat& grey, double x, double y) {
  // Continuous coordinates -> OpenCV pixel centres.
  const double u = std::clamp(x - 0.5, 0.0, grey.cols - 1.001);
  const double v = std::clamp(y - 0.5, 0.0, grey.rows - 1.001);
  const int u0 = static_cast<int>(u), v0 = static_cast<int>(v);
  const double fu = u - u0, fv = v - v0;
  const auto at = [&](int c, int r) { return static_cast<double>(grey.at<float>(r, c)); };
  return (1 - fv) * ((1 - fu) * at(u0, v0) + fu * at(u0 + 1, v0)) +
         fv * ((1 - fu) * at(u0, v0 + 1) + fu * at(u0 + 1, v0 + 1));
}

// Sub-pixel outline points along radial profiles: the steepest descent of brightness crossing a
// circle's neighbourhood (0.8 to 1.2 radii), refined by a parabola through the three samples
// around the maximum.
std::vector<Eigen::Vector2d> RadialEdgePoints(const cv::Mat& grey, const SphereCircle& circle) {
  std::vector<Eigen::Vector2d> points;
  constexpr double kStep = 0.25;
  for (int a = 0; a < kRadialProfiles; ++a) {
    const double angle = 2 * kPi * a / kRadialProfiles;
    const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
    const double start = 0.8 * circle.radius, end = 1.2 * circle.radius;
    std::vector<double> derivative;
    std::vector<double> radii;
    double previous = Bilinear(grey, circle.centre.x() + direction.x() * start,
                               circle.centre.y() + direction.y() * start);
    for (double r = start + kStep; r <= end; r += kStep) {
      const Eigen::Vector2d p = circle.centre + r * direction;
      if (p.x() < 1 || p.y() < 1 || p.x() > grey.cols - 1 || p.y() > grey.rows - 1) break;
      const double value = Bilinear(grey, p.x(), p.y());
      derivative.push_back(previous - value);  // brightness falls outward at the outline
      radii.push_back(r - kStep / 2);
      previous = value;
    }
    if (derivative.size() < 3) continue;
    const auto best = std::max_element(derivative.begin() + 1, derivative.end() - 1);
    if (*best <= 0.0) continue;
    const std::size_t i = static_cast<std::size_t>(best - derivative.begin());
    const double d0 = derivative[i - 1], d1 = derivative[i], d2 = derivative[i + 1];
    const double denominator = d0 - 2 * d1 + d2;
    const double offset = denominator < 0.0 ? 0.5 * (d0 - d2) / denominator : 0.0;
    points.push_back(circle.centre + (radii[i] + offset * kStep) * direction);
  }
  return points;
}

double EdgeRms(const SphereCircle& circle, const std::vector<Eigen::Vector2d>& points) {
  if (points.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& p : points) {
    const double d = (p - circle.centre).norm() - circle.radius;
    sum += d * d;
  }
  return std::sqrt(sum / static_cast<double>(points.size()));
}

// The circle through `points`: the geometric fit with a Huber loss from `start` when this build
// has the refinement (Ceres), Kasa's algebraic fit otherwise (the unrefined estimate).
SphereCircle FitCircle(const SphereCircle& start, const std::vector<Eigen::Vector2d>& points) {
  if (MirrorSphereRefinementAvailable()) return RefineCircle(start, points);
  return AlgebraicCircle(points).value_or(start);
}

// A sub-pixel point where the mask's coverage crosses one half between two neighbouring pixels,
// and which of the two is inside.
struct MaskEdge {
  Eigen::Vector2d point;
  int inside_x = 0, inside_y = 0;
};

std::vector<MaskEdge> MaskEdges(const Image& mask) {
  std::vector<MaskEdge> edges;
  const auto coverage = [&](int x, int y) { return static_cast<double>(mask.at(x, y, 0)); };
  // Between (x, y) and (x + dx, y + dy), if the coverage crosses one half.
  const auto add = [&](int x, int y, int dx, int dy) {
    const double v0 = coverage(x, y), v1 = coverage(x + dx, y + dy);
    if ((v0 - 0.5) * (v1 - 0.5) >= 0.0) return;
    const double t = (0.5 - v0) / (v1 - v0);
    const bool first_inside = v0 > 0.5;
    edges.push_back({Eigen::Vector2d(x + 0.5 + t * dx, y + 0.5 + t * dy), first_inside ? x : x + dx,
                     first_inside ? y : y + dy});
  };
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x + 1 < mask.width(); ++x) add(x, y, 1, 0);
  }
  for (int x = 0; x < mask.width(); ++x) {
    for (int y = 0; y + 1 < mask.height(); ++y) add(x, y, 0, 1);
  }
  return edges;
}

// The circle of a mask's outline points; throws Error naming `source` when they are too few or
// not a circle.
SphereCircle FitMaskOutline(const std::vector<Eigen::Vector2d>& points, const fs::path& source) {
  const auto start = AlgebraicCircle(points);
  if (static_cast<int>(points.size()) < kMinimumEdgePoints || !start) {
    throw Error(source, "sphere not found: the mask has no outline (is it empty or full?)");
  }
  const SphereCircle circle = FitCircle(*start, points);
  const double rms = EdgeRms(circle, points);
  if (!(circle.radius > 2.0) || rms > 0.05 * circle.radius) {
    throw Error(source, fmt::format("sphere not found: the mask's outline is not a circle (RMS "
                                    "distance {:.2f} px from the best circle of radius {:.1f} px)",
                                    rms, circle.radius));
  }
  return circle;
}

// The normalised mean of the directions that the spheres' highlights of one image give (one
// sphere: its direction): the unrefined distant light.
Eigen::Vector3d MeanDirection(const std::vector<MirrorSphereFit>& spheres, std::size_t image) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const MirrorSphereFit& sphere : spheres) {
    sum += LightFromHighlight(sphere.initial, sphere.highlights[image].position).vector();
  }
  return sum.normalized();
}

// The point nearest to every sphere's mirror ray of one image (least squares): the near lamp's
// start for the refinement. Rays that are (nearly) parallel meet far away; the lamp is then put
// far along their mean direction.
Eigen::Vector3d TriangulateLamp(const std::vector<MirrorSphereFit>& spheres, std::size_t image,
                                int width, int height) {
  Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
  Eigen::Vector3d right_side = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_point = Eigen::Vector3d::Zero();
  for (const MirrorSphereFit& sphere : spheres) {
    const Eigen::Vector2d& h = sphere.highlights[image].position;
    const Eigen::Vector3d point = MirrorPointInSampleFrame(sphere.initial, h, width, height);
    const Eigen::Vector3d d = LightFromHighlight(sphere.initial, h).vector();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - d * d.transpose();
    normal_matrix += across;
    right_side += across * point;
    mean_point += point / static_cast<double>(spheres.size());
  }
  const Eigen::Vector3d lamp = normal_matrix.ldlt().solve(right_side);
  if (lamp.allFinite() && lamp.z() > mean_point.z()) return lamp;
  return mean_point + 10.0 * std::max(width, height) * MeanDirection(spheres, image);
}

}  // namespace

CameraIntrinsics ReadCameraIntrinsics(const fs::path& path) {
  std::vector<double> values;
  for (const NumberLine& line : ReadNumberLines(path)) {
    values.insert(values.end(), line.numbers.begin(), line.numbers.end());
  }
  if (values.size() != 9) {
    throw Error(path,
                fmt::format("expected a 3 x 3 camera matrix (9 numbers), found {}", values.size()));
  }
  CameraIntrinsics k{values[0], values[4], values[2], values[5]};
  if (!(k.fx > 0.0 && k.fy > 0.0)) {
    throw Error(path, "the focal lengths (first and fifth numbers) must be positive");
  }
  return k;
}

std::vector<Eigen::Vector2d> MaskEdgePoints(const Image& mask) {
  std::vector<Eigen::Vector2d> points;
  for (const MaskEdge& edge : MaskEdges(mask)) points.push_back(edge.point);
  return points;
}

SphereCircle FitSphereToMask(const Image& mask, const fs::path& source) {
  return FitMaskOutline(MaskEdgePoints(mask), source);
}

std::vector<std::vector<Eigen::Vector2d>> MaskSphereOutlines(const Image& mask) {
  cv::Mat inside(mask.height(), mask.width(), CV_8U);
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x < mask.width(); ++x) inside.at<std::uint8_t>(y, x) = mask.at(x, y, 0) > 0.5f;
  }
  cv::Mat labels;
  const int regions = cv::connectedComponents(inside, labels, 8, CV_32S);
  std::vector<std::vector<Eigen::Vector2d>> outlines(static_cast<std::size_t>(regions));
  // Each edge point belongs to the region of the pixel of its pair that is inside.
  for (const MaskEdge& edge : MaskEdges(mask)) {
    const int label = labels.at<int>(edge.inside_y, edge.inside_x);
    outlines[static_cast<std::size_t>(label)].push_back(edge.point);
  }
  std::erase_if(outlines, [](const std::vector<Eigen::Vector2d>& points) {
    return static_cast<int>(points.size()) < kMinimumEdgePoints;
  });
  const auto mean_x = [](const std::vector<Eigen::Vector2d>& points) {
    double sum = 0.0;
    for (const auto& p : points) sum += p.x();
    return sum / static_cast<double>(points.size());
  };
  std::sort(outlines.begin(), outlines.end(),
            [&](const auto& a, const auto& b) { return mean_x(a) < mean_x(b); });
  return outlines;
}

SphereCircle DetectSphere(const std::vector<Image>& images, const fs::path& source,
                          std::vector<Eigen::Vector2d>* edge_points) {
  if (images.empty()) throw Error(source, "sphere not found: no images");
  // The per-pixel median over the images: the sphere's body and outline (the room it mirrors)
  // stay, the highlights, which move from image to image, go (their maximum would draw rings of
  // highlights that Hough takes for circles).
  std::vector<cv::Mat> greys;
  for (const Image& image : images) greys.push_back(GreyMat(image));
  cv::Mat body(greys.front().rows, greys.front().cols, CV_32F);
  tbb::parallel_for(0, body.rows, [&](int y) {
    std::vector<float> column(greys.size());
    for (int x = 0; x < body.cols; ++x) {
      for (std::size_t i = 0; i < greys.size(); ++i) column[i] = greys[i].at<float>(y, x);
      std::nth_element(column.begin(), column.begin() + column.size() / 2, column.end());
      body.at<float>(y, x) = column[column.size() / 2];
    }
  });
  // 8-bit for Hough: stretch so that the 99th percentile is white (a dim body would otherwise
  // use a few grey levels).
  std::vector<float> sorted(body.begin<float>(), body.end<float>());
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() * 99 / 100, sorted.end());
  const double white = std::max(1e-6f, sorted[sorted.size() * 99 / 100]);
  cv::Mat eight;
  body.convertTo(eight, CV_8U, 255.0 / white);
  cv::medianBlur(eight, eight, 5);
  const int smaller = std::min(eight.cols, eight.rows);
  std::vector<cv::Vec3f> circles;
  cv::HoughCircles(eight, circles, cv::HOUGH_GRADIENT, 1.0, smaller / 2.0, 100.0, 30.0,
                   smaller / 10, smaller / 2);
  if (circles.empty()) {
    throw Error(source, "sphere not found: no circle in the images (give the sphere's mask)");
  }
  // Hough's centre is in OpenCV pixel coordinates (centres at integers).
  SphereCircle start{Eigen::Vector2d(circles[0][0] + 0.5, circles[0][1] + 0.5), circles[0][2]};
  std::vector<Eigen::Vector2d> points = RadialEdgePoints(body, start);
  if (static_cast<int>(points.size()) < kMinimumEdgePoints) {
    throw Error(source, "sphere not found: its outline is too faint to measure");
  }
  SphereCircle circle = FitCircle(start, points);
  // Once more around the refined circle (the profiles are then centred on the outline).
  points = RadialEdgePoints(body, circle);
  if (static_cast<int>(points.size()) >= kMinimumEdgePoints) circle = FitCircle(circle, points);
  // A faint or cluttered outline gives a circle that is wrong without failing: refuse it.
  const double rms = EdgeRms(circle, points);
  if (static_cast<int>(points.size()) < kRadialProfiles / 2 ||
      rms > std::max(kMaximumDetectedRms, kMaximumDetectedRelativeRms * circle.radius)) {
    throw Error(source, fmt::format("sphere not found reliably: its outline is too faint or "
                                    "cluttered ({} of {} radial profiles, {:.2f} px RMS from the "
                                    "best circle); give the sphere's mask",
                                    points.size(), kRadialProfiles, rms));
  }
  if (edge_points) *edge_points = std::move(points);
  return circle;
}

std::string_view ToString(LightModel model) { return NameOf(model, kLightModelNames); }

LightModel ParseLightModel(std::string_view name) {
  return ValueNamed(name, kLightModelNames, "light model");
}

Eigen::Vector3d SphereCentreInSampleFrame(const SphereCircle& circle, int width, int height) {
  return {circle.centre.x() - width / 2.0, height / 2.0 - circle.centre.y(), circle.radius};
}

Eigen::Vector3d MirrorPointInSampleFrame(const SphereCircle& circle,
                                         const Eigen::Vector2d& highlight, int width, int height) {
  const Eigen::Vector2d d = highlight - circle.centre;
  const double above = std::sqrt(std::max(0.0, circle.radius * circle.radius - d.squaredNorm()));
  return SphereCentreInSampleFrame(circle, width, height) + Eigen::Vector3d(d.x(), -d.y(), above);
}

Highlight LocateHighlight(const Image& image, const SphereCircle& sphere,
                          const HighlightOptions& options, const std::string& image_name) {
  const cv::Mat grey = GreyMat(image);
  cv::Mat smooth;
  cv::GaussianBlur(grey, smooth, cv::Size(0, 0), 1.0);
  const int x0 = std::max(0, static_cast<int>(std::floor(sphere.centre.x() - sphere.radius)));
  const int x1 =
      std::min(image.width() - 1, static_cast<int>(std::ceil(sphere.centre.x() + sphere.radius)));
  const int y0 = std::max(0, static_cast<int>(std::floor(sphere.centre.y() - sphere.radius)));
  const int y1 =
      std::min(image.height() - 1, static_cast<int>(std::ceil(sphere.centre.y() + sphere.radius)));
  const auto inside = [&](int x, int y) {
    return (Eigen::Vector2d(x + 0.5, y + 0.5) - sphere.centre).norm() < sphere.radius;
  };
  std::vector<float> values;
  int peak_x = -1, peak_y = -1;
  float peak_smooth = -1.0f;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (!inside(x, y)) continue;
      values.push_back(grey.at<float>(y, x));
      if (smooth.at<float>(y, x) > peak_smooth) {
        peak_smooth = smooth.at<float>(y, x);
        peak_x = x, peak_y = y;
      }
    }
  }
  if (values.empty()) {
    throw Error(image_name, "sphere not found: the circle lies outside the image");
  }
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  const double median = values[values.size() / 2];
  const double peak = grey.at<float>(peak_y, peak_x);
  if (peak < options.minimum_peak || peak < options.minimum_contrast * median) {
    throw Error(image_name,
                fmt::format("highlight too weak: the body point of the sphere is {:.4f} "
                            "(full scale 1) against a sphere median of {:.4f}; it needs at least "
                            "{:.3f} and {:.1f} x the median",
                            peak, median, options.minimum_peak, options.minimum_contrast));
  }
  // The blob: connected pixels above half-way between the sphere's median and the peak.
  const double threshold = median + 0.5 * (peak - median);
  Highlight result;
  result.peak = peak;
  double weight_sum = 0.0;
  Eigen::Vector2d weighted = Eigen::Vector2d::Zero();
  std::vector<std::uint8_t> visited(static_cast<std::size_t>(image.width()) * image.height(), 0);
  std::queue<std::pair<int, int>> queue;
  queue.emplace(peak_x, peak_y);
  visited[static_cast<std::size_t>(peak_y) * image.width() + peak_x] = 1;
  while (!queue.empty()) {
    const auto [x, y] = queue.front();
    queue.pop();
    const double value = grey.at<float>(y, x);
    const double w = value - threshold;
    weighted += w * Eigen::Vector2d(x + 0.5, y + 0.5);
    weight_sum += w;
    ++result.blob_pixels;
    bool clipped = false;
    for (float v : image.pixel(x, y)) clipped = clipped || v >= options.saturation_level;
    if (clipped) ++result.saturated_pixels;
    constexpr int kDx[4] = {1, -1, 0, 0}, kDy[4] = {0, 0, 1, -1};
    for (int d = 0; d < 4; ++d) {
      const int nx = x + kDx[d], ny = y + kDy[d];
      if (nx < 0 || ny < 0 || nx >= image.width() || ny >= image.height()) continue;
      auto& seen = visited[static_cast<std::size_t>(ny) * image.width() + nx];
      if (seen || !inside(nx, ny) || grey.at<float>(ny, nx) < threshold) continue;
      seen = 1;
      queue.emplace(nx, ny);
    }
  }
  const double saturated_radius = std::sqrt(result.saturated_pixels / kPi);
  if (saturated_radius > options.maximum_saturated_radius * sphere.radius) {
    throw Error(image_name,
                fmt::format("saturated highlight: a clipped blob of {} pixels (radius {:.1f} px, "
                            "more than {:.0f} % of the sphere's {:.1f} px radius) has no "
                            "measurable centre; capture the sphere with a shorter exposure",
                            result.saturated_pixels, saturated_radius,
                            100 * options.maximum_saturated_radius, sphere.radius));
  }
  result.position = weight_sum > 0.0 ? (weighted / weight_sum).eval()
                                     : Eigen::Vector2d(peak_x + 0.5, peak_y + 0.5);
  const double fraction = (result.position - sphere.centre).norm() / sphere.radius;
  if (fraction > options.maximum_radius_fraction) {
    throw Error(image_name,
                fmt::format("highlight at the sphere's rim ({:.3f} of the radius from the centre, "
                            "limit {:.2f}): the light is nearly behind the sphere and its "
                            "direction cannot be measured",
                            fraction, options.maximum_radius_fraction));
  }
  return result;
}

LightDirection LightFromHighlight(const SphereCircle& sphere, const Eigen::Vector2d& highlight) {
  const double nx = (highlight.x() - sphere.centre.x()) / sphere.radius;
  const double ny = -(highlight.y() - sphere.centre.y()) / sphere.radius;
  const double nz = std::sqrt(std::max(0.0, 1.0 - nx * nx - ny * ny));
  // l = 2 (n.v) n - v with v = (0, 0, 1).
  return LightDirection::FromVector(2 * nz * nx, 2 * nz * ny, 2 * nz * nz - 1);
}

LightDirection LightFromHighlight(const SphereCircle& sphere, const Eigen::Vector2d& highlight,
                                  const CameraIntrinsics& camera) {
  return PerspectiveLight(SphereCentreFromCircle(sphere, camera), highlight, camera);
}

Eigen::Vector2d HighlightFromLight(const SphereCircle& sphere, const LightDirection& light) {
  const Eigen::Vector3d half = (light.vector() + Eigen::Vector3d::UnitZ()).normalized();
  return sphere.centre + sphere.radius * Eigen::Vector2d(half.x(), -half.y());
}

namespace {

// Every sphere's highlight in every image; one Error lists every failure.
void LocateAllHighlights(const std::vector<Image>& images, const std::vector<std::string>& names,
                         const MirrorSphereOptions& options, const fs::path& source,
                         std::vector<MirrorSphereFit>& spheres) {
  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  const std::size_t count = images.size() * spheres.size();
  progress.Start("highlights", count);
  for (auto& sphere : spheres) sphere.highlights.resize(images.size());
  std::vector<std::string> failures(count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t job) {
    const std::size_t i = job / spheres.size(), s = job % spheres.size();
    std::string name = i < names.size() ? names[i] : fmt::format("image {}", i);
    if (spheres.size() > 1) name += fmt::format(" (sphere {})", s + 1);
    try {
      spheres[s].highlights[i] =
          LocateHighlight(images[i], spheres[s].initial, options.highlight, name);
    } catch (const Error& error) {
      failures[job] = error.what();
    }
    progress.Advance();
  });
  progress.Finish();
  std::string message;
  int failed = 0;
  for (const std::string& failure : failures) {
    if (failure.empty()) continue;
    message += (failed++ ? "; " : "") + failure;
  }
  if (failed) {
    throw Error(source, fmt::format("{} of {} sphere images failed: {}", failed, count, message));
  }
}

// Step 4 for an orthographic camera: the joint refinement of every sphere with the lights; its
// result replaces the unrefined one only when the solve is usable.
void RefineOrthographic(const std::vector<std::vector<Eigen::Vector2d>>& outlines,
                        const MirrorSphereOptions& options, int width, int height,
                        MirrorSphereCalibration& result) {
  std::vector<MirrorSphereObservations> observations;
  MirrorSphereEstimate start;
  for (std::size_t s = 0; s < result.spheres.size(); ++s) {
    MirrorSphereObservations sphere{outlines[s], {}};
    for (const Highlight& h : result.spheres[s].highlights) sphere.highlights.push_back(h.position);
    observations.push_back(std::move(sphere));
    start.spheres.push_back(result.spheres[s].initial);
  }
  for (std::size_t i = 0; i < result.lights.size(); ++i) {
    start.lights.push_back(options.light_model == LightModel::kNear
                               ? TriangulateLamp(result.spheres, i, width, height)
                               : result.lights[i].vector());
  }
  const MirrorSphereRefinement refinement = RefineMirrorSpheres(
      observations, options.light_model, start, width, height, options.refine_max_iterations);
  result.refinement.status = refinement.status;
  result.refinement.iterations = refinement.iterations;
  if (!refinement.usable) return;
  result.refinement.used = true;
  result.refinement.highlight_sigma_pixels = refinement.highlight_sigma_pixels;
  result.refinement.highlight_sigma_measured = refinement.highlight_sigma_measured;
  result.light_uncertainty_degrees = refinement.light_sigma_degrees;
  for (std::size_t s = 0; s < result.spheres.size(); ++s) {
    result.spheres[s].refined = refinement.estimate.spheres[s];
  }
  result.lights.clear();
  for (const Eigen::Vector3d& light : refinement.estimate.lights) {
    result.lights.push_back(LightDirection::FromVector(light));
  }
  if (options.light_model == LightModel::kNear) result.lamp_positions = refinement.estimate.lights;
}

// The perspective camera (one sphere): the lights from the sphere's 3-D centre, refined jointly
// when asked.
void CalibratePerspective(const std::vector<Eigen::Vector2d>& edges,
                          const MirrorSphereOptions& options, MirrorSphereCalibration& result) {
  const CameraIntrinsics& camera = *options.camera;
  MirrorSphereFit& sphere = result.spheres.front();
  Eigen::Vector3d centre = SphereCentreFromCircle(sphere.initial, camera);
  std::vector<Eigen::Vector3d> lights;
  for (const Highlight& h : sphere.highlights) {
    lights.push_back(PhotomatToCamera(PerspectiveLight(centre, h.position, camera).vector()));
  }
  if (options.refine) {
    std::vector<Eigen::Vector3d> edge_rays;
    for (const auto& p : edges) edge_rays.push_back(CameraRay(camera, p));
    std::vector<Eigen::Vector2d> opencv_highlights;
    for (const Highlight& h : sphere.highlights)
      opencv_highlights.push_back(ToOpenCvPixel(h.position));
    result.refinement.status =
        RefinePerspectiveSphere(edge_rays, MeanFocal(camera), opencv_highlights, camera,
                                options.refine_max_iterations, &centre, &lights);
    result.refinement.used = result.refinement.status == "converged";
  }
  // Report the sphere as its image circle (centre of the outline, mean radius).
  const Eigen::Vector3d projected_centre(camera.fx * centre.x() / centre.z() + camera.cx,
                                         camera.fy * centre.y() / centre.z() + camera.cy, 1.0);
  sphere.refined.centre = Eigen::Vector2d(projected_centre.x() + 0.5, projected_centre.y() + 0.5);
  sphere.refined.radius = MeanFocal(camera) * std::tan(std::asin(1.0 / centre.norm()));
  double sum = 0.0;
  for (const auto& p : edges) {
    const Eigen::Vector3d ray = CameraRay(camera, p);
    const double angle = std::atan2(ray.cross(centre).norm(), ray.dot(centre));
    const double d = MeanFocal(camera) * (angle - std::asin(1.0 / centre.norm()));
    sum += d * d;
  }
  sphere.edge_rms_pixels = edges.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(edges.size()));
  result.lights.clear();
  for (const auto& light : lights)
    result.lights.push_back(LightDirection::FromVector(CameraToPhotomat(light)));
}

}  // namespace

MirrorSphereCalibration CalibrateLightsFromMirrorSphere(const std::vector<Image>& images,
                                                        const std::vector<std::string>& names,
                                                        const std::optional<Image>& mask,
                                                        const MirrorSphereOptions& options,
                                                        const fs::path& source) {
  if (images.empty()) throw Error(source, "no sphere images");
  const int width = images.front().width(), height = images.front().height();
  MirrorSphereCalibration result;
  result.perspective = options.camera.has_value();
  result.light_model = options.light_model;
  std::vector<std::vector<Eigen::Vector2d>> outlines;
  if (mask) {
    if (mask->width() != width || mask->height() != height) {
      throw Error(source, fmt::format("the sphere mask is {}x{} but the images are {}x{}",
                                      mask->width(), mask->height(), width, height));
    }
    outlines = MaskSphereOutlines(*mask);
    if (outlines.empty()) {
      throw Error(source, "sphere not found: the mask has no outline (is it empty or full?)");
    }
    for (const auto& points : outlines) {
      result.spheres.emplace_back().initial = FitMaskOutline(points, source);
    }
  } else {
    outlines.emplace_back();
    result.spheres.emplace_back().initial = DetectSphere(images, source, &outlines.back());
  }
  const std::size_t sphere_count = result.spheres.size();
  if (result.perspective && sphere_count > 1) {
    throw Error(source, fmt::format("the mask holds {} spheres, but a perspective camera "
                                    "(--camera) takes one sphere",
                                    sphere_count));
  }
  if (options.light_model == LightModel::kNear && (sphere_count < 2 || result.perspective)) {
    throw Error(source,
                fmt::format("near lights are triangulated from two or more spheres seen "
                            "by an orthographic camera; the mask holds {}{}",
                            sphere_count, result.perspective ? " and --camera is given" : ""));
  }
  if (options.refine && !MirrorSphereRefinementAvailable()) {
    throw Error(MirrorSphereRefinementAbsence() +
                ": calibrate the lights without it (the unrefined sphere: --no-refine)");
  }
  LocateAllHighlights(images, names, options, source, result.spheres);

  for (std::size_t s = 0; s < sphere_count; ++s) {
    result.spheres[s].refined = result.spheres[s].initial;
    result.spheres[s].edge_points = static_cast<int>(outlines[s].size());
  }
  result.refinement.requested = options.refine;
  result.refinement.status = options.refine ? "" : "not requested";
  const std::size_t n = images.size();
  if (!result.perspective) {
    for (std::size_t i = 0; i < n; ++i) {
      result.lights.push_back(LightDirection::FromVector(MeanDirection(result.spheres, i)));
    }
    if (options.refine) RefineOrthographic(outlines, options, width, height, result);
  } else {
    CalibratePerspective(outlines.front(), options, result);
  }
  for (std::size_t s = 0; s < sphere_count; ++s) {
    if (!result.perspective) {
      result.spheres[s].edge_rms_pixels = EdgeRms(result.spheres[s].refined, outlines[s]);
    }
  }
  const MirrorSphereFit& first = result.spheres.front();
  result.sphere = first.refined;
  result.initial = first.initial;
  result.highlights = first.highlights;
  result.edge_rms_pixels = first.edge_rms_pixels;
  result.edge_points = first.edge_points;
  return result;
}

}  // namespace photomat
