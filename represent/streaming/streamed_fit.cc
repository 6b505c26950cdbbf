#include "represent/streaming/streamed_fit.h"

#include <fmt/format.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <map>
#include <memory>

#include "core/disk_space.h"
#include "core/error.h"
#include "core/memory_limits.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/light_profile_fit.h"
#include "represent/fitting/observations.h"
#include "represent/streaming/band_streamer.h"
#include "represent/streaming/fitted_stack_writer.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using streaming_internal::Band;
using streaming_internal::IsLightProfile;
using streaming_internal::NeedsGram;
using streaming_internal::Streamer;

// Fixed: every decoder's chunk (16 rows of up to 4-byte samples, alpha included).
std::size_t DecoderChunkBytes(const StreamedSet& set) {
  return static_cast<std::size_t>(set.size()) * 16 * static_cast<std::size_t>(set.width()) *
         static_cast<std::size_t>(set.channels() + 1) * 4;
}

}  // namespace

std::size_t DefaultStreamedBudget(const StreamedSet& set) {
  return DefaultBandBudget(kMinimumFitMemory, DecoderChunkBytes(set));
}

std::size_t DefaultFitMemory() { return DefaultMemoryBudget(kMinimumFitMemory); }

int StreamedBandRows(std::size_t memory_bytes, const StreamedSet& set,
                     std::span<const Method> methods, bool robust, int concurrent_fits) {
  const auto n = static_cast<std::size_t>(set.size());
  const auto channels = static_cast<std::size_t>(set.channels());
  const auto width = static_cast<std::size_t>(set.width());
  // Per pixel of a band: the image data matrix (4 bytes per sample), which least squares
  // decodes straight into (Streamer::ReadLeastSquaresBand), but a robust fit decodes into band
  // images first and copies (4 + 4), and keeps the measured masks (1 per image). Two bands are
  // held at once (the next one is decoded while this one is fitted: Streamer::Pass). Each robust
  // fit: the weights (4 per image) and, for Eigen-k, rbf and bilinear, the imputed matrix and its
  // products (8 per sample); one per band held (FitStreamed) or per concurrent fold fit. One
  // method's maps at a time (per concurrent fit), with the fit's products and the writer's
  // interleaved copy (12 bytes per map). A masked least-squares fit adds each decoding thread's
  // scratch band (4 bytes per channel; only the band being read has them).
  int planes = 0;
  bool imputed = false;
  for (const Method& method : methods) {
    planes = std::max(planes, StackMapCount(method, set.size(), set.channels()));
    imputed |= NeedsGram(method);
  }
  const std::size_t per_band_pixel = n * channels * (robust ? 8 : 4) + (robust ? n : 0);
  const std::size_t per_robust_fit = robust ? n * 4 + (imputed ? n * channels * 8 : 0) : 0;
  const std::size_t robust_fits = static_cast<std::size_t>(std::max(concurrent_fits, 2));
  const std::size_t scratch =
      !robust && set.masked()
          ? static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()) * channels * 4
          : 0;
  const std::size_t per_pixel = 2 * per_band_pixel + robust_fits * per_robust_fit +
                                static_cast<std::size_t>(planes) * 12 *
                                    static_cast<std::size_t>(std::max(concurrent_fits, 1)) +
                                scratch;
  const std::size_t fixed = DecoderChunkBytes(set);
  const std::size_t room = memory_bytes > fixed ? memory_bytes - fixed : 0;
  return RowsWithinBytes(room, per_pixel * width, set.height());
}

