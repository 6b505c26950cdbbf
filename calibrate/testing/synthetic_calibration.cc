#include "calibrate/testing/synthetic_calibration.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/microfacet_brdf.h"
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

namespace {

// Where a sub-sample sees a sphere: the reflected direction (photomat frame) and the point of the
// sphere (sample frame; orthographic camera only).
struct MirrorSample {
  Eigen::Vector3d reflected;
  Eigen::Vector3d point;
};

std::optional<MirrorSample> OrthographicSample(const MirrorSphereRenderOptions& options,
                                               const Eigen::Vector2d& p) {
  std::vector<SphereCircle> spheres = {options.sphere};
  spheres.insert(spheres.end(), options.more_spheres.begin(), options.more_spheres.end());
  for (const SphereCircle& sphere : spheres) {
    const Eigen::Vector2d d = (p - sphere.centre) / sphere.radius;
    if (d.squaredNorm() >= 1.0) continue;
    const Eigen::Vector3d n(d.x(), -d.y(), std::sqrt(1.0 - d.squaredNorm()));
    const Eigen::Vector3d centre(sphere.centre.x() - options.width / 2.0,
                                 options.height / 2.0 - sphere.centre.y(), sphere.radius);
    return MirrorSample{2.0 * n.z() * n - Eigen::Vector3d::UnitZ(), centre + sphere.radius * n};
  }
  return std::nullopt;
}

std::optional<MirrorSample> PerspectiveSample(const MirrorSphereRenderOptions& options,
                                              const Eigen::Vector2d& p) {
  const CameraIntrinsics& k = *options.camera;
  const Eigen::Vector3d c = options.sphere_centre_camera;
  const Eigen::Vector3d u =
      Eigen::Vector3d((p.x() - 0.5 - k.cx) / k.fx, (p.y() - 0.5 - k.cy) / k.fy, 1.0).normalized();
  const double uc = u.dot(c);
  const double discriminant = uc * uc - c.squaredNorm() + 1.0;
  if (discriminant <= 0.0) return std::nullopt;
  const Eigen::Vector3d n = ((uc - std::sqrt(discriminant)) * u - c).normalized();
  const Eigen::Vector3d r = 2.0 * n.dot(-u) * n + u;  // camera frame
  return MirrorSample{Eigen::Vector3d(r.x(), -r.y(), -r.z()), Eigen::Vector3d::Zero()};
}

void Blur(Image& image, double sigma) {
  if (sigma <= 0.0) return;
  for (int c = 0; c < image.channels(); ++c) {
    cv::Mat plane(image.height(), image.width(), CV_32F);
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) plane.at<float>(y, x) = image.at(x, y, c);
    }
    cv::GaussianBlur(plane, plane, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
    for (int y = 0; y < image.height(); ++y) {
      for (int x = 0; x < image.width(); ++x) image.at(x, y, c) = plane.at<float>(y, x);
    }
  }
}

