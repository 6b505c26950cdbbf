#pragma once

#include <Eigen/Core>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>
#include <vector>

#include "core/json_file.h"
#include "core/light_direction.h"
#include "represent/model/light_interpolation.h"

namespace photomat {

// The light half of a representation: the function from a light direction to the k coefficients
// c(l) that weight the representation's maps (thesis eq. 4.4.5, i = M1 c). It depends on the
// light set the representation was fitted from, never on pixels, so it is shared unchanged by a
// sample and everything synthesised from it.
class LightBasis {
 public:
  virtual ~LightBasis() = default;
  virtual std::string_view kind() const = 0;
  virtual int size() const = 0;
  virtual Eigen::VectorXd Coefficients(const LightDirection& light) const = 0;
  // If c(l) = A l for a fixed A (size x 3), A; lets normals be read off any such representation.
  virtual std::optional<Eigen::MatrixXd> LinearInLight() const { return std::nullopt; }
  // {"kind": ..., parameters}; read back by LightBasisFromJson.
  virtual nlohmann::json ToJson() const = 0;
};

// c = A l. Gradient uses A = identity (c = l); 3I uses A = L^-1 of its three lights.
class LinearLightBasis final : public LightBasis {
 public:
  explicit LinearLightBasis(Eigen::MatrixXd matrix);
  static std::shared_ptr<const LinearLightBasis> Lambertian() {
    return std::make_shared<LinearLightBasis>(Eigen::MatrixXd::Identity(3, 3));
  }
  std::string_view kind() const override { return "linear"; }
  int size() const override { return static_cast<int>(matrix_.rows()); }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override {
    return matrix_ * light.vector();
  }
  std::optional<Eigen::MatrixXd> LinearInLight() const override { return matrix_; }
  nlohmann::json ToJson() const override;

 private:
  Eigen::MatrixXd matrix_;
};

// Malzbender's biquadratic, in the thesis's order: (lx^2, ly^2, lx ly, lx, ly, 1). The same
// order as PTM files: a0 u^2 + a1 v^2 + a2 uv + a3 u + a4 v + a5.
class PtmLightBasis final : public LightBasis {
 public:
  std::string_view kind() const override { return "ptm"; }
  int size() const override { return 6; }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override;
  nlohmann::json ToJson() const override { return {{"kind", "ptm"}}; }
};

// c = l, the light direction itself: the input of a nonlinear per-pixel shading
// (represent/model/shading.h, the `pbr` method). Not LinearInLight: the output is not A l.
class DirectionLightBasis final : public LightBasis {
 public:
  std::string_view kind() const override { return "direction"; }
  int size() const override { return 3; }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override {
    return light.vector();
  }
  nlohmann::json ToJson() const override { return {{"kind", "direction"}}; }
};

// Coefficients known at the fitted lights (Eigen-k's M2 columns), interpolated in between
// (LightInterpolator, thesis eq. 4.4.16 and its generalisation to irregular sets).
class InterpolatedLightBasis final : public LightBasis {
 public:
  // `values` is size x nodes: column i holds the coefficients at nodes[i].
  InterpolatedLightBasis(std::vector<LightDirection> nodes, Eigen::MatrixXd values,
                         std::optional<LightInterpolator::Scheme> scheme = std::nullopt);
  std::string_view kind() const override { return "interpolated"; }
  int size() const override { return static_cast<int>(values_.rows()); }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override;
  nlohmann::json ToJson() const override;

  const LightInterpolator& interpolator() const { return interpolator_; }
  const Eigen::MatrixXd& values() const { return values_; }

 private:
  LightInterpolator interpolator_;
  Eigen::MatrixXd values_;
};

// Throws Error naming the reader's file and JSON path for unknown kinds or bad parameters.
std::shared_ptr<const LightBasis> LightBasisFromJson(const JsonReader& json);

// The PTM terms of each light as the columns of a 6 x n matrix (the thesis's L_ptm).
Eigen::MatrixXd PtmTerms(const std::vector<LightDirection>& lights);

}  // namespace photomat
