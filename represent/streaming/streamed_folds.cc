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

using streaming_internal::AllImages;
using streaming_internal::Band;
using streaming_internal::IsLightProfile;
using streaming_internal::NeedsGram;
using streaming_internal::Streamer;

void CheckStreamable(const StreamedSet& set, std::span<const Method> methods,
                     std::span<const PredictionFold> folds) {
  for (const Method& method : methods) {
    if (!StreamsRobustFolds(method)) throw Error(set.source(), NeuralIsTrainedApart());
    CheckFoldsFit(folds, method, set.source());
  }
}

// The fold bases of the Gram-based methods, by method index and fold: what the in-memory fold
// fit derives from the Gram matrix of the profiles it fits.
struct FoldBases {
  std::map<std::size_t, std::vector<EigenBasis>> eigen;
  std::map<std::size_t, std::vector<LightProfileModel>> profiles;
  // Robust Eigen-k: each EM iteration's basis, the start's first (RobustFit::FitEigen's).
  std::map<std::size_t, std::vector<std::vector<EigenBasis>>> robust_eigen;
};

// Least squares: the fold bases from the whole set's Gram matrix (the in-memory fold fit,
// FitObservations of the fold's images, takes its rows and columns). They are independent of
// each other (leave-one-out: one per image, each rbf or bilinear model choosing its own kernel
// width or smoothness), so they are made in parallel.
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

// One band's robust fit of one fold's images, as the in-memory robust fold fit makes it
// (RobustFit of the fold's images), its measured masks found on the band as captured.
class RobustFoldBand {
 public:
  RobustFoldBand(const StreamedSet& set, const Band& band, const PredictionFold& fold,
                 const RobustFitOptions& options)
      : observations_(*band.observations),
        fit_(observations_, set.lights(), fold.fitted, BandOptions(band, options), set.source()),
        columns_(AllImages(static_cast<int>(fold.fitted.size()))) {}

  // The fold's profiles with their distrusted samples imputed (RobustFit::EigenStart, one column
  // per fitted image), made once and shared by the fold's Gram-based methods.
  const Eigen::MatrixXf& Start() {
    if (!start_) start_ = fit_.EigenStart();
    return *start_;
  }
  // Robust Eigen-k's imputed matrix after one EM step with each of `bases`.
  Eigen::MatrixXf Imputed(std::span<const EigenBasis> bases) {
    Eigen::MatrixXf filled = Start();
    for (const EigenBasis& basis : bases) fit_.EigenImpute(filled, basis.v);
    return filled;
  }
  void AddTo(RowGram& gram, const Eigen::MatrixXf& profiles) const {
    gram.Add(profiles, observations_.pixel_indices(), observations_.width(),
             observations_.channels());
  }
  // Fold f's fit of methods[i] (its bases, for the Gram-based methods, in `bases`).
  Representation Fit(std::size_t i, const Method& method, const FoldBases& bases, std::size_t f) {
    if (IsLightProfile(method)) {
      return ProjectLightProfiles(bases.profiles.at(i)[f], observations_, Start(), columns_);
    }
    if (method.kind == Method::Kind::kEigen) {
      const std::span<const EigenBasis> iterations = bases.robust_eigen.at(i)[f];
      return fit_.EigenFromImputed(Imputed(iterations.first(iterations.size() - 1)),
                                   iterations.back());
    }
    return fit_.Fit(method);
  }

 private:
  static RobustFitOptions BandOptions(const Band& band, RobustFitOptions options) {
    options.measured = band.measured;
    options.progress = nullptr;
    return options;
  }

  const Observations& observations_;
  RobustFit fit_;
  std::vector<int> columns_;
  std::optional<Eigen::MatrixXf> start_;
};

std::vector<RowGram> FoldGrams(std::span<const PredictionFold> folds) {
  std::vector<RowGram> grams;
  for (const PredictionFold& fold : folds) {
    grams.emplace_back(static_cast<Eigen::Index>(fold.fitted.size()));
  }
  return grams;
}

