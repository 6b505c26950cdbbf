#include "calibrate/testing/synthetic_calibration.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

constexpr double kPi = std::numbers::pi;

void AddNoise(Image& image, double sigma, std::uint64_t seed) {
  if (sigma <= 0.0) return;
  Random random(seed);
  AddGaussianNoise(image, sigma, random);
}

}  // namespace

MirrorSphereRender RenderMirrorSphere(const std::vector<LightDirection>& lights,
                                      const MirrorSphereRenderOptions& options) {
  if (lights.empty()) throw Error("no lights to render");
  if (options.width < 8 || options.height < 8 || options.supersampling < 1 ||
      !(options.sphere.radius > 1.0)) {
    throw Error("mirror sphere render: bad size, radius or supersampling");
  }
  const int w = options.width, h = options.height, s = options.supersampling;
  const double sigma = options.lamp_sigma_degrees * kPi / 180.0;
  // Per sub-sample: the reflected direction (photomat frame) where the sub-sample sees the sphere.
  const auto reflected_at = [&](const Eigen::Vector2d& p) -> std::optional<Eigen::Vector3d> {
    if (!options.camera) {
      const Eigen::Vector2d d = (p - options.sphere.centre) / options.sphere.radius;
      if (d.squaredNorm() >= 1.0) return std::nullopt;
      const Eigen::Vector3d n(d.x(), -d.y(), std::sqrt(1.0 - d.squaredNorm()));
      return 2.0 * n.z() * n - Eigen::Vector3d::UnitZ();
    }
    const CameraIntrinsics& k = *options.camera;
    const Eigen::Vector3d c = options.sphere_centre_camera;
    const Eigen::Vector3d u =
        Eigen::Vector3d((p.x() - 0.5 - k.cx) / k.fx, (p.y() - 0.5 - k.cy) / k.fy, 1.0).normalized();
    const double uc = u.dot(c);
    const double discriminant = uc * uc - c.squaredNorm() + 1.0;
    if (discriminant <= 0.0) return std::nullopt;
    const Eigen::Vector3d n = ((uc - std::sqrt(discriminant)) * u - c).normalized();
    const Eigen::Vector3d r = 2.0 * n.dot(-u) * n + u;  // camera frame
    return Eigen::Vector3d(r.x(), -r.y(), -r.z());
  };
  MirrorSphereRender render;
  render.coverage = Image(w, h, std::vector<std::string>{"Y"});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int inside = 0;
      for (int sy = 0; sy < s; ++sy) {
        for (int sx = 0; sx < s; ++sx) {
          if (reflected_at(Eigen::Vector2d(x + (sx + 0.5) / s, y + (sy + 0.5) / s))) ++inside;
        }
      }
      render.coverage.at(x, y, 0) = static_cast<float>(inside) / static_cast<float>(s * s);
    }
  }
  render.images.resize(lights.size());
  tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
    const Eigen::Vector3d l = lights[i].vector();
    Image image(w, h, std::vector<std::string>{"R", "G", "B"});
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        double sum = 0.0;
        for (int sy = 0; sy < s; ++sy) {
          for (int sx = 0; sx < s; ++sx) {
            const auto reflected =
                reflected_at(Eigen::Vector2d(x + (sx + 0.5) / s, y + (sy + 0.5) / s));
            if (!reflected) {
              sum += options.background;
              continue;
            }
            const double angle = std::atan2(reflected->cross(l).norm(), reflected->dot(l));
            sum += options.lamp_peak * std::exp(-angle * angle / (2 * sigma * sigma)) +
                   options.environment * (0.6 + 0.4 * reflected->y());
          }
        }
        const auto value = static_cast<float>(sum / (s * s));
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = value;
      }
    }
    AddNoise(image, options.noise_sigma, options.noise_seed * 1000003ULL + i);
    render.images[i] = std::move(image);
  });
  return render;
}

MirrorSphereRenderOptions SmallSphereRenderOptions() {
  MirrorSphereRenderOptions options;
  options.width = 200;
  options.height = 150;
  options.sphere = {Eigen::Vector2d(97.3, 76.6), 60.0};
  options.supersampling = 3;
  return options;
}

std::vector<std::string> SphereImageNames(std::size_t count) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < count; ++i) names.push_back(fmt::format("sphere_{}.png", i));
  return names;
}

AngleStats CompareLights(const std::vector<LightDirection>& a,
                         const std::vector<LightDirection>& b) {
  AngleStats stats;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double angle = a[i].AngleToDegrees(b[i]);
    stats.mean += angle / static_cast<double>(a.size());
    stats.max = std::max(stats.max, angle);
  }
  return stats;
}

PhotometricSet RenderNearLightCapture(const SyntheticMaterial& material,
                                      const std::vector<NearLight>& lights) {
  if (lights.empty()) throw Error("no lights to render");
  const int w = material.normals.width(), h = material.normals.height();
  std::vector<Image> images(lights.size());
  tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
    Image image(w, h, std::vector<std::string>{"R", "G", "B"});
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const auto np = material.normals.pixel(x, y);
        const Eigen::Vector3d n(np[0], np[1], np[2]);
        const Eigen::Vector3d to_light =
            lights[i].position - SamplePoint(w, h, x, y, material.height.at(x, y, 0));
        const double distance = to_light.norm();
        const double irradiance =
            lights[i].intensity * std::max(0.0, n.dot(to_light / distance)) / (distance * distance);
        for (int c = 0; c < 3; ++c) {
          image.at(x, y, c) = static_cast<float>(material.albedo.at(x, y, c) * irradiance);
        }
      }
    }
    images[i] = std::move(image);
  });
  std::vector<std::string> names;
  for (std::size_t i = 0; i < lights.size(); ++i) names.push_back(fmt::format("near light {}", i));
  return PhotometricSet(std::move(images), NominalDirections(lights), std::move(names));
}

PhotometricSet RenderNearLightTarget(int width, int height, const std::vector<NearLight>& lights,
                                     double albedo, double noise_sigma, std::uint64_t noise_seed) {
  if (lights.empty()) throw Error("no lights to render");
  std::vector<Image> images(lights.size());
  tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
    Image image(width, height, std::vector<std::string>{"R", "G", "B"});
    for (int y = 0; y < height; ++y) {
      for (int x = 0; x < width; ++x) {
        const Eigen::Vector3d to_light = lights[i].position - SamplePoint(width, height, x, y);
        const double distance = to_light.norm();
        const double value =
            albedo * lights[i].intensity * to_light.z() / (distance * distance * distance);
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = static_cast<float>(value);
      }
    }
    AddNoise(image, noise_sigma, noise_seed * 1000003ULL + i);
    images[i] = std::move(image);
  });
  std::vector<std::string> names;
  for (std::size_t i = 0; i < lights.size(); ++i) names.push_back(fmt::format("target {}", i));
  return PhotometricSet(std::move(images), NominalDirections(lights), std::move(names));
}

}  // namespace photomat
