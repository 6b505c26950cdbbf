#include "relight/export/material_maps.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <optional>

#include "core/error.h"
#include "relight/formats/interchange.h"
#include "represent/surface/surface_integration.h"
#include "represent/surface/tiled_poisson.h"

namespace photomat {
namespace {

void DecodeToLinear(std::span<float> values, ColourSpace space) {
  if (space != ColourSpace::kSrgb) return;
  for (float& v : values) v = static_cast<float>(SrgbToLinear(v));
}

std::vector<std::string> Prefixed(const std::string& prefix, int channels) {
  std::vector<std::string> names;
  for (const auto& c : OutputChannelNames(channels)) names.push_back(prefix + c);
  return names;
}

// Channels of the representation's maps named `names`, or an empty image.
Image NamedMaps(const Representation& r, const std::vector<std::string>& names) {
  Image out(r.width(), r.height(), names);
  std::vector<int> source;
  for (const auto& name : names) {
    source.push_back(r.maps().FindChannel(name));
    if (source.back() < 0) return {};
  }
  for (std::size_t c = 0; c < names.size(); ++c) {
    const std::span<const float> plane = r.maps().plane(source[c]);
    std::copy(plane.begin(), plane.end(), out.plane(static_cast<int>(c)).begin());
  }
  return out;
}

// The 3 x K solve of least-squares photometric stereo, (L L^T)^-1 L, or nothing when the lights
// are (nearly) coplanar.
std::optional<Eigen::MatrixXd> LambertianSolve(const std::vector<LightDirection>& lights) {
  if (lights.size() < 3) return std::nullopt;
  const Eigen::MatrixXd l = LightMatrix(lights);
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(l, Eigen::ComputeThinU | Eigen::ComputeThinV);
  if (svd.singularValues()[2] < 0.02 * svd.singularValues()[0]) return std::nullopt;
  return svd.matrixU() * svd.singularValues().cwiseInverse().asDiagonal() *
         svd.matrixV().transpose();
}

// Least-squares Lambertian fit to the representation relit at the sample lights (its capture
// lights, or the dome when they are too few or coplanar): per pixel and channel the albedo-scaled
// normal. Writes unit normals (of the channel sum) unless `keep_normals`, and the albedo of each
// channel along the (given or fitted) normal.
void LambertianFit(const Representation& r, const MaterialMapOptions& options, bool keep_normals,
                   Image& normals, Image& albedo) {
  std::vector<LightDirection> lights = options.sample_lights;
  std::optional<Eigen::MatrixXd> solve = LambertianSolve(lights);
  if (!solve) {
    lights = RefitLights();
    solve = LambertianSolve(lights);
  }
  std::vector<Image> relit(lights.size());
  tbb::parallel_for(std::size_t{0}, lights.size(), [&](std::size_t i) {
    relit[i] = r.Relight(lights[i]);
    DecodeToLinear(relit[i].values(), options.values);
  });
  const int channels = r.output_channels();
  if (!keep_normals) {
    normals =
        Image(r.width(), r.height(), std::vector<std::string>{"normal.X", "normal.Y", "normal.Z"});
  }
  albedo = Image(r.width(), r.height(), Prefixed("albedo.", channels));
  tbb::parallel_for(std::size_t{0}, normals.pixel_count(), [&](std::size_t p) {
    Eigen::MatrixXd values(lights.size(), channels);
    for (std::size_t i = 0; i < lights.size(); ++i) {
      for (int c = 0; c < channels; ++c) values(i, c) = relit[i].pixel(p)[c];
    }
    const Eigen::MatrixXd scaled = *solve * values;  // 3 x C
    Eigen::Vector3d n;
    if (keep_normals) {
      const auto given = normals.pixel(p);
      n = Eigen::Vector3d(given[0], given[1], given[2]);
    } else {
      n = scaled.rowwise().sum();
      n = n.norm() > 0.0 ? n.normalized() : Eigen::Vector3d::UnitZ();
      for (int k = 0; k < 3; ++k) normals.pixel(p)[k] = static_cast<float>(n[k]);
    }
    for (int c = 0; c < channels; ++c) {
      albedo.pixel(p)[c] = static_cast<float>(std::max(0.0, scaled.col(c).dot(n)));
    }
  });
}

void ZeroOutside(Image& image, const Mask& mask) {
  for (std::size_t p = 0; p < image.pixel_count(); ++p) {
    if (!mask[p]) std::fill(image.pixel(p).begin(), image.pixel(p).end(), 0.0f);
  }
}

}  // namespace

std::string_view ToString(HeightIntegrator integrator) {
  return integrator == HeightIntegrator::kFrankotChellappa ? "fc" : "poisson";
}

HeightIntegrator ParseHeightIntegrator(std::string_view name) {
  if (name == "poisson") return HeightIntegrator::kPoisson;
  if (name == "fc" || name == "frankot-chellappa") return HeightIntegrator::kFrankotChellappa;
  throw Error(fmt::format("unknown height integrator \"{}\": expected poisson or fc", name));
}

Mask CoverageMask(const Representation& representation) {
  const Image& maps = representation.maps();
  Mask mask(maps.width(), maps.height(), false);
  for (std::size_t p = 0; p < maps.pixel_count(); ++p) {
    const auto v = maps.pixel(p);
    mask.Set(p, std::any_of(v.begin(), v.end(), [](float x) { return x != 0.0f; }));
  }
  return mask;
}

Image HeightFromNormals(const Image& normals, const Mask& mask, HeightIntegrator integrator) {
  const Image gradients = GradientsFromNormals(normals);
  Image height = integrator == HeightIntegrator::kFrankotChellappa
                     ? IntegrateFrankotChellappa(gradients)
                     : IntegratePoissonAnySize(gradients, mask);
  height.set_channel_names({"height"});
  return height;
}

MaterialMaps ExtractSurfaceMaps(const Representation& r, const MaterialMapOptions& options) {
  MaterialMaps out;
  out.mask = CoverageMask(r);
  out.normals = NamedMaps(r, {"normal.X", "normal.Y", "normal.Z"});
  // pbr: the base colour is the albedo (diffuse reflectance) of core/microfacet_brdf.h.
  Image albedo =
      NamedMaps(r, Prefixed(IsMicrofacet(r.shading()) ? "base." : "albedo.", r.output_channels()));
  if (!albedo.empty()) albedo.set_channel_names(Prefixed("albedo.", r.output_channels()));
  if (!out.normals.empty() && !albedo.empty() && options.values == ColourSpace::kLinear) {
    out.normals_source = "the representation's normal maps";
    out.albedo = std::move(albedo);
  } else if (auto estimated = EstimateNormals(r)) {
    out.normals = std::move(*estimated);
    out.normals_source = r.basis().kind() == "ptm" ? "the PTM luminance maximum"
                                                   : "the light basis (linear in the light)";
    LambertianFit(r, options, true, out.normals, out.albedo);
  } else {
    LambertianFit(r, options, false, out.normals, out.albedo);
    out.normals_source = "a Lambertian fit to the representation relit at its capture lights";
  }
  ZeroOutside(out.normals, out.mask);
  ZeroOutside(out.albedo, out.mask);
  return out;
}

MaterialMaps ExtractMaterialMaps(const Representation& r, const MaterialMapOptions& options) {
  if (CoverageMask(r).CountSet() == 0)
    throw Error(fmt::format("{}: every map is zero", r.method()));
  MaterialMaps out = ExtractSurfaceMaps(r, options);
  out.height = HeightFromNormals(out.normals, out.mask, options.height);
  if (options.height == HeightIntegrator::kFrankotChellappa) ZeroOutside(out.height, out.mask);
  return out;
}

}  // namespace photomat
