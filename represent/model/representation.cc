#include "represent/model/representation.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.h"

namespace photomat {

nlohmann::json MapLayout::ToJson() const {
  nlohmann::json json = {{"basis_size", basis_size},
                         {"basis_per_channel", basis_per_channel},
                         {"has_gain", has_gain},
                         {"output_channels", output_channels}};
  if (shading_maps > 0) json["shading_maps"] = shading_maps;
  return json;
}

std::vector<std::string> OutputChannelNames(int channels) {
  if (channels == 1) return {"Y"};
  if (channels == 3) return {"R", "G", "B"};
  std::vector<std::string> names;
  for (int c = 0; c < channels; ++c) names.push_back(fmt::format("C{}", c));
  return names;
}

std::vector<std::string> CoefficientMapNames(const std::string& prefix, int terms,
                                             const std::vector<std::string>& channel_names) {
  std::vector<std::string> names;
  for (int j = 0; j < terms; ++j) {
    for (const std::string& channel : channel_names) {
      names.push_back(fmt::format("{}{}.{}", prefix, j, channel));
    }
  }
  return names;
}

Representation::Representation(std::string method, Image maps, MapLayout layout,
                               std::shared_ptr<const LightBasis> basis, nlohmann::json details)
    : method_(std::move(method)),
      maps_(std::move(maps)),
      layout_(layout),
      basis_(std::move(basis)),
      details_(std::move(details)) {
  if (!basis_) throw Error(fmt::format("{}: no light basis", method_));
  if (layout_.output_channels < 1 || layout_.basis_size < 1) {
    throw Error(fmt::format("{}: empty map layout", method_));
  }
  if (maps_.channels() != layout_.MapCount()) {
    throw Error(fmt::format("{}: {} maps, but the layout needs {}", method_, maps_.channels(),
                            layout_.MapCount()));
  }
  if (layout_.shading_maps > 0 && basis_->kind() != "direction") {
    throw Error(fmt::format("{}: a shading takes the light direction, not a \"{}\" basis", method_,
                            basis_->kind()));
  }
  if (basis_->size() != layout_.basis_size) {
    throw Error(fmt::format("{}: the light basis has {} terms, the maps {}", method_,
                            basis_->size(), layout_.basis_size));
  }
}

namespace {

MapLayout ShadingLayout(const PixelShading* shading) {
  if (!shading) return {};
  MapLayout layout;
  layout.basis_size = 3;
  layout.basis_per_channel = false;
  layout.output_channels = shading->output_channels();
  layout.shading_maps = shading->map_count();
  return layout;
}

}  // namespace

Representation::Representation(std::string method, Image maps,
                               std::shared_ptr<const PixelShading> shading, nlohmann::json details)
    : Representation(std::move(method), std::move(maps), ShadingLayout(shading.get()),
                     std::make_shared<DirectionLightBasis>(), std::move(details)) {
  if (!shading) throw Error(fmt::format("{}: no shading", method_));
  shading_ = std::move(shading);
}

void Representation::RelightPixel(PixelValues<const float> maps,
                                  const Eigen::VectorXf& coefficients, std::span<float> out) const {
  if (shading_) {
    // The basis is the light direction (DirectionLightBasis).
    shading_->Shade(maps, std::span<const float>(coefficients.data(), 3), out);
    return;
  }
  const int per_term = layout_.BasisMapsPerTerm();
  for (int o = 0; o < layout_.output_channels; ++o) {
    const int b = layout_.basis_per_channel ? o : 0;
    float sum = 0.0f;
    for (int j = 0; j < layout_.basis_size; ++j) sum += coefficients[j] * maps[j * per_term + b];
    out[o] = layout_.has_gain ? sum * maps[layout_.GainOffset() + o] : sum;
  }
}

Image Representation::Relight(const LightDirection& light, const RelightOptions& options) const {
  const Eigen::VectorXf coefficients = basis_->Coefficients(light).cast<float>();
  Image image(maps_.width(), maps_.height(), OutputChannelNames(layout_.output_channels));
  if (shading_) {
    tbb::parallel_for(std::size_t{0}, image.pixel_count(), [&](std::size_t p) {
      std::array<float, 16> out{};
      RelightPixel(maps_.pixel(p), coefficients, std::span<float>(out.data(), image.channels()));
      for (int c = 0; c < image.channels(); ++c) {
        image.pixel(p)[c] = options.clamp_negative ? std::max(out[c], 0.0f) : out[c];
      }
    });
    return image;
  }
  // Row by row, plane by plane: out_o = gain_o * sum_j c_j B_j,o is an axpy per basis map (the
  // same sums, in the same order, as RelightPixel).
  const int per_term = layout_.BasisMapsPerTerm();
  const int width = maps_.width();
  tbb::parallel_for(0, maps_.height(), [&](int y) {
    for (int o = 0; o < layout_.output_channels; ++o) {
      const int b = layout_.basis_per_channel ? o : 0;
      float* out = image.row(o, y).data();
      std::fill(out, out + width, 0.0f);
      for (int j = 0; j < layout_.basis_size; ++j) {
        const float c = coefficients[j];
        const float* basis = maps_.row(j * per_term + b, y).data();
        for (int x = 0; x < width; ++x) out[x] += c * basis[x];
      }
      if (layout_.has_gain) {
        const float* gain = maps_.row(layout_.GainOffset() + o, y).data();
        for (int x = 0; x < width; ++x) out[x] *= gain[x];
      }
      if (options.clamp_negative) {
        for (int x = 0; x < width; ++x) out[x] = std::max(out[x], 0.0f);
      }
    }
  });
  return image;
}

Representation Representation::WithMaps(Image maps) const {
  return WithMapsAndDetails(std::move(maps), details_);
}

Representation Representation::WithMapsAndDetails(Image maps, nlohmann::json details) const {
  if (maps.channels() != maps_.channels()) {
    throw Error(fmt::format("{}: {} maps given, the representation has {}", method_,
                            maps.channels(), maps_.channels()));
  }
  if (maps.channel_names().empty()) maps.set_channel_names(maps_.channel_names());
  if (shading_) return Representation(method_, std::move(maps), shading_, std::move(details));
  return Representation(method_, std::move(maps), layout_, basis_, std::move(details));
}

namespace {

Image NormalImage(int width, int height) {
  return Image(width, height, std::vector<std::string>{"normal.X", "normal.Y", "normal.Z"});
}

void StoreNormal(Image& normals, std::size_t p, Eigen::Vector3d n) {
  const double norm = n.norm();
  n = norm > 0.0 ? (n / norm).eval() : Eigen::Vector3d::UnitZ();
  for (int c = 0; c < 3; ++c) normals.pixel(p)[c] = static_cast<float>(n[c]);
}

// Sum over output channels of gain_o * B_j,o: the luminance-like weight of basis term j.
double CombinedBasis(const Representation& r, PixelValues<const float> maps, int j) {
  const MapLayout& layout = r.layout();
  double sum = 0.0;
  for (int o = 0; o < layout.output_channels; ++o) {
    const double b = maps[j * layout.BasisMapsPerTerm() + (layout.basis_per_channel ? o : 0)];
    sum += layout.has_gain ? b * maps[layout.GainOffset() + o] : b;
  }
  return sum;
}

}  // namespace

std::optional<Image> EstimateNormals(const Representation& r) {
  if (const PixelShading* shading = r.shading()) {
    const std::optional<int> offset = shading->normal_offset();
    if (!offset) return std::nullopt;
    Image normals = NormalImage(r.width(), r.height());
    tbb::parallel_for(std::size_t{0}, normals.pixel_count(), [&](std::size_t p) {
      const auto maps = r.maps().pixel(p);
      const int n = *offset;
      StoreNormal(normals, p, Eigen::Vector3d(maps[n], maps[n + 1], maps[n + 2]));
    });
    return normals;
  }
  const std::optional<Eigen::MatrixXd> linear = r.basis().LinearInLight();
  const bool ptm = r.basis().kind() == "ptm";
  if (!linear && !ptm) return std::nullopt;
  Image normals = NormalImage(r.width(), r.height());
  const int k = r.layout().basis_size;
  tbb::parallel_for(std::size_t{0}, normals.pixel_count(), [&](std::size_t p) {
    const auto maps = r.maps().pixel(p);
    Eigen::VectorXd combined(k);
    for (int j = 0; j < k; ++j) combined[j] = CombinedBasis(r, maps, j);
    if (linear) {
      // i = sum_j c_j B_j = sum_j (A l)_j B_j = (A^T B) . l: the albedo-scaled normal is A^T B.
      StoreNormal(normals, p, linear->transpose() * combined);
      return;
    }
    // PTM (IMPLEMENTER CHOICE): for a Lambertian pixel L(u, v) = rho (nx u + ny v + nz w) with
    // w = sqrt(1 - u^2 - v^2) even in u and v, so the fit's linear terms are a3 = rho nx and
    // a4 = rho ny, while w is absorbed by the constant and square terms (a5 ~ rho nz). Hence
    // n = normalise(a3, a4, a5). Malzbender's luminance maximum (2001, eq. 16-17) lands at
    // (nx / nz, ny / nz) under the same model and breaks on non-concave fits: on DiLiGenT ball it
    // measured 48.5 degrees mean error against 3.5 for this estimate (least squares: 4.3).
    StoreNormal(normals, p, {combined[3], combined[4], combined[5]});
  });
  return normals;
}

}  // namespace photomat
