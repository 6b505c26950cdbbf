#include "capture/synthetic/synthetic_capture.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>

#include "core/enum_names.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/microfacet_brdf.h"
#include "core/random.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using Rgb = Eigen::Vector3d;

constexpr double kPi = std::numbers::pi;

double SmoothStep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Signed distance from a to b on a circle of circumference `period`, in [-period/2, period/2).
double WrapDelta(double a, double b, double period) {
  double d = std::fmod(a - b, period);
  if (d < -period / 2) d += period;
  if (d >= period / 2) d -= period;
  return d;
}

// A smooth periodic random field in [0, 1]: a few random plane waves with integer frequencies.
class PeriodicNoise {
 public:
  PeriodicNoise(Random& random, double width, double height, int waves, int max_frequency)
      : width_(width), height_(height) {
    for (int i = 0; i < waves; ++i) {
      Wave wave;
      wave.kx = static_cast<double>(random.Index(2 * max_frequency + 1)) - max_frequency;
      wave.ky = static_cast<double>(random.Index(max_frequency + 1)) + (wave.kx == 0 ? 1 : 0);
      wave.phase = random.Uniform(0, 2 * kPi);
      wave.amplitude = 1.0 / std::hypot(wave.kx, wave.ky);
      total_ += wave.amplitude;
      waves_.push_back(wave);
    }
  }
  double operator()(double u, double v) const {
    double sum = 0.0;
    for (const Wave& w : waves_) {
      sum += w.amplitude * std::sin(2 * kPi * (w.kx * u / width_ + w.ky * v / height_) + w.phase);
    }
    return 0.5 + 0.5 * sum / total_;
  }

 private:
  struct Wave {
    double kx, ky, phase, amplitude;
  };
  double width_, height_, total_ = 0.0;
  std::vector<Wave> waves_;
};

// A procedural pattern: height (pixel units, before slope normalisation) and albedo at (u, v).
struct Pattern {
  std::function<double(double, double)> height;
  std::function<Rgb(double, double)> albedo;
};

Pattern MakeBumps(const SyntheticMaterialOptions& o, Random& random) {
  struct Bump {
    double u, v, radius, amplitude;
    Rgb tint;
  };
  const double w = o.width, h = o.height;
  const double scale = std::sqrt(w * h) / 128.0;
  const int count = std::max(4, static_cast<int>(w * h / 450.0));
  auto bumps = std::make_shared<std::vector<Bump>>();
  for (int i = 0; i < count; ++i) {
    const double shade = random.Uniform(0.8, 1.1);
    bumps->push_back({random.Uniform(0, w), random.Uniform(0, h), random.Uniform(3.0, 8.0) * scale,
                      (random.Uniform() < 0.75 ? 1.0 : -0.6) * random.Uniform(0.6, 1.0),
                      Rgb(shade, shade * random.Uniform(0.9, 1.05), shade * 0.95)});
  }
  auto noise = std::make_shared<PeriodicNoise>(random, w, h, 12, 6);
  Pattern pattern;
  pattern.height = [=](double u, double v) -> double {
    double s = 0.0;
    for (const Bump& b : *bumps) {
      const double du = WrapDelta(u, b.u, w), dv = WrapDelta(v, b.v, h);
      if (std::abs(du) > 5 * b.radius || std::abs(dv) > 5 * b.radius) continue;  // exp < 4e-6
      s += b.amplitude * b.radius * std::exp(-(du * du + dv * dv) / (2 * b.radius * b.radius));
    }
    return s;
  };
  pattern.albedo = [=](double u, double v) -> Rgb {
    const double t = (*noise)(u, v);
    Rgb colour = (1 - t) * Rgb(0.55, 0.42, 0.25) + t * Rgb(0.75, 0.68, 0.5);
    for (const Bump& b : *bumps) {
      const double du = WrapDelta(u, b.u, w), dv = WrapDelta(v, b.v, h);
      if (std::abs(du) > b.radius || std::abs(dv) > b.radius) continue;
      const double inside = 1.0 - SmoothStep(0.6 * b.radius, 1.0 * b.radius, std::hypot(du, dv));
      colour = colour.cwiseProduct(Rgb::Ones() + inside * (b.tint - Rgb::Ones()));
    }
    return colour;
  };
  return pattern;
}

