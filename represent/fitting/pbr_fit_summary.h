#pragma once

#include <cstddef>
#include <nlohmann/json.hpp>

namespace photomat {

// What a pbr fit (pbr_fit.h) found over its pixels: "pbr_summary" in its details. Counts add, so
// a streamed fit sums its bands' summaries into the whole set's (represent/streaming).
struct PbrFitSummary {
  std::size_t pixels = 0;
  std::size_t lobe_sampled = 0;    // some measured light inside the fitted lobe's half maximum
  std::size_t lobe_unsampled = 0;  // none: roughness and F0 undetermined
  std::size_t regularised = 0;     // unsampled and refitted towards the prior
  double total_cost = 0.0;         // sum of the pixels' final Cauchy costs

  void Add(const PbrFitSummary& other);
  // The counts above and mean_final_cost (total_cost / pixels).
  nlohmann::json ToJson() const;
  // From ToJson's object; throws nlohmann::json's errors on another.
  static PbrFitSummary FromJson(const nlohmann::json& json);
};

}  // namespace photomat
