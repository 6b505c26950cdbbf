#include "calibrate/lights/mirror_sphere.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <queue>

#include "calibrate/lights/mirror_sphere_refinement.h"
#include "core/error.h"
#include "core/text_parsing.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

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
  const auto coverage = [&](int x, int y) { return static_cast<double>(mask.at(x, y, 0)); };
  for (int y = 0; y < mask.height(); ++y) {
    for (int x = 0; x + 1 < mask.width(); ++x) {
      const double v0 = coverage(x, y), v1 = coverage(x + 1, y);
      if ((v0 - 0.5) * (v1 - 0.5) < 0.0) {
        points.emplace_back(x + 0.5 + (0.5 - v0) / (v1 - v0), y + 0.5);
      }
    }
  }
  for (int x = 0; x < mask.width(); ++x) {
    for (int y = 0; y + 1 < mask.height(); ++y) {
      const double v0 = coverage(x, y), v1 = coverage(x, y + 1);
      if ((v0 - 0.5) * (v1 - 0.5) < 0.0) {
        points.emplace_back(x + 0.5, y + 0.5 + (0.5 - v0) / (v1 - v0));
      }
    }
  }
  return points;
}

SphereCircle FitSphereToMask(const Image& mask, const fs::path& source) {
  const std::vector<Eigen::Vector2d> points = MaskEdgePoints(mask);
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

MirrorSphereCalibration CalibrateLightsFromMirrorSphere(const std::vector<Image>& images,
                                                        const std::vector<std::string>& names,
                                                        const std::optional<Image>& mask,
                                                        const MirrorSphereOptions& options,
                                                        const fs::path& source) {
  if (images.empty()) throw Error(source, "no sphere images");
  MirrorSphereCalibration result;
  std::vector<Eigen::Vector2d> edges;
  if (mask) {
    if (mask->width() != images.front().width() || mask->height() != images.front().height()) {
      throw Error(source,
                  fmt::format("the sphere mask is {}x{} but the images are {}x{}", mask->width(),
                              mask->height(), images.front().width(), images.front().height()));
    }
    result.initial = FitSphereToMask(*mask, source);
    edges = MaskEdgePoints(*mask);
  } else {
    result.initial = DetectSphere(images, source, &edges);
  }

  NullProgress no_progress;
  Progress& progress = OrNull(options.progress, no_progress);
  progress.Start("highlights", images.size());
  result.highlights.resize(images.size());
  std::vector<std::string> failures(images.size());
  tbb::parallel_for(std::size_t{0}, images.size(), [&](std::size_t i) {
    const std::string name = i < names.size() ? names[i] : fmt::format("image {}", i);
    try {
      result.highlights[i] = LocateHighlight(images[i], result.initial, options.highlight, name);
    } catch (const Error& error) {
      failures[i] = error.what();
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
    throw Error(source,
                fmt::format("{} of {} sphere images failed: {}", failed, images.size(), message));
  }

  result.perspective = options.camera.has_value();
  result.edge_points = static_cast<int>(edges.size());
  const std::size_t n = images.size();
  std::vector<Eigen::Vector3d> lights(n);
  std::vector<Eigen::Vector2d> highlights(n);
  for (std::size_t i = 0; i < n; ++i) highlights[i] = result.highlights[i].position;
  if (!result.perspective) {
    result.sphere = result.initial;
    for (std::size_t i = 0; i < n; ++i) {
      lights[i] = LightFromHighlight(result.initial, highlights[i]).vector();
    }
    if (options.refine) RefineOrthographicSphere(edges, highlights, &result.sphere, &lights);
    result.edge_rms_pixels = EdgeRms(result.sphere, edges);
  } else {
    const CameraIntrinsics& camera = *options.camera;
    Eigen::Vector3d centre = SphereCentreFromCircle(result.initial, camera);
    for (std::size_t i = 0; i < n; ++i) {
      lights[i] = PhotomatToCamera(PerspectiveLight(centre, highlights[i], camera).vector());
    }
    if (options.refine) {
      std::vector<Eigen::Vector3d> edge_rays;
      for (const auto& p : edges) edge_rays.push_back(CameraRay(camera, p));
      std::vector<Eigen::Vector2d> opencv_highlights;
      for (const auto& h : highlights) opencv_highlights.push_back(ToOpenCvPixel(h));
      RefinePerspectiveSphere(edge_rays, MeanFocal(camera), opencv_highlights, camera, &centre,
                              &lights);
    }
    // Report the refined sphere as its image circle (centre of the outline, mean radius).
    const Eigen::Vector3d projected_centre(camera.fx * centre.x() / centre.z() + camera.cx,
                                           camera.fy * centre.y() / centre.z() + camera.cy, 1.0);
    result.sphere.centre = Eigen::Vector2d(projected_centre.x() + 0.5, projected_centre.y() + 0.5);
    result.sphere.radius = MeanFocal(camera) * std::tan(std::asin(1.0 / centre.norm()));
    double sum = 0.0;
    for (const auto& p : edges) {
      const Eigen::Vector3d ray = CameraRay(camera, p);
      const double angle = std::atan2(ray.cross(centre).norm(), ray.dot(centre));
      const double d = MeanFocal(camera) * (angle - std::asin(1.0 / centre.norm()));
      sum += d * d;
    }
    result.edge_rms_pixels =
        edges.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(edges.size()));
    for (auto& light : lights) light = CameraToPhotomat(light);
  }
  for (const auto& light : lights) result.lights.push_back(LightDirection::FromVector(light));
  return result;
}

}  // namespace photomat