// The render of `count` images; `light_towards(i, point)` is the direction of image i's light
// seen from a point of a sphere.
template <typename LightTowards>
MirrorSphereRender RenderSpheres(std::size_t count, const MirrorSphereRenderOptions& options,
                                 const LightTowards& light_towards) {
  if (options.width < 8 || options.height < 8 || options.supersampling < 1 ||
      !(options.sphere.radius > 1.0)) {
    throw Error("mirror sphere render: bad size, radius or supersampling");
  }
  if (options.camera && !options.more_spheres.empty()) {
    throw Error("mirror sphere render: more spheres need the orthographic camera");
  }
  const int w = options.width, h = options.height, s = options.supersampling;
  const double sigma = options.lamp_sigma_degrees * kPi / 180.0;
  const auto sample_at = [&](const Eigen::Vector2d& p) {
    return options.camera ? PerspectiveSample(options, p) : OrthographicSample(options, p);
  };
  MirrorSphereRender render;
  render.coverage = Image(w, h, std::vector<std::string>{"Y"});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int inside = 0;
      for (int sy = 0; sy < s; ++sy) {
        for (int sx = 0; sx < s; ++sx) {
          if (sample_at(Eigen::Vector2d(x + (sx + 0.5) / s, y + (sy + 0.5) / s))) ++inside;
        }
      }
      render.coverage.at(x, y, 0) = static_cast<float>(inside) / static_cast<float>(s * s);
    }
  }
  Blur(render.coverage, options.blur_sigma);
  render.images.resize(count);
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    Image image(w, h, std::vector<std::string>{"R", "G", "B"});
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        double sum = 0.0;
        for (int sy = 0; sy < s; ++sy) {
          for (int sx = 0; sx < s; ++sx) {
            const auto sample = sample_at(Eigen::Vector2d(x + (sx + 0.5) / s, y + (sy + 0.5) / s));
            if (!sample) {
              sum += options.background;
              continue;
            }
            const Eigen::Vector3d l = light_towards(i, sample->point);
            const Eigen::Vector3d& reflected = sample->reflected;
            const double angle = std::atan2(reflected.cross(l).norm(), reflected.dot(l));
            sum += options.lamp_peak * std::exp(-angle * angle / (2 * sigma * sigma)) +
                   options.environment * (0.6 + 0.4 * reflected.y());
          }
        }
        const auto value = static_cast<float>(sum / (s * s));
        for (int c = 0; c < 3; ++c) image.at(x, y, c) = value;
      }
    }
    Blur(image, options.blur_sigma);
    AddNoise(image, options.noise_sigma, options.noise_seed * 1000003ULL + i);
    render.images[i] = std::move(image);
  });
  return render;
}

}  // namespace

MirrorSphereRender RenderMirrorSphere(const std::vector<LightDirection>& lights,
                                      const MirrorSphereRenderOptions& options) {
  if (lights.empty()) throw Error("no lights to render");
  return RenderSpheres(lights.size(), options,
                       [&](std::size_t i, const Eigen::Vector3d&) { return lights[i].vector(); });
}

MirrorSphereRender RenderMirrorSpheresUnderLamps(const std::vector<Eigen::Vector3d>& lamps,
                                                 const MirrorSphereRenderOptions& options) {
  if (lamps.empty()) throw Error("no lamps to render");
  if (options.camera) throw Error("mirror sphere render: near lamps need the orthographic camera");
  return RenderSpheres(lamps.size(), options, [&](std::size_t i, const Eigen::Vector3d& point) {
    return (lamps[i] - point).normalized().eval();
  });
}

MirrorSphereRenderOptions SmallSphereRenderOptions() {
  MirrorSphereRenderOptions options;
  options.width = 200;
  options.height = 150;
  options.sphere = {Eigen::Vector2d(97.3, 76.6), 60.0};
  options.supersampling = 3;
  return options;
}

MirrorSphereRenderOptions TwoSphereRenderOptions() {
  MirrorSphereRenderOptions options;
  options.width = 320;
  options.height = 240;
  options.sphere = {Eigen::Vector2d(70.3, 150.6), 40.0};
  options.more_spheres = {{Eigen::Vector2d(248.7, 96.2), 41.5}};
  options.supersampling = 3;
  options.lamp_sigma_degrees = 2.0;
  options.blur_sigma = 1.0;
  options.noise_sigma = 0.01;
  options.noise_seed = 17;
  return options;
}

std::vector<Eigen::Vector3d> NearLampRing(int count, double distance) {
  std::vector<Eigen::Vector3d> lamps;
  for (int i = 0; i < count; ++i) {
    const double slant = 15.0 + 40.0 * (i % 4) / 3.0, tilt = 360.0 * i / count + 7.0;
    lamps.push_back(distance * LightDirection::FromSlantTilt(slant, tilt).vector());
  }
  return lamps;
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
                                      const std::vector<NearLight>& lights, bool microfacet) {
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
        if (microfacet) {
          const Eigen::Vector3d l = to_light / distance;
          const MicrofacetResponse<double> response = MicrofacetRadiance<double>(
              n.data(), l.data(), material.roughness.at(x, y, 0), material.f0.at(x, y, 0));
          const double irradiance = lights[i].intensity / (distance * distance);
          for (int c = 0; c < 3; ++c) {
            image.at(x, y, c) = static_cast<float>(
                irradiance * (response.diffuse * material.albedo.at(x, y, c) + response.specular));
          }
          continue;
        }
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
