#include "represent/streaming/streamed_folds.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <map>

#include "core/error.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/light_profile_fit.h"
#include "represent/streaming/band_streamer.h"
#include "represent/streaming/streamed_fit.h"

namespace photomat {
namespace {

using streaming_internal::Band;
using streaming_internal::IsLightProfile;
using streaming_internal::NeedsGram;
using streaming_internal::Streamer;

void CheckStreamable(const StreamedSet& set, std::span<const Method> methods,
                     std::span<const PredictionFold> folds, bool robust) {
  for (const Method& method : methods) {
    if (method.kind == Method::Kind::kNeural) throw Error(set.source(), NeuralIsTrainedApart());
    if (robust && !StreamsRobustFolds(method)) {
      throw Error(set.source(),
                  fmt::format("robust {}'s prediction folds are not streamed (each fold's fit "
                              "imputes over the whole set: evaluate it in memory)",
                              method.Name()));
    }
    CheckFoldsFit(folds, method, set.source());
  }
}

// The fold bases of the Gram-based methods, by method and fold: what the in-memory fold fit
// (FitObservations from the fold's images) derives from the whole set's Gram matrix.
struct FoldBases {
  std::map<std::size_t, std::vector<EigenBasis>> eigen;
  std::map<std::size_t, std::vector<LightProfileModel>> profiles;
};

// The fold bases are independent of each other (leave-one-out: one per image, each rbf or bilinear
// model choosing its own kernel width or smoothness), so they are made in parallel.
FoldBases MakeFoldBases(const StreamedSet& set, std::span<const Method> methods,
                        std::span<const PredictionFold> folds, const RowGram& gram) {
  FoldBases bases;
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const Method& method = methods[i];
    if (!NeedsGram(method)) continue;
    if (IsLightProfile(method)) {
      std::vector<LightProfileModel>& models = bases.profiles[i];
      models.resize(folds.size());
      tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
        models[f] = FitLightProfileModel(gram.gram(), gram.column_sums(), set.lights(),
                                         folds[f].fitted, method, set.source());
      });
    } else {
      std::vector<EigenBasis>& eigen = bases.eigen[i];
      eigen.resize(folds.size());
      tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
        eigen[f] = EigenBasisFromGram(gram.gram(), gram.column_sums(), folds[f].fitted,
                                      method.eigen_k, set.source());
      });
    }
  }
  return bases;
}

}  // namespace

bool StreamsRobustFolds(const Method& method) {
  return !RobustFitImputesOverTheSet(method) && method.kind != Method::Kind::kNeural;
}

int VisitFoldFits(StreamedSet& set, std::span<const Method> methods,
                  std::span<const PredictionFold> folds,
                  const std::function<void(const FoldFit&)>& visit, const FoldFitOptions& options) {
  CheckStreamable(set, methods, folds, options.robust.has_value());
  StreamedFitOptions streamed;
  streamed.progress = options.progress;
  streamed.robust = options.robust.has_value();
  // IMPLEMENTER CHOICE: a band holds as many folds' maps as there are threads fitting them.
  const int concurrent =
      std::min(static_cast<int>(folds.size()), tbb::this_task_arena::max_concurrency());
  streamed.band_rows = options.band_rows > 0
                           ? options.band_rows
                           : StreamedBandRows(options.memory_bytes > 0 ? options.memory_bytes
                                                                       : DefaultStreamedBudget(set),
                                              set, methods, streamed.robust, concurrent);
  // Robust bands carry their measured masks; each fold makes its own robust fit.
  Streamer streamer(set, methods, streamed, /*robust_fit_of_every_image=*/false);
  RowGram gram(set.size());
  if (std::any_of(methods.begin(), methods.end(), NeedsGram)) {
    streamer.Pass("predict: gram", [&](Band& band) {
      if (band.empty()) return;
      const Observations& o = *band.observations;
      gram.Add(o.matrix(), o.pixel_indices(), o.width(), o.channels());
    });
  }
  const FoldBases bases = MakeFoldBases(set, methods, folds, gram);
  streamer.Pass("predict: folds", [&](Band& band) {
    if (band.empty()) return;
    const Observations& observations = *band.observations;
    for (std::size_t i = 0; i < methods.size(); ++i) {
      const Method& method = methods[i];
      tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
        const std::vector<int>& fitted = folds[f].fitted;
        const Representation fit = [&] {
          if (IsLightProfile(method)) {
            return ProjectLightProfiles(bases.profiles.at(i)[f], observations,
                                        observations.matrix(), fitted);
          }
          if (method.kind == Method::Kind::kEigen) {
            return FitEigenWithBasis(observations, set.lights(), fitted, bases.eigen.at(i)[f]);
          }
          if (options.robust) {
            RobustFitOptions robust = *options.robust;
            robust.measured = band.measured;
            robust.progress = nullptr;
            return RobustFit(observations, set.lights(), fitted, robust, set.source()).Fit(method);
          }
          return FitObservations(observations, set.lights(), method, fitted, set.source());
        }();
        visit(FoldFit{i, f, band.first, fit, observations});
      });
    }
  });
  return streamer.band_rows();
}

}  // namespace photomat
