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

StreamedFitReport FitStreamed(StreamedSet& set, std::span<const Method> methods,
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
  Streamer streamer(set, methods, options);
  const int n = set.size();
  const fs::path& source = set.source();
  const bool needs_gram = std::any_of(methods.begin(), methods.end(), NeedsGram);
  RowGram start_gram(n);
  if (needs_gram) {
    streamer.Pass("fit: gram", [&](Band& band) {
      if (band.empty()) return;
      const Observations& o = *band.observations;
      start_gram.Add(band.StartProfiles(), o.pixel_indices(), o.width(), o.channels());
    });
  }
  // The rbf and bilinear models, by method index: from the Gram pass alone.
  std::map<std::size_t, LightProfileModel> profiles;
  nlohmann::json profile_details = nlohmann::json::object();
  if (options.robust) {
    profile_details["robust"] = options.robust_options.ToJson();
    profile_details["robust"]["measured_masks"] = true;  // found per band (StreamedFitOptions)
  }
  for (std::size_t i = 0; i < methods.size(); ++i) {
    if (!IsLightProfile(methods[i])) continue;
    profiles.emplace(i, FitLightProfileModel(start_gram.gram(), start_gram.column_sums(),
                                             set.lights(), methods[i], source, profile_details));
  }
  // The Eigen-k bases, by k: least squares from the Gram pass; robust: the Gram pass gives the
  // first EM iteration's, and one pass more makes each further iteration's.
  std::map<int, EigenBasis> eigen;
  std::map<int, std::vector<EigenBasis>> robust_eigen;  // per k, the basis of each iteration
  for (const Method& method : methods) {
    if (method.kind != Method::Kind::kEigen) continue;
    const EigenBasis basis = EigenBasisFromGram(start_gram.gram(), start_gram.column_sums(),
                                                streamer.all(), method.eigen_k, source);
    if (options.robust) {
      robust_eigen[method.eigen_k] = {basis};
    } else {
      eigen[method.eigen_k] = basis;
    }
  }
  for (int iteration = 1; !robust_eigen.empty() && iteration <= kRobustEigenIterations;
       ++iteration) {
    std::map<int, RowGram> grams;
    for (const auto& entry : robust_eigen) grams.emplace(entry.first, RowGram(n));
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
          EigenBasisFromGram(gram.gram(), gram.column_sums(), streamer.all(), k, source));
    }
  }

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
      const Method& method = methods[i];
      const auto representation = [&]() -> Representation {
        if (IsLightProfile(method)) {
          return ProjectLightProfiles(profiles.at(i), *band.observations, band.StartProfiles(),
                                      streamer.all());
        }
        if (method.kind == Method::Kind::kEigen) {
          if (!band.robust) {
            return FitEigenWithBasis(*band.observations, set.lights(), streamer.all(),
                                     eigen.at(method.eigen_k));
          }
          const std::vector<EigenBasis>& bases = robust_eigen.at(method.eigen_k);
          Eigen::MatrixXf filled = band.StartProfiles();
          for (std::size_t t = 0; t + 1 < bases.size(); ++t) {
            band.robust->EigenImpute(filled, bases[t].v);
          }
          return band.robust->EigenFromImputed(filled, bases.back());
        }
        if (band.robust) return band.robust->Fit(method);
        return FitObservations(*band.observations, set.lights(), method, streamer.all(), source);
      }();
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
