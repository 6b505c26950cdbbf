#include "represent/model/light_basis.h"

#include <fmt/format.h>

#include "core/error.h"
#include "core/json_file.h"
#include "represent/model/hsh.h"
#include "represent/model/light_profile_basis.h"

namespace photomat {

LinearLightBasis::LinearLightBasis(Eigen::MatrixXd matrix) : matrix_(std::move(matrix)) {
  if (matrix_.cols() != 3 || matrix_.rows() == 0 || !matrix_.allFinite()) {
    throw Error("a linear light basis needs a finite k x 3 matrix");
  }
}

nlohmann::json LinearLightBasis::ToJson() const {
  return {{"kind", "linear"}, {"matrix", MatrixToJson(matrix_)}};
}

Eigen::VectorXd PtmLightBasis::Coefficients(const LightDirection& light) const {
  const double u = light.x(), v = light.y();
  Eigen::VectorXd c(6);
  c << u * u, v * v, u * v, u, v, 1.0;
  return c;
}

Eigen::MatrixXd PtmTerms(const std::vector<LightDirection>& lights) {
  Eigen::MatrixXd terms(6, lights.size());
  const PtmLightBasis basis;
  for (std::size_t i = 0; i < lights.size(); ++i) terms.col(i) = basis.Coefficients(lights[i]);
  return terms;
}

InterpolatedLightBasis::InterpolatedLightBasis(std::vector<LightDirection> nodes,
                                               Eigen::MatrixXd values,
                                               std::optional<LightInterpolator::Scheme> scheme)
    : interpolator_(std::move(nodes), scheme), values_(std::move(values)) {
  if (values_.cols() != static_cast<Eigen::Index>(interpolator_.nodes().size()) ||
      values_.rows() == 0 || !values_.allFinite()) {
    throw Error(fmt::format("interpolated light basis: {}x{} values for {} lights", values_.rows(),
                            values_.cols(), interpolator_.nodes().size()));
  }
}

Eigen::VectorXd InterpolatedLightBasis::Coefficients(const LightDirection& light) const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(values_.rows());
  for (const auto& [node, weight] : interpolator_.Weights(light)) c += weight * values_.col(node);
  return c;
}

nlohmann::json InterpolatedLightBasis::ToJson() const {
  nlohmann::json nodes = nlohmann::json::array();
  for (const LightDirection& l : interpolator_.nodes()) nodes.push_back({l.x(), l.y(), l.z()});
  return {{"kind", "interpolated"},
          {"scheme", ToString(interpolator_.scheme())},
          {"lights", std::move(nodes)},
          {"values", MatrixToJson(values_.transpose())}};  // one row per light
}

std::shared_ptr<const LightBasis> LightBasisFromJson(const JsonReader& json) {
  const std::string kind = json["kind"].String();
  try {
    if (kind == "linear") {
      return std::make_shared<LinearLightBasis>(MatrixFromJson(json["matrix"], 3));
    }
    if (kind == "ptm") return std::make_shared<PtmLightBasis>();
    if (kind == "direction") return std::make_shared<DirectionLightBasis>();
    if (kind == "hsh") return std::make_shared<HshLightBasis>(json["terms"].Integer());
    if (kind == "rbf" || kind == "bilinear") {
      const JsonReader pca_json = json["pca"];
      if (pca_json.ArraySize() == 0) pca_json.Fail("empty matrix");
      const Eigen::MatrixXd pca =
          MatrixFromJson(pca_json, static_cast<Eigen::Index>(pca_json[0].ArraySize()));
      if (kind == "bilinear") {
        return std::make_shared<BilinearLightBasis>(json["grid_size"].Integer(), pca);
      }
      const Eigen::MatrixXd lights = MatrixFromJson(json["lights"], 3);
      std::vector<LightDirection> nodes;
      for (Eigen::Index i = 0; i < lights.rows(); ++i) {
        nodes.push_back(LightDirection::FromVector(lights.row(i).transpose()));
      }
      const RbfTail tail =
          json.Has("tail") ? RbfTailFromString(json["tail"].String()) : RbfTail::kAffine;
      return std::make_shared<RbfLightBasis>(
          RbfInterpolation(nodes, json["width_deg"].Number(), json["regularisation"].Number(),
                           tail),
          pca);
    }
    if (kind == "interpolated") {
      const Eigen::MatrixXd lights = MatrixFromJson(json["lights"], 3);
      std::vector<LightDirection> nodes;
      for (Eigen::Index i = 0; i < lights.rows(); ++i) {
        nodes.push_back(LightDirection::FromVector(lights.row(i).transpose()));
      }
      const JsonReader values_json = json["values"];
      if (values_json.ArraySize() == 0) values_json.Fail("empty matrix");
      const auto k = static_cast<Eigen::Index>(values_json[0].ArraySize());
      const Eigen::MatrixXd values = MatrixFromJson(values_json, k).transpose();
      std::optional<LightInterpolator::Scheme> scheme;
      if (json.Has("scheme")) {
        const std::string name = json["scheme"].String();
        if (name == "slant-rings")
          scheme = LightInterpolator::Scheme::kSlantRings;
        else if (name == "triangulation")
          scheme = LightInterpolator::Scheme::kTriangulation;
        else
          json["scheme"].Fail("expected \"slant-rings\" or \"triangulation\"");
      }
      return std::make_shared<InterpolatedLightBasis>(nodes, values, scheme);
    }
  } catch (const Error& error) {
    if (!error.file().empty()) throw;
    json.Fail(error.fault());
  }
  json["kind"].Fail(fmt::format("unknown light basis \"{}\"", kind));
}

}  // namespace photomat
