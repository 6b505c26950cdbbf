#include "represent/fitting/pbr_fit_summary.h"

#include <algorithm>

namespace photomat {

void PbrFitSummary::Add(const PbrFitSummary& other) {
  pixels += other.pixels;
  lobe_sampled += other.lobe_sampled;
  lobe_unsampled += other.lobe_unsampled;
  regularised += other.regularised;
  total_cost += other.total_cost;
}

nlohmann::json PbrFitSummary::ToJson() const {
  return {{"pixels", pixels},
          {"lobe_sampled", lobe_sampled},
          {"lobe_unsampled", lobe_unsampled},
          {"regularised", regularised},
          {"mean_final_cost", total_cost / std::max<double>(1.0, static_cast<double>(pixels))}};
}

PbrFitSummary PbrFitSummary::FromJson(const nlohmann::json& json) {
  PbrFitSummary summary;
  summary.pixels = json.at("pixels").get<std::size_t>();
  summary.lobe_sampled = json.at("lobe_sampled").get<std::size_t>();
  summary.lobe_unsampled = json.at("lobe_unsampled").get<std::size_t>();
  summary.regularised = json.at("regularised").get<std::size_t>();
  summary.total_cost =
      json.at("mean_final_cost").get<double>() * static_cast<double>(summary.pixels);
  return summary;
}

}  // namespace photomat