// Robust: the in-memory robust fold fit of Eigen-k, rbf or bilinear imputes the fold's distrusted
// samples (RobustFit::EigenStart) and fits on the Gram matrix of the imputed profiles, and robust
// Eigen-k iterates (kRobustEigenIterations EM steps, each from the Gram matrix of the whole
// imputed matrix). Each sum is a streamed pass for every fold at once: the start's (every
// Gram-based method's first basis), then one per further EM iteration while Eigen-k is asked.
// Each pass makes every band's robust fold fits again, so memory stays a band's, at the cost of
// kRobustEigenIterations + 2 robust fits of every band and fold.
FoldBases MakeRobustFoldBases(const StreamedSet& set, std::span<const Method> methods,
                              std::span<const PredictionFold> folds, const RobustFitOptions& robust,
                              Streamer& streamer) {
  FoldBases bases;
  if (std::none_of(methods.begin(), methods.end(), NeedsGram)) return bases;
  std::vector<RowGram> start = FoldGrams(folds);
  streamer.Pass("predict: robust gram", [&](Band& band) {
    if (band.empty()) return;
    tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
      RobustFoldBand fold(set, band, folds[f], robust);
      fold.AddTo(start[f], fold.Start());
    });
  });
  nlohmann::json details = {{"robust", robust.ToJson()}};
  details["robust"]["measured_masks"] = true;  // found per band, as in memory for the whole set
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const Method& method = methods[i];
    if (!NeedsGram(method)) continue;
    const bool profile = IsLightProfile(method);
    if (profile) bases.profiles[i].resize(folds.size());
    if (!profile) bases.robust_eigen[i].resize(folds.size());
    tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
      const std::vector<int>& fitted = folds[f].fitted;
      if (profile) {
        bases.profiles[i][f] =
            FitLightProfileModel(start[f].gram(), start[f].column_sums(),
                                 SelectLights(set.lights(), fitted), method, set.source(), details);
        return;
      }
      bases.robust_eigen[i][f] = {EigenBasisFromGram(start[f].gram(), start[f].column_sums(),
                                                     AllImages(static_cast<int>(fitted.size())),
                                                     method.eigen_k, set.source())};
    });
  }
  for (int iteration = 1; !bases.robust_eigen.empty() && iteration <= kRobustEigenIterations;
       ++iteration) {
    std::map<std::size_t, std::vector<RowGram>> grams;
    for (const auto& entry : bases.robust_eigen) grams.emplace(entry.first, FoldGrams(folds));
    streamer.Pass(fmt::format("predict: robust eigen, EM {} of {}", iteration + 1,
                              kRobustEigenIterations + 1),
                  [&](Band& band) {
                    if (band.empty()) return;
                    tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
                      RobustFoldBand fold(set, band, folds[f], robust);
                      for (const auto& [i, per_fold] : bases.robust_eigen) {
                        fold.AddTo(grams.at(i)[f], fold.Imputed(per_fold[f]));
                      }
                    });
                  });
    for (auto& [i, per_fold] : bases.robust_eigen) {
      for (std::size_t f = 0; f < folds.size(); ++f) {
        const RowGram& gram = grams.at(i)[f];
        per_fold[f].push_back(EigenBasisFromGram(
            gram.gram(), gram.column_sums(), AllImages(static_cast<int>(folds[f].fitted.size())),
            methods[i].eigen_k, set.source()));
      }
    }
  }
  return bases;
}

}  // namespace

bool StreamsRobustFolds(const Method& method) { return method.kind != Method::Kind::kNeural; }

int VisitFoldFits(StreamedSet& set, std::span<const Method> methods,
                  std::span<const PredictionFold> folds,
                  const std::function<void(const FoldFit&)>& visit, const FoldFitOptions& options) {
  CheckStreamable(set, methods, folds);
  StreamedFitOptions streamed;
  streamed.progress = options.progress;
  streamed.robust = options.robust.has_value();
  // IMPLEMENTER CHOICE: a band holds as many folds' maps (and robust fits) as there are threads
  // fitting them.
  const int concurrent =
      std::min(static_cast<int>(folds.size()), tbb::this_task_arena::max_concurrency());
  streamed.band_rows = options.band_rows > 0
                           ? options.band_rows
                           : StreamedBandRows(options.memory_bytes > 0 ? options.memory_bytes
                                                                       : DefaultStreamedBudget(set),
                                              set, methods, streamed.robust, concurrent);
  // Robust bands carry their measured masks; each fold makes its own robust fit.
  Streamer streamer(set, methods, streamed, /*robust_fit_of_every_image=*/false);
  if (options.robust) {
    const FoldBases bases = MakeRobustFoldBases(set, methods, folds, *options.robust, streamer);
    // Each fold's robust fit of a band is made once for all the methods.
    streamer.Pass("predict: folds", [&](Band& band) {
      if (band.empty()) return;
      tbb::parallel_for(std::size_t{0}, folds.size(), [&](std::size_t f) {
        RobustFoldBand fold(set, band, folds[f], *options.robust);
        for (std::size_t i = 0; i < methods.size(); ++i) {
          visit(FoldFit{i, f, band.first, fold.Fit(i, methods[i], bases, f), *band.observations});
        }
      });
    });
    return streamer.band_rows();
  }
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
          return FitObservations(observations, set.lights(), method, fitted, set.source());
        }();
        visit(FoldFit{i, f, band.first, fit, observations});
      });
    }
  });
  return streamer.band_rows();
}

}  // namespace photomat