Pattern MakeGrooves(const SyntheticMaterialOptions& o, Random& random) {
  const double w = o.width, h = o.height;
  const int grooves = std::max(2, static_cast<int>(std::lround(w / 21.0)));
  const int waves = std::max(1, static_cast<int>(std::lround(h / 64.0)));
  const double groove_width = 0.35;  // fraction of the groove period
  auto noise = std::make_shared<PeriodicNoise>(random, w, h, 10, 5);
  const auto in_groove = [=](double u) {
    const double phase = std::fmod(u * grooves / w, 1.0);
    return 1.0 - SmoothStep(0.0, groove_width / 2, std::abs(phase - 0.5));
  };
  Pattern pattern;
  pattern.height = [=](double u, double v) -> double {
    const double period = w / grooves;
    return -0.25 * period * in_groove(u) + 0.12 * period * std::sin(2 * kPi * waves * v / h);
  };
  pattern.albedo = [=](double u, double v) -> Rgb {
    const double t = (*noise)(u, v);
    const Rgb land = (1 - t) * Rgb(0.35, 0.45, 0.6) + t * Rgb(0.5, 0.6, 0.75);
    return (1 - in_groove(u)) * land + in_groove(u) * Rgb(0.2, 0.22, 0.3);
  };
  return pattern;
}

Pattern MakeBricks(const SyntheticMaterialOptions& o, Random& random) {
  struct Brick {
    Rgb colour;
    double tilt_u, tilt_v;
  };
  const double w = o.width, h = o.height;
  const int columns = std::max(2, static_cast<int>(std::lround(w / 40.0)));
  const int rows = std::max(2, 2 * static_cast<int>(std::lround(h / 40.0)));  // even: periodic
  const double brick_w = w / columns, brick_h = h / rows;
  const double mortar = 0.06 * brick_h, bevel = 0.22 * brick_h;
  auto bricks = std::make_shared<std::vector<Brick>>();
  for (int i = 0; i < rows * columns; ++i) {
    const double r = random.Uniform(0.45, 0.75);
    bricks->push_back({Rgb(r, r * random.Uniform(0.45, 0.6), r * random.Uniform(0.3, 0.42)),
                       random.Uniform(-0.06, 0.06), random.Uniform(-0.06, 0.06)});
  }
  auto noise = std::make_shared<PeriodicNoise>(random, w, h, 16, 12);
  // Which brick (u, v) is on, the local offsets from its centre, and the distance to its edge.
  const auto locate = [=](double u, double v, int& index, double& du, double& dv) {
    const int row = static_cast<int>(std::floor(v / brick_h)) % rows;
    const double shifted = u + (row % 2 ? brick_w / 2 : 0.0);
    const int column = static_cast<int>(std::floor(shifted / brick_w)) % columns;
    index = ((row + rows) % rows) * columns + (column + columns) % columns;
    du = std::fmod(shifted, brick_w) - brick_w / 2;
    dv = std::fmod(v, brick_h) - brick_h / 2;
    return std::min(brick_w / 2 - std::abs(du), brick_h / 2 - std::abs(dv));
  };
  Pattern pattern;
  pattern.height = [=](double u, double v) -> double {
    int index;
    double du, dv;
    const double edge = locate(u, v, index, du, dv);
    const double raised = SmoothStep(mortar, mortar + bevel, edge);
    const Brick& b = (*bricks)[index];
    return raised * (0.3 * brick_h + b.tilt_u * du + b.tilt_v * dv) +
           0.015 * brick_h * std::sin(2 * kPi * 7 * u / w) * std::sin(2 * kPi * 5 * v / h);
  };
  pattern.albedo = [=](double u, double v) -> Rgb {
    int index;
    double du, dv;
    const double edge = locate(u, v, index, du, dv);
    const double raised = SmoothStep(mortar, mortar + bevel * 0.5, edge);
    const double grain = 0.85 + 0.3 * (*noise)(u, v);
    return grain * (raised * (*bricks)[index].colour + (1 - raised) * Rgb(0.62, 0.6, 0.56));
  };
  return pattern;
}

Pattern MakePattern(const SyntheticMaterialOptions& options, Random& random) {
  switch (options.pattern) {
    case SurfacePattern::kBumps:
      return MakeBumps(options, random);
    case SurfacePattern::kGrooves:
      return MakeGrooves(options, random);
    case SurfacePattern::kBricks:
      break;
  }
  return MakeBricks(options, random);
}

// Bilinear, periodic sample of a one-channel image at continuous pixel coordinates (u right,
// v up, pixel centres at half-integers).
double SamplePeriodic(const Image& image, double u, double v) {
  const int w = image.width(), h = image.height();
  const double x = u - 0.5, y = (h - v) - 0.5;  // column and row
  const double x0 = std::floor(x), y0 = std::floor(y);
  const double fx = x - x0, fy = y - y0;
  const auto at = [&](double xi, double yi) {
    const int c = ((static_cast<int>(xi) % w) + w) % w;
    const int r = ((static_cast<int>(yi) % h) + h) % h;
    return static_cast<double>(image.at(c, r, 0));
  };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) +
         fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