namespace {

void CheckFitRequest(const StreamedSet& set, std::span<const Method> methods,
                     std::span<const fs::path> stacks, const StreamedFitOptions& options) {
  if (methods.size() != stacks.size()) {
    throw Error(set.source(),
                fmt::format("{} methods but {} stack files", methods.size(), stacks.size()));
  }
  for (const Method& method : methods) {
    if (method.kind == Method::Kind::kNeural) throw Error(set.source(), NeuralIsTrainedApart());
    if (set.size() < method.MinimumImages()) {
      throw Error(set.source(), fmt::format("{} needs at least {} images; the set has {}",
                                            method.Name(), method.MinimumImages(), set.size()));
    }
  }
  if (options.encoded_values && options.robust) {
    throw Error(set.source(), "robust fits are of linear values, not of sRGB-encoded ones");
  }
}

// What the methods with a global sum take from whole passes over the set before the maps.
struct GlobalModels {
  // The rbf and bilinear models, by method index: from the Gram pass alone.
  std::map<std::size_t, LightProfileModel> profiles;
  // The Eigen-k bases, by k: least squares from the Gram pass.
  std::map<int, EigenBasis> eigen;
  // Robust Eigen-k, per k: the basis of each EM iteration (the Gram pass gives the first).
  std::map<int, std::vector<EigenBasis>> robust_eigen;
};

// The robust Eigen-k bases' further EM iterations: one pass each, every k's Gram matrix of the
// profiles imputed with the bases so far.
void IterateRobustEigen(Streamer& streamer, const StreamedSet& set,
                        std::map<int, std::vector<EigenBasis>>& robust_eigen) {
  for (int iteration = 1; !robust_eigen.empty() && iteration <= kRobustEigenIterations;
       ++iteration) {
    std::map<int, RowGram> grams;
    for (const auto& entry : robust_eigen) grams.emplace(entry.first, RowGram(set.size()));
    streamer.Pass(
        fmt::format("fit: robust eigen, EM {} of {}", iteration + 1, kRobustEigenIterations + 1),
        [&](Band& band) {
          if (band.empty()) return;
          const Observations& o = *band.observations;
          for (auto& [k, bases] : robust_eigen) {
            Eigen::MatrixXf filled = band.StartProfiles();
            for (const EigenBasis& basis : bases) band.robust->EigenImpute(filled, basis.v);
            grams.at(k).Add(filled, o.pixel_indices(), o.width(), o.channels());
          }
        });
    for (auto& [k, bases] : robust_eigen) {
      const RowGram& gram = grams.at(k);
      bases.push_back(
          EigenBasisFromGram(gram.gram(), gram.column_sums(), streamer.all(), k, set.source()));
    }
  }
}

// The Gram pass (when a method needs it) and the models made from it.
GlobalModels FitGlobalModels(Streamer& streamer, const StreamedSet& set,
                             std::span<const Method> methods, const StreamedFitOptions& options) {
  GlobalModels models;
  if (!std::any_of(methods.begin(), methods.end(), NeedsGram)) return models;
  RowGram start_gram(set.size());
  streamer.Pass("fit: gram", [&](Band& band) {
    if (band.empty()) return;
    const Observations& o = *band.observations;
    start_gram.Add(band.StartProfiles(), o.pixel_indices(), o.width(), o.channels());
  });
  nlohmann::json profile_details = nlohmann::json::object();
  if (options.robust) {
    profile_details["robust"] = options.robust_options.ToJson();
    profile_details["robust"]["measured_masks"] = true;  // found per band (StreamedFitOptions)
  }
  for (std::size_t i = 0; i < methods.size(); ++i) {
    const Method& method = methods[i];
    if (IsLightProfile(method)) {
      models.profiles.emplace(
          i, FitLightProfileModel(start_gram.gram(), start_gram.column_sums(), set.lights(), method,
                                  set.source(), profile_details));
    } else if (method.kind == Method::Kind::kEigen) {
      const EigenBasis basis = EigenBasisFromGram(start_gram.gram(), start_gram.column_sums(),
                                                  streamer.all(), method.eigen_k, set.source());
      if (options.robust) {
        models.robust_eigen[method.eigen_k] = {basis};
      } else {
        models.eigen[method.eigen_k] = basis;
      }
    }
  }
  IterateRobustEigen(streamer, set, models.robust_eigen);
  return models;
}

// Method `index`'s fit of one band.
Representation FitBand(Band& band, std::size_t index, std::span<const Method> methods,
                       const GlobalModels& models, const StreamedSet& set,
                       const Streamer& streamer) {
  const Method& method = methods[index];
  if (IsLightProfile(method)) {
    return ProjectLightProfiles(models.profiles.at(index), *band.observations, band.StartProfiles(),
                                streamer.all());
  }
  if (method.kind == Method::Kind::kEigen) {
    if (!band.robust) {
      return FitEigenWithBasis(*band.observations, set.lights(), streamer.all(),
                               models.eigen.at(method.eigen_k));
    }
    const std::vector<EigenBasis>& bases = models.robust_eigen.at(method.eigen_k);
    Eigen::MatrixXf filled = band.StartProfiles();
    for (std::size_t t = 0; t + 1 < bases.size(); ++t) {
      band.robust->EigenImpute(filled, bases[t].v);
    }
    return band.robust->EigenFromImputed(filled, bases.back());
  }
  if (band.robust) return band.robust->Fit(method);
  return FitObservations(*band.observations, set.lights(), method, streamer.all(), set.source());
}

}  // namespace

StreamedFitReport FitStreamed(StreamedSet& set, std::span<const Method> methods,
                              std::span<const fs::path> stacks, const StreamedFitOptions& options) {
  CheckFitRequest(set, methods, stacks, options);
  Streamer streamer(set, methods, options);
  const GlobalModels models = FitGlobalModels(streamer, set, methods, options);
  std::vector<std::unique_ptr<FittedStackWriter>> outputs;
  for (const fs::path& path : stacks) {
    outputs.push_back(std::make_unique<FittedStackWriter>(path, set.width(), set.height(),
                                                          options.compression, options.provenance));
  }
  StreamedFitReport report;
  RobustFitSummary summary;
  streamer.Pass("fit: maps", [&](Band& band) {
    if (band.empty()) return;  // zero maps (FittedStackWriter)
    if (band.robust) summary.Add(band.robust->summary());
    for (std::size_t i = 0; i < methods.size(); ++i) {
      const Representation representation = FitBand(band, i, methods, models, set, streamer);
      if (const auto found = representation.details().find("pbr_summary");
          found != representation.details().end()) {
        if (!report.pbr_summary) report.pbr_summary.emplace();
        report.pbr_summary->Add(PbrFitSummary::FromJson(*found));
      }
      outputs[i]->Write(band.first, representation);
    }
  });
  if (options.robust) report.robust_summary = summary;
  for (auto& output : outputs) output->Commit();
  report.band_rows = streamer.band_rows();
  report.passes = streamer.passes();
  for (const auto& output : outputs) report.map_counts.push_back(output->maps());
  report.saturated_pixels = set.SaturatedPixels();
  return report;
}

std::size_t StreamedStackBytes(const StreamedSet& set, std::span<const Method> methods) {
  std::size_t bytes = 0;
  for (const Method& method : methods) {
    bytes += ImageFileBytes(set.width(), set.height(),
                            StackMapCount(method, set.size(), set.channels()), 4);
  }
  return bytes;
}

}  // namespace photomat
