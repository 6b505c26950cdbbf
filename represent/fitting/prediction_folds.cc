#include "represent/fitting/prediction_folds.h"

#include <fmt/format.h>

#include "core/error.h"

namespace photomat {

std::vector<PredictionFold> PredictionFolds(int images, int hold_out_every) {
  std::vector<PredictionFold> folds;
  if (hold_out_every > 0) {
    PredictionFold& fold = folds.emplace_back();
    for (int i = 0; i < images; ++i) {
      (i % hold_out_every == 0 ? fold.predicted : fold.fitted).push_back(i);
    }
    return folds;
  }
  for (int k = 0; k < images; ++k) {
    PredictionFold& fold = folds.emplace_back();
    fold.predicted = {k};
    for (int i = 0; i < images; ++i) {
      if (i != k) fold.fitted.push_back(i);
    }
  }
  return folds;
}

void CheckFoldsFit(std::span<const PredictionFold> folds, const Method& method,
                   const std::filesystem::path& source) {
  for (const PredictionFold& fold : folds) {
    if (static_cast<int>(fold.fitted.size()) < method.MinimumImages()) {
      throw Error(source, fmt::format("a prediction fold fits {} images; {} needs {}",
                                      fold.fitted.size(), method.Name(), method.MinimumImages()));
    }
  }
}

}  // namespace photomat