// True if the height field blocks the light before it reaches (u, v).
bool InCastShadow(const Image& height, double max_height, double u, double v,
                  const Eigen::Vector3d& light) {
  const double horizontal = std::hypot(light.x(), light.y());
  if (horizontal < 1e-9) return false;
  const double du = light.x() / horizontal, dv = light.y() / horizontal;
  const double rise = light.z() / horizontal;  // height gained per pixel travelled
  const double start = SamplePeriodic(height, u, v);
  constexpr double kStep = 0.5, kTolerance = 1e-3;
  for (double t = kStep; start + rise * t <= max_height; t += kStep) {
    if (SamplePeriodic(height, u + du * t, v + dv * t) > start + rise * t + kTolerance) {
      return true;
    }
  }
  return false;
}

constexpr std::array<NamedValue<SurfacePattern>, 3> kPatternNames = {
    {{SurfacePattern::kBumps, "bumps"},
     {SurfacePattern::kGrooves, "grooves"},
     {SurfacePattern::kBricks, "bricks"}}};

// The GGX maps: smooth periodic fields over [min, max], from a stream of their own so that the
// height and albedo of a seed stay what they were before these maps existed.
void AddMicrofacetMaps(const SyntheticMaterialOptions& options, SyntheticMaterial& material) {
  if (!(options.roughness_min >= 0.0 && options.roughness_min <= options.roughness_max &&
        options.roughness_max <= 1.0)) {
    throw Error("the roughness range must satisfy 0 <= min <= max <= 1");
  }
  if (!(options.f0_min >= 0.0 && options.f0_min <= options.f0_max && options.f0_max <= 1.0)) {
    throw Error("the F0 range must satisfy 0 <= min <= max <= 1");
  }
  Random random(options.seed * 1000003ULL + 0x9e37);
  const int w = options.width, h = options.height;
  const PeriodicNoise roughness_noise(random, w, h, 8, 3);
  const PeriodicNoise f0_noise(random, w, h, 8, 3);
  material.roughness = Image(w, h, std::vector<std::string>{"roughness"});
  material.f0 = Image(w, h, std::vector<std::string>{"f0"});
  for (int row = 0; row < h; ++row) {
    for (int col = 0; col < w; ++col) {
      const double u = col + 0.5, v = h - row - 0.5;
      material.roughness.at(col, row, 0) = static_cast<float>(
          options.roughness_min +
          (options.roughness_max - options.roughness_min) * roughness_noise(u, v));
      material.f0.at(col, row, 0) =
          static_cast<float>(options.f0_min + (options.f0_max - options.f0_min) * f0_noise(u, v));
    }
  }
}

}  // namespace

std::string_view ToString(SurfacePattern pattern) { return NameOf(pattern, kPatternNames); }

std::optional<SurfacePattern> ParseSurfacePattern(std::string_view name) {
  return FindValueNamed(name, kPatternNames);
}

SyntheticMaterial MakeSyntheticMaterial(const SyntheticMaterialOptions& options) {
  if (options.width < 8 || options.height < 8 || options.width > 16384 || options.height > 16384) {
    throw Error(fmt::format("synthetic size {}x{}: width and height must be in 8..16384",
                            options.width, options.height));
  }
  if (!(options.max_slope_degrees > 0.0 && options.max_slope_degrees < 85.0)) {
    throw Error("the maximum slope must be between 0 and 85 degrees");
  }
  Random random(options.seed);
  const Pattern pattern = MakePattern(options, random);
  const int w = options.width, h = options.height;
  Image height(w, h, std::vector<std::string>{"height"});
  Image gradient(w, h, 2);
  SyntheticMaterial material{Image(w, h, 1), Image(w, h, std::vector<std::string>{"R", "G", "B"}),
                             Image(w, h, std::vector<std::string>{"R", "G", "B"}), Image(),
                             Image()};  // roughness and F0: AddMicrofacetMaps
  // Gradients by central differences of the smooth pattern, 1e-3 pixel apart: the truth is the
  // pattern's own slope at the pixel centre, not a finite difference between pixels.
  constexpr double kDelta = 1e-3;
  tbb::parallel_for(0, h, [&](int row) {
    for (int col = 0; col < w; ++col) {
      const double u = col + 0.5, v = h - row - 0.5;
      height.at(col, row, 0) = static_cast<float>(pattern.height(u, v));
      gradient.at(col, row, 0) = static_cast<float>(
          (pattern.height(u + kDelta, v) - pattern.height(u - kDelta, v)) / (2 * kDelta));
      gradient.at(col, row, 1) = static_cast<float>(
          (pattern.height(u, v + kDelta) - pattern.height(u, v - kDelta)) / (2 * kDelta));
      const Rgb albedo = pattern.albedo(u, v).cwiseMax(0.05).cwiseMin(0.9);
      for (int c = 0; c < 3; ++c) material.albedo.at(col, row, c) = static_cast<float>(albedo[c]);
    }
  });
  double steepest = 0.0;
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    steepest = std::max(steepest, std::hypot(double{gradient.pixel(p)[0]}, gradient.pixel(p)[1]));
  }
  const double scale =
      std::tan(options.max_slope_degrees * kPi / 180.0) / std::max(steepest, 1e-12);
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    const double gp = gradient.pixel(p)[0] * scale, gq = gradient.pixel(p)[1] * scale;
    height.pixel(p)[0] = static_cast<float>(height.pixel(p)[0] * scale);
    const Eigen::Vector3d n = Eigen::Vector3d(-gp, -gq, 1.0).normalized();
    for (int c = 0; c < 3; ++c) material.normals.pixel(p)[c] = static_cast<float>(n[c]);
  }
  material.height = std::move(height);
  AddMicrofacetMaps(options, material);
  return material;
}

