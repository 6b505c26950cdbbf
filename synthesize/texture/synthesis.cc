#include "synthesize/texture/synthesis.h"

#include <fmt/format.h>

#include <array>

#include "core/enum_names.h"
#include "core/error.h"

namespace photomat {
namespace {

nlohmann::json MatchingJson(const MatchingOptions& matching) {
  return {{"metric", ToString(matching.metric)},
          {"scaling", ToString(matching.scaling)},
          {"weights", matching.weights}};
}

nlohmann::json Describe(const Image& guide, const SynthesisOptions& options,
                        const SynthesisPlan& plan) {
  nlohmann::json description = {
      {"method", ToString(options.method)}, {"width", options.target.width},
      {"height", options.target.height},    {"tileable", options.target.tileable},
      {"seed", options.target.seed},        {"sample_width", guide.width()},
      {"sample_height", guide.height()}};
  if (plan.placement) {
    const QuiltOptions& quilt = options.quilt;
    int searched = 0, continued = 0;
    for (const PlacedBlock& block : plan.placement->blocks) {
      searched += block.choice == PlacedBlock::Choice::kSearch;
      continued += block.choice == PlacedBlock::Choice::kCoherence;
    }
    description["quilt"] = {{"block", plan.placement->block_size},
                            {"overlap", plan.placement->overlap},
                            {"tolerance", quilt.tolerance},
                            {"error_floor", quilt.error_floor},
                            {"candidate_stride", quilt.candidate_stride},
                            {"coherence", quilt.coherence},
                            {"forced_search_rate", quilt.forced_search_rate},
                            {"search", ToString(quilt.search)},
                            {"matching", MatchingJson(quilt.matching)},
                            {"blocks", plan.placement->blocks.size()},
                            {"searched_blocks", searched},
                            {"continued_blocks", continued}};
  } else {
    const PixelSynthesisOptions& pixel = options.pixel;
    description["pixel"] = {{"levels", pixel.levels},
                            {"neighbourhood", pixel.neighbourhood},
                            {"parent_neighbourhood", pixel.parent_neighbourhood},
                            {"forced_search_rate", pixel.forced_search_rate},
                            {"search", ToString(pixel.search)},
                            {"matching", MatchingJson(pixel.matching)}};
  }
  return description;
}

constexpr std::array<NamedValue<SynthesisMethod>, 2> kMethodNames = {
    {{SynthesisMethod::kQuilt, "quilt"}, {SynthesisMethod::kPixel, "pixel"}}};

}  // namespace

std::string_view ToString(SynthesisMethod method) { return NameOf(method, kMethodNames); }

SynthesisMethod ParseSynthesisMethod(std::string_view name) {
  return ValueNamed(name, kMethodNames, "synthesis method");
}

SynthesisPlan PlanSynthesis(const Image& guide, const SynthesisOptions& options,
                            Progress* progress) {
  SynthesisPlan plan;
  if (options.method == SynthesisMethod::kQuilt) {
    plan.placement = PlanQuilt(guide, options.target, options.quilt, progress);
    plan.source_map = plan.placement->RenderSourceMap();
  } else {
    plan.source_map = PlanPixelSynthesis(guide, options.target, options.pixel, progress);
  }
  plan.description = Describe(guide, options, plan);
  return plan;
}

Representation ApplySourceMap(const Representation& representation, const SourceMap& map,
                              const nlohmann::json& description) {
  nlohmann::json details = representation.details();
  if (!details.is_object()) details = nlohmann::json::object();
  details["synthesis"] = description;
  return representation.WithMapsAndDetails(map.Apply(representation.maps()), std::move(details));
}

Representation Synthesize(const Representation& representation, const SynthesisOptions& options,
                          Progress* progress, const Image* guide) {
  const Image& planned_on = guide ? *guide : representation.maps();
  if (planned_on.width() != representation.width() ||
      planned_on.height() != representation.height()) {
    throw Error(fmt::format("the guide is {}x{} but the maps are {}x{}", planned_on.width(),
                            planned_on.height(), representation.width(), representation.height()));
  }
  const SynthesisPlan plan = PlanSynthesis(planned_on, options, progress);
  return ApplySourceMap(representation, plan.source_map, plan.description);
}

}  // namespace photomat
