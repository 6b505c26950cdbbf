// photomat solid: solid textures from 2D views (Dischler et al. 1998), grown from a solid exemplar
// under frame-field control (Su 2008), and procedural exemplars; `carve` is in
// solid_carve_command.cc (it needs meshes too).
#include "apps/solid_command.h"

#include <fmt/format.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <optional>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#ifdef PHOTOMAT_WITH_CARVING
#include "apps/solid_carve_command.h"
#endif
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/progress.h"
#include "synthesize/solid/exemplar_solid.h"
#include "synthesize/solid/frame_field.h"
#include "synthesize/solid/procedural_exemplars.h"
#include "synthesize/solid/solid_quality.h"
#include "synthesize/solid/spectral_solid.h"
#include "synthesize/volume/volume_io.h"

namespace photomat::app {

std::unique_ptr<tbb::global_control> LimitThreads(int threads) {
  if (threads <= 0) return nullptr;
  return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                               static_cast<std::size_t>(threads));
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

namespace {

constexpr std::string_view kCarveDescription =
    "Carve a mesh out of a solid texture: every vertex takes the volume's value where the mesh "
    "sits in it (its bounding box centred in the volume, longest side across it). Writes "
    "carved.ply and carved.glb (per-vertex colours), vertex_values.csv (every channel), "
    "preview_{front,right,back,left,top}.png and carve.json.";

void WriteOutputs(const std::filesystem::path& out, const std::filesystem::path& slices,
                  const Image& volume) {
  WriteVolume(out, volume);
  fmt::print("wrote a {} solid of {} channels to {}\n", ToString(volume.extent()),
             volume.channels(), out.string());
  if (!slices.empty()) {
    const bool colour = volume.FindChannel("R") >= 0 || volume.channels() <= 3;
    SliceDisplay display;
    display.normalise = !colour;
    WriteCentralSlices(slices, "", volume, display);
    fmt::print("wrote the central xy, xz, yz slices to {}\n", slices.string());
  }
}

// --- from-views ---

struct FromViewsCommandOptions {
  std::string xy, xz, yz, all;
  std::string xy_transform = "none", xz_transform = "none", yz_transform = "none";
  std::string order = "xy,xz,yz";
  SpectralSolidOptions spectral;
  bool parallel_update = false;
  std::filesystem::path out, slices, report;
  int threads = 0;
};

void AddFromViewsOptions(CLI::App& command, FromViewsCommandOptions& options) {
  command.add_option("--xy", options.xy, "View of the xy slices (image file)");
  command.add_option("--xz", options.xz, "View of the xz slices");
  command.add_option("--yz", options.yz, "View of the yz slices");
  command.add_option("--view", options.all,
                     "One view for all three orientations (an isotropic material)");
  for (auto [name, target] : {std::pair{"--xy-transform", &options.xy_transform},
                              std::pair{"--xz-transform", &options.xz_transform},
                              std::pair{"--yz-transform", &options.yz_transform}}) {
    command
        .add_option(name, *target,
                    "Turn that view first: none, transpose, rotate90, rotate180, rotate270, "
                    "flipx, flipy")
        ->capture_default_str();
  }
  command.add_option("--size", options.spectral.size, "Block side N")->capture_default_str();
  command.add_option("--iterations", options.spectral.iterations, "Relaxation iterations")
      ->capture_default_str();
  command.add_option("--crops", options.spectral.crops, "Sub-models q per view")
      ->capture_default_str();
  command
      .add_option("--crop-size", options.spectral.crop_size,
                  "Sub-model side (0: N, or half the view when it is smaller than 2N)")
      ->capture_default_str();
  command.add_option("--regions", options.spectral.regions, "Energy regions z")
      ->capture_default_str();
  command.add_option("--order", options.order, "Orientation order of each iteration")
      ->capture_default_str();
  command.add_flag("--parallel-update", options.parallel_update,
                   "Update all orientations from the same old block (the 1996 method) instead "
                   "of slice after slice");
  command.add_option("--seed", options.spectral.seed, "Seed of the initial noise")
      ->capture_default_str();
  command.add_option("--out", options.out, "Output volume: FILE.vdb or a folder (EXR slices)")
      ->required();
  command.add_option("--slices", options.slices, "Folder for PNG pictures of central slices");
  command.add_option("--report", options.report,
                     "JSON file: convergence and per-orientation fit after each iteration");
  command.add_option("--threads", options.threads, "Threads (0: all; same result any count)")
      ->capture_default_str();
}

// The views given, each turned as asked; --view gives all three orientations.
std::vector<SolidView> ViewsOf(const FromViewsCommandOptions& options) {
  std::vector<SolidView> views;
  const auto add = [&](const std::string& file, SlicePlane plane, const std::string& transform) {
    if (file.empty()) return;
    const auto parsed = ParseViewTransform(transform);
    if (!parsed) throw Error(fmt::format("unknown view transform \"{}\"", transform));
    views.push_back({plane, ApplyViewTransform(ReadImage(file).image, *parsed)});
  };
  const bool one_view = !options.all.empty();
  if (one_view && (!options.xy.empty() || !options.xz.empty() || !options.yz.empty())) {
    throw Error("--view sets all three orientations; do not combine it with --xy/--xz/--yz");
  }
  add(one_view ? options.all : options.xy, SlicePlane::kXY, options.xy_transform);
  add(one_view ? options.all : options.xz, SlicePlane::kXZ, options.xz_transform);
  add(one_view ? options.all : options.yz, SlicePlane::kYZ, options.yz_transform);
  if (views.empty()) throw Error("give at least one view (--xy, --xz, --yz or --view)");
  return views;
}

// The spectral synthesis's options, with --order's orientation order.
SpectralSolidOptions SpectralOptionsOf(const FromViewsCommandOptions& options) {
  SpectralSolidOptions spectral = options.spectral;
  spectral.order.clear();
  std::string_view rest = options.order;
  while (!rest.empty()) {
    const std::size_t comma = rest.find(',');
    const auto plane = ParseSlicePlane(rest.substr(0, comma));
    if (!plane) throw Error(fmt::format("--order: \"{}\" is not xy, xz or yz", options.order));
    spectral.order.push_back(*plane);
    rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
  }
  spectral.sequential = !options.parallel_update;
  spectral.measure_every_iteration = !options.report.empty();
  return spectral;
}

void PrintSpectralFits(const SpectralSolidResult& result) {
  for (const IterationReport& iteration : result.iterations) {
    fmt::print("iteration {}: relative change {:.4f}\n", iteration.iteration,
               iteration.relative_change);
  }
  for (const PlaneFit& fit : result.iterations.back().fits) {
    fmt::print(
        "{}: slice histogram L1 {:.3f} (worst {:.3f}), amplitudes inside the view's "
        "range {:.1f} % (slice mean {:.1f} %), {:.2f} dB from its mean spectrum\n",
        ToString(fit.plane), fit.histogram_l1_mean, fit.histogram_l1_max, 100 * fit.inside_bounds,
        100 * fit.inside_bounds_average, fit.log_spectral_distance_db);
  }
}

// --report: convergence and each orientation's fit after every iteration.
void WriteSpectralReport(const std::filesystem::path& path, const SpectralSolidOptions& spectral,
                         const SpectralSolidResult& result, double seconds) {
  nlohmann::json iterations = nlohmann::json::array();
  for (const IterationReport& iteration : result.iterations) {
    nlohmann::json fits = nlohmann::json::object();
    for (const PlaneFit& fit : iteration.fits) {
      fits[std::string(ToString(fit.plane))] = {
          {"histogram_l1_mean", fit.histogram_l1_mean},
          {"histogram_l1_max", fit.histogram_l1_max},
          {"inside_bounds", fit.inside_bounds},
          {"inside_bounds_average", fit.inside_bounds_average},
          {"log_spectral_distance_db", fit.log_spectral_distance_db}};
    }
    iterations.push_back({{"iteration", iteration.iteration},
                          {"relative_change", iteration.relative_change},
                          {"fits", fits}});
  }
  WriteJsonFile(path, {{"size", spectral.size},
                       {"crop_size", result.model.crop_size},
                       {"seconds", seconds},
                       {"iterations", iterations}});
}

void RunFromViews(const FromViewsCommandOptions& options) {
  const auto limit = LimitThreads(options.threads);
  const std::vector<SolidView> views = ViewsOf(options);
  const SpectralSolidOptions spectral = SpectralOptionsOf(options);
  const auto start = std::chrono::steady_clock::now();
  TerminalProgressBar bar;
  const SpectralSolidResult result = SynthesizeSpectralSolid(views, spectral, &bar);
  const double seconds = Seconds(start);
  PrintSpectralFits(result);
  fmt::print("synthesis took {:.2f} s\n", seconds);
  WriteOutputs(options.out, options.slices, result.volume);
  if (!options.report.empty()) WriteSpectralReport(options.report, spectral, result, seconds);
}

void AddFromViews(CLI::App& solid) {
  CLI::App* command = solid.add_subcommand(
      "from-views",
      "Synthesise an N^3 solid texture whose slices in each orientation look like the 2D view "
      "given for it (spectrum and histogram; Dischler et al. 1998). Each view must show its plane "
      "with the slice axes: xy: x right, y down; xz: x right, z down; yz: y right, z down.");
  BindCommand(*command, AddFromViewsOptions, RunFromViews);
}

// --- grow ---

Image LoadExemplar(const std::string& source, int procedural_size, std::uint64_t seed) {
  constexpr std::string_view kPrefix = "procedural:";
  if (source.rfind(kPrefix, 0) == 0) {
    const std::string name = source.substr(kPrefix.size());
    const auto pattern = ParseProceduralPattern(name);
    if (!pattern) {
      throw Error(
          fmt::format("unknown procedural exemplar \"{}\": marble, wood, cells, stripes "
                      "or noise",
                      name));
    }
    return MakeProceduralExemplar(*pattern, procedural_size, seed);
  }
  return ReadVolume(source);
}

std::optional<std::filesystem::path> CacheFolder(const std::string& requested, bool disabled) {
  if (disabled) return std::nullopt;
  if (!requested.empty()) return std::filesystem::path(requested);
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) {
    return std::filesystem::path(xdg) / "photomat" / "solid";
  }
  if (const char* home = std::getenv("HOME"); home && *home) {
    return std::filesystem::path(home) / ".cache" / "photomat" / "solid";
  }
  return std::nullopt;
}

struct GrowCommandOptions {
  std::string exemplar;
  int procedural_size = 64;
  std::string size = "128";
  std::string field;
  FieldParameters field_parameters;
  ExemplarSolidOptions synthesis;
  AppearanceOptions appearance;
  SimilarityOptions similarity;
  bool interior = false;
  bool single_resolution = false;
  std::string cache;
  bool no_cache = false;
  std::filesystem::path out, coordinates, slices, report;
  int threads = 0;
};

void AddGrowOptions(CLI::App& command, GrowCommandOptions& options) {
  command
      .add_option("exemplar", options.exemplar,
                  "Exemplar volume (FILE.vdb or an EXR slice folder), or procedural:NAME "
                  "(marble, wood, cells, stripes, noise)")
      ->required();
  command.add_option("--exemplar-size", options.procedural_size, "Side of a procedural exemplar")
      ->capture_default_str();
  command.add_option("--size", options.size, "Output size: N or XxYxZ")->capture_default_str();
  command.add_option("--field", options.field,
                     "Frame field: circular, oval, slant, zigzag, slant3d, or a volume FILE of 9 "
                     "channels (f1, f2, f3: the output directions of the exemplar's x, y, z) or "
                     "6 (f1, f2)");
  command
      .add_option("--angle", options.field_parameters.angle_degrees,
                  "Slant and zigzag angle, degrees")
      ->capture_default_str();
  command.add_option("--ratio", options.field_parameters.ratio, "Oval semi-axes ratio a:b")
      ->capture_default_str();
  command.add_option("--band", options.field_parameters.band, "Zigzag band width, voxels")
      ->capture_default_str();
  command.add_option("--jitter", options.synthesis.jitter, "Jitter strength r")
      ->capture_default_str();
  command
      .add_option("--passes", options.synthesis.correction_passes,
                  "Correction passes per level (0: jitter only)")
      ->capture_default_str();
  command
      .add_option("--dimensions", options.appearance.dimensions, "Appearance-space dimensions d")
      ->capture_default_str();
  command.add_option("--candidates", options.similarity.candidates, "Similarity set size k")
      ->capture_default_str();
  command.add_flag("--interior", options.interior,
                   "The exemplar does not tile: use only voxels whose neighbourhood is inside");
  command.add_flag("--single-resolution", options.single_resolution,
                   "Match every level against the exemplar itself (the thesis) instead of its "
                   "Gaussian stack");
  command
      .add_option("--histogram-matching", options.synthesis.histogram_matching,
                  "First step of the colour-bin prices that keep the result's per-channel "
                  "histograms at the exemplar's (after Kopf et al. 2007; 0: off)")
      ->capture_default_str();
  command
      .add_option("--occupancy-matching", options.synthesis.occupancy_matching,
                  "Weight lambda against over-used exemplar regions (0: off)")
      ->capture_default_str();
  command
      .add_option("--seed", options.synthesis.seed,
                  "Seed of the jitter (and of a "
                  "procedural exemplar)")
      ->capture_default_str();
  command.add_option("--cache", options.cache,
                     "Similarity-set cache folder (default: $XDG_CACHE_HOME/photomat/solid or "
                     "~/.cache/photomat/solid)");
  command.add_flag("--no-cache", options.no_cache, "Neither read nor write the cache");
  command.add_option("--out", options.out, "Output volume: FILE.vdb or a folder (EXR slices)")
      ->required();
  command.add_option("--coordinates", options.coordinates,
                     "Also write the exemplar coordinate of every voxel (a volume)");
  command.add_option("--slices", options.slices, "Folder for PNG pictures of central slices");
  command.add_option("--report", options.report,
                     "JSON file: timings, objective per pass, neighbourhood-match error");
  command.add_option("--threads", options.threads, "Threads (0: all; same result any count)")
      ->capture_default_str();
}

// --field: a named field made at the output's size, or a volume of frame vectors.
std::optional<FrameField> FrameFieldOf(const GrowCommandOptions& options, const ImageExtent& size) {
  if (options.field.empty()) return std::nullopt;
  if (const auto kind = ParseFieldKind(options.field)) {
    return MakeFrameField(*kind, size, options.field_parameters);
  }
  if (!std::filesystem::exists(options.field)) {
    throw Error(
        fmt::format("--field: \"{}\" is neither circular, oval, slant, zigzag, "
                    "slant3d nor an existing volume",
                    options.field));
  }
  try {
    return FrameFieldFromVolume(ReadVolume(options.field));
  } catch (const Error& error) {
    throw error.InFile(options.field);
  }
}

// The exemplar's appearance space and similarity set (from the cache when it has them).
PreparedExemplar PrepareGrowExemplar(const GrowCommandOptions& options, const Image& exemplar,
                                     Progress& bar, double& seconds) {
  AppearanceOptions appearance = options.appearance;
  appearance.boundary =
      options.interior ? ExemplarBoundary::kInterior : ExemplarBoundary::kPeriodic;
  appearance.gaussian_stack = !options.single_resolution;
  const auto start = std::chrono::steady_clock::now();
  PreparedExemplar prepared = PrepareExemplar(exemplar, appearance, options.similarity,
                                              CacheFolder(options.cache, options.no_cache), &bar);
  seconds = Seconds(start);
  fmt::print(
      "appearance space: {} dimensions keep {:.1f} % of the neighbourhood variance; "
      "similarity set {} ({:.2f} s)\n",
      prepared.appearance.dimensions, 100 * prepared.appearance.retained_variance,
      prepared.from_cache ? "read from " + prepared.cache_file.string() : "built", seconds);
  return prepared;
}

// --report: timings, the objective per pass and the result's distances from the exemplar.
void WriteGrowReport(const GrowCommandOptions& options, const ImageExtent& size,
                     const Image& exemplar, const PreparedExemplar& prepared,
                     const ExemplarSolidResult& result, double prepare_seconds,
                     double synthesis_seconds) {
  nlohmann::json passes = nlohmann::json::array();
  for (const PassReport& pass : result.passes) {
    passes.push_back({{"level", pass.level},
                      {"spacing", pass.spacing},
                      {"pass", pass.pass},
                      {"objective", pass.objective}});
  }
  WriteJsonFile(
      options.report,
      {{"exemplar", options.exemplar},
       {"size", ToString(size)},
       {"retained_variance", prepared.appearance.retained_variance},
       {"similarity_from_cache", prepared.from_cache},
       {"gaussian_stack_levels", prepared.stack.size()},
       {"prepare_seconds", prepare_seconds},
       {"synthesis_seconds", synthesis_seconds},
       {"passes", passes},
       {"neighbourhood_match_error",
        NeighbourhoodMatchError(result.volume, exemplar, prepared.appearance)},
       {"coherent_fraction", CoherentFraction(result.coordinates, prepared.appearance.domain)},
       {"histogram_distance", HistogramDistance(result.volume, exemplar)},
       {"earth_mover_distance", EarthMoverDistance(result.volume, exemplar)},
       {"spectrum_distance_db", LogSpectralDistance(RadialPowerSpectrum(result.volume, 8),
                                                    RadialPowerSpectrum(exemplar, 8))}});
}

void RunGrow(const GrowCommandOptions& options) {
  const auto limit = LimitThreads(options.threads);
  const auto size = ParseVolumeSize(options.size);
  if (!size) throw Error(fmt::format("--size: \"{}\" is not N or XxYxZ", options.size));
  const Image exemplar =
      LoadExemplar(options.exemplar, options.procedural_size, options.synthesis.seed);
  ExemplarSolidOptions synthesis = options.synthesis;
  synthesis.size = *size;
  const std::optional<FrameField> field = FrameFieldOf(options, *size);
  if (field) synthesis.field = &*field;
  TerminalProgressBar bar;
  double prepare_seconds = 0.0;
  const PreparedExemplar prepared = PrepareGrowExemplar(options, exemplar, bar, prepare_seconds);
  const auto synthesis_start = std::chrono::steady_clock::now();
  const ExemplarSolidResult result = SynthesizeExemplarSolid(exemplar, prepared, synthesis, &bar);
  const double synthesis_seconds = Seconds(synthesis_start);
  fmt::print("synthesis took {:.2f} s\n", synthesis_seconds);
  WriteOutputs(options.out, options.slices, result.volume);
  if (!options.coordinates.empty()) WriteVolume(options.coordinates, result.coordinates);
  if (!options.report.empty()) {
    WriteGrowReport(options, *size, exemplar, prepared, result, prepare_seconds, synthesis_seconds);
  }
}

void AddGrow(CLI::App& solid) {
  CLI::App* command = solid.add_subcommand(
      "grow",
      "Grow a solid texture of any size from a solid exemplar by pyramid synthesis of exemplar "
      "coordinates (Su 2008), optionally steered by a frame field. Every channel of the exemplar "
      "is carried, so a volume of representation maps grows as well as a colour one.");
  BindCommand(*command, AddGrowOptions, RunGrow);
}

// --- exemplar ---

void AddExemplar(CLI::App& solid) {
  struct Options {
    std::string pattern = "marble";
    int size = 64;
    std::uint64_t seed = 1;
    std::filesystem::path out, slices;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = solid.add_subcommand(
      "exemplar", "Write a procedural solid exemplar (periodic along every axis).");
  command->add_option("--pattern", options->pattern, "marble, wood, cells, stripes or noise")
      ->capture_default_str();
  command->add_option("--size", options->size, "Side in voxels")->capture_default_str();
  command->add_option("--seed", options->seed, "Seed")->capture_default_str();
  command->add_option("--out", options->out, "Output volume: FILE.vdb or a folder (EXR slices)")
      ->required();
  command->add_option("--slices", options->slices, "Folder for PNG pictures of central slices");
  command->callback([options] {
    WriteOutputs(options->out, options->slices,
                 LoadExemplar("procedural:" + options->pattern, options->size, options->seed));
  });
}

}  // namespace

void AddSolidCommand(CLI::App& app) {
  CLI::App* solid = AddListedCommand(app, "solid");
  solid->require_subcommand(1);
  AddFromViews(*solid);
  AddGrow(*solid);
#ifdef PHOTOMAT_WITH_CARVING
  AddSolidCarveCommand(*solid, kCarveDescription);
#else
  AddAbsentCommand(*solid, "carve", kCarveDescription, Component::kCarving);
#endif
  AddExemplar(*solid);
}

}  // namespace photomat::app