PhotometricSet RenderSyntheticCapture(const SyntheticMaterial& material,
                                      const std::vector<LightDirection>& lights,
                                      const SyntheticRenderOptions& options) {
  if (lights.empty()) throw Error("no lights to render");
  if (options.microfacet && options.specular > 0.0) {
    throw Error("a synthetic capture has either Blinn-Phong or GGX highlights, not both");
  }
  const int w = material.normals.width(), h = material.normals.height();
  float max_height = -INFINITY;
  for (float v : material.height.values()) max_height = std::max(max_height, v);
  std::vector<Image> images(lights.size());
  tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
    const Eigen::Vector3d l = lights[i].vector();
    const Eigen::Vector3d half = (l + Eigen::Vector3d::UnitZ()).normalized();
    Image image(w, h, std::vector<std::string>{"R", "G", "B"});
    for (int row = 0; row < h; ++row) {
      for (int col = 0; col < w; ++col) {
        const auto np = material.normals.pixel(col, row);
        const Eigen::Vector3d n(np[0], np[1], np[2]);
        double shading = n.dot(l);
        double highlight = 0.0;
        const bool lit = shading > 0.0 &&
                         !(options.shadows &&
                           InCastShadow(material.height, max_height, col + 0.5, h - row - 0.5, l));
        if (options.shadows && !lit) shading = 0.0;
        if (options.specular > 0.0 && lit) {
          highlight = options.specular * std::pow(std::max(0.0, n.dot(half)), options.shininess);
        }
        if (options.microfacet) {
          // Attached shadows are in the BRDF (0 for n.l <= 0); cast shadows as above.
          const MicrofacetResponse<double> response =
              lit || !options.shadows ? MicrofacetRadiance<double>(
                                            n.data(), l.data(), material.roughness.at(col, row, 0),
                                            material.f0.at(col, row, 0))
                                      : MicrofacetResponse<double>{0.0, 0.0};
          shading = response.diffuse;
          highlight = response.specular;
        }
        for (int c = 0; c < 3; ++c) {
          image.at(col, row, c) =
              static_cast<float>(material.albedo.at(col, row, c) * shading + highlight);
        }
      }
    }
    if (options.noise_sigma > 0.0) {
      // One stream per image, so the noise does not depend on the thread schedule.
      Random random(options.noise_seed * 1000003ULL + i);
      AddGaussianNoise(image, options.noise_sigma, random);
    }
    images[i] = std::move(image);
  });
  std::vector<std::string> names;
  for (std::size_t i = 0; i < lights.size(); ++i) {
    names.push_back(fmt::format("synthetic slant {:.1f} tilt {:.1f}", lights[i].SlantDegrees(),
                                lights[i].TiltDegrees()));
  }
  return PhotometricSet(std::move(images), lights, std::move(names));
}

void WriteSyntheticCapture(const fs::path& folder, const SyntheticMaterial& material,
                           const PhotometricSet& set, const SaveSetOptions& options) {
  CaptureManifest manifest = SavePhotometricSet(folder, set, options);
  WriteImage(folder / "gt_normals.exr", material.normals);
  WriteImage(folder / "gt_albedo.exr", material.albedo);
  WriteImage(folder / "gt_height.exr", material.height);
  WriteImage(folder / "gt_roughness.exr", material.roughness);
  WriteImage(folder / "gt_f0.exr", material.f0);
  manifest.ground_truth_normals = "gt_normals.exr";
  manifest.ground_truth_albedo = "gt_albedo.exr";
  manifest.ground_truth_height = "gt_height.exr";
  WriteCaptureManifest(folder / kCaptureManifestName, manifest);
}

}  // namespace photomat
