// photomat rd: reaction-diffusion patterns grown on a mesh (FEM) or on a periodic grid (a tileable
// material written as a map stack).
#include "apps/rd_command.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/progress.h"
#include "represent/stack/map_stack.h"
#include "synthesize/mesh/field_colours.h"
#include "synthesize/mesh/loop_subdivision.h"
#include "synthesize/mesh/mesh.h"
#include "synthesize/mesh/mesh_io.h"
#include "synthesize/mesh/mesh_render.h"
#include "synthesize/surface/geometric_diffusion.h"
#include "synthesize/surface/pattern_analysis.h"
#include "synthesize/surface/pattern_material.h"
#include "synthesize/surface/ready_pattern.h"

namespace photomat::app {
namespace {

struct RdOptions {
  std::string mesh;
  std::string grid;
  std::string model = "turk";
  int steps = 3000;
  double settle = 0.0;
  std::optional<double> tau;
  std::uint64_t seed = 1;
  // Turk
  double s = 0.05;
  double beta_noise = 0.1;
  // Gray-Scott
  std::optional<double> f, k;
  std::string pearson;
  // Brusselator
  double delta = 1.0;
  double gamma = 0.1;
  bool printed_form = false;
  // Meshes
  std::string normalize = "bbox";
  std::optional<double> size;
  int subdivide = 0;
  int smooth_steps = 0;
  double noise = 0.0;
  std::string direction;
  double anisotropy = 4.0;
  std::string mass;
  double cg_tolerance = 1e-6;
  bool gauss_seidel = false;
  // Output
  std::string colour_map = "viridis";
  int preview_size = 512;
  double relief = 3.0;
  std::filesystem::path out;
};

// "sphere[:RADIUS[:LEVEL]]", "torus[:R:r]" or a mesh file.
TriangleMesh LoadOrMakeMesh(const std::string& spec) {
  std::vector<std::string> parts;
  std::stringstream stream(spec);
  for (std::string part; std::getline(stream, part, ':');) parts.push_back(part);
  auto number = [&](std::size_t i, double fallback) {
    if (i >= parts.size()) return fallback;
    try {
      return std::stod(parts[i]);
    } catch (const std::exception&) {
      throw Error(fmt::format("--mesh {}: \"{}\" is not a number", spec, parts[i]));
    }
  };
  if (!parts.empty() && parts[0] == "sphere") {
    return MakeIcosphere(number(1, 1.0), static_cast<int>(number(2, 5)));
  }
  if (!parts.empty() && parts[0] == "torus") {
    const double major = number(1, 3.0), minor = number(2, 1.0);
    const int around = static_cast<int>(std::lround(number(3, 192)));
    return MakeTorus(major, minor, around, std::max(3, static_cast<int>(around * minor / major)));
  }
  return ReadMesh(spec);
}

std::unique_ptr<ReactionDiffusionModel> MakeModel(const RdOptions& o) {
  if (o.model == "turk") {
    TurkParameters p;
    p.s = o.s;
    p.beta_noise = o.beta_noise;
    return MakeTurkModel(p);
  }
  if (o.model == "grayscott") {
    GrayScottParameters p;
    int reference_width = 256;  // Pearson's grid, which the seed fraction refers to
    if (!o.pearson.empty()) {
      const ReadyGrayScottPattern pattern = ReadReadyGrayScott(o.pearson);
      p = pattern.parameters;
      reference_width = pattern.width;
    }
    if (o.f) p.f = *o.f;
    if (o.k) p.k = *o.k;
    // On a grid of another size, Pearson's seed keeps its size in cells (20 x 20): a smaller
    // seed dies out.
    if (!o.grid.empty()) {
      const int width = ParseSize(o.grid).first;
      p.seed_size = std::min(0.5, p.seed_size * reference_width / width);
    }
    return MakeGrayScottModel(p);
  }
  if (o.model == "brusselator") {
    BrusselatorParameters p;
    p.delta = o.delta;
    p.gamma = o.gamma;
    p.printed_form = o.printed_form;
    return MakeBrusselatorModel(p);
  }
  if (o.model == "fhn") return MakeFitzHughNagumoModel({});
  throw Error(
      fmt::format("unknown model \"{}\": expected turk, grayscott, brusselator or fhn", o.model));
}

std::optional<Anisotropy> ParseDirection(const RdOptions& o) {
  if (o.direction.empty()) return std::nullopt;
  Anisotropy anisotropy;
  const std::string& d = o.direction;
  if (d.size() < 3 || (d.rfind("around-", 0) != 0 && d.rfind("along-", 0) != 0)) {
    throw Error(fmt::format("--direction {}: expected around-x|y|z or along-x|y|z", d));
  }
  anisotropy.field =
      d.rfind("around-", 0) == 0 ? DirectionField::kAroundAxis : DirectionField::kAlongAxis;
  const char axis = d.back();
  if (axis == 'x') {
    anisotropy.axis = Eigen::Vector3d::UnitX();
  } else if (axis == 'y') {
    anisotropy.axis = Eigen::Vector3d::UnitY();
  } else if (axis == 'z') {
    anisotropy.axis = Eigen::Vector3d::UnitZ();
  } else {
    throw Error(fmt::format("--direction {}: the axis must be x, y or z", d));
  }
  if (!(o.anisotropy >= 1.0)) throw Error("--anisotropy must be at least 1");
  anisotropy.along = o.anisotropy;
  anisotropy.across = 1.0;
  return anisotropy;
}

void WriteHistory(const std::filesystem::path& path, const SimulationResult& result,
                  const std::vector<std::string>& species) {
  std::string text = "step,time,max_rate,rms_rate";
  for (const auto& name : species) text += ",cg_iterations_" + name;
  text += "\n";
  for (const auto& r : result.history) {
    text += fmt::format("{},{:.6g},{:.6g},{:.6g}", r.step, r.time, r.max_rate, r.rms_rate);
    for (int i : r.iterations) text += fmt::format(",{}", i);
    text += "\n";
  }
  WriteTextFileAtomically(path, text);
}

nlohmann::json Summary(const RdOptions& o, const ReactionDiffusionModel& model,
                       const SimulationResult& result, double tau, double seconds) {
  return {{"model", model.name()},     {"steps", result.steps},
          {"time", result.time},       {"time_step", tau},
          {"settled", result.settled}, {"cg_iterations", result.total_iterations},
          {"seconds", seconds},        {"seed", o.seed}};
}

void RunOnGrid(const RdOptions& o, ReactionDiffusionModel& model, SimulationOptions options) {
  const auto [width, height] = ParseSize(o.grid);
  // Pearson's grid spacing for Gray-Scott (his D are in those units); unit spacing otherwise.
  double spacing = 1.0;
  if (o.model == "grayscott") {
    spacing = o.pearson.empty() ? 2.5 / 256 : ReadReadyGrayScott(o.pearson).dx;
  }
  const FemDomain domain = FemDomain::PeriodicGrid(width, height, spacing);
  TerminalProgressBar bar;
  const auto start = std::chrono::steady_clock::now();
  const SimulationResult result = SimulateReactionDiffusion(model, domain, options, &bar);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Eigen::VectorXd& field = result.fields[model.pattern_species()];
  CreateFolder(o.out);
  const GridShape grid = *domain.grid();
  WriteImage(o.out / "pattern.exr", GridFieldImage(grid, field, "Y"));
  // The colour-mapped pattern as an sRGB PNG (tiles seamlessly).
  FieldColourOptions colours;
  colours.map = ParseColourMap(o.colour_map);
  const auto rgb = FieldColours(field, colours);
  Image preview(width, height, {"R", "G", "B"});
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    for (int c = 0; c < 3; ++c) preview.pixel(i)[c] = rgb[i][c];
  }
  ImageWriteOptions png;
  png.sample_type = SampleType::kUint8;
  png.encoding = ColourSpace::kSrgb;
  WriteImage(o.out / "pattern.png", preview, png);
  PatternMaterialOptions material;
  material.relief_pixels = o.relief;
  StackProvenance provenance;
  provenance.source = fmt::format("photomat rd --grid {} --model {}", o.grid, model.name());
  SaveRepresentation(o.out / "rd.exr", PatternMaterial(grid, field, material), provenance);
  WriteFitManifest(o.out, provenance.source, {{"gradient", "rd.exr"}});
  WriteHistory(o.out / "history.csv", result, model.species_names());
  nlohmann::json summary = Summary(o, model, result, options.time_step, seconds);
  const double wavelength = DominantGridWavelength(grid, field);
  summary["grid"] = {width, height};
  summary["spacing"] = spacing;
  summary["wavelength"] = wavelength;
  WriteJsonFile(o.out / "summary.json", summary);
  fmt::print(
      "{} on a {}x{} periodic grid: {} steps ({}), {} CG iterations, {:.1f} s; dominant "
      "wavelength {:.3g} ({:.1f} nodes); wrote pattern.png, rd.exr (map stack) to {}\n",
      model.name(), width, height, result.steps, result.settled ? "settled" : "not settled",
      result.total_iterations, seconds, wavelength, wavelength / spacing, o.out.string());
}

void RunOnMesh(const RdOptions& o, ReactionDiffusionModel& model, SimulationOptions options) {
  TriangleMesh mesh = LoadOrMakeMesh(o.mesh);
  const double size = o.size.value_or(o.model == "grayscott" ? 2.5 : 100.0);
  NormalizeMesh(mesh, ParseMeshNormalization(o.normalize), size);
  if (o.subdivide > 0) mesh = LoopSubdivide(mesh, o.subdivide);
  if (o.noise > 0.0) AddNormalNoise(mesh, o.noise * MeanEdgeLength(mesh), o.seed);
  const double edge = MeanEdgeLength(mesh);
  if (o.model == "turk" && edge > TurkCriticalWavelength(o.s) / 4) {
    fmt::print(stderr,
               "photomat: warning: mean edge {:.3g} is over a quarter of the pattern wavelength "
               "{:.3g}: use --subdivide or a larger --size\n",
               edge, TurkCriticalWavelength(o.s));
  }
  TerminalProgressBar bar;
  const auto start = std::chrono::steady_clock::now();
  SimulationResult result;
  if (o.smooth_steps > 0) {
    GeometricDiffusionOptions geometry;
    geometry.steps = o.smooth_steps;
    CoupledResult coupled = SimulateCoupled(mesh, model, options, geometry, &bar);
    mesh = std::move(coupled.mesh);
    result = std::move(coupled.pattern);
  } else {
    result = SimulateReactionDiffusion(model, FemDomain::FromMesh(mesh), options, &bar);
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const Eigen::VectorXd& field = result.fields[model.pattern_species()];
  FieldColourOptions colour_options;
  colour_options.map = ParseColourMap(o.colour_map);
  const auto colours = FieldColours(field, colour_options);
  CreateFolder(o.out);
  WriteMesh(o.out / "pattern.ply", mesh, colours);
  WriteMesh(o.out / "pattern.glb", mesh, colours);
  PreviewOptions preview;
  preview.size = o.preview_size;
  WritePreviews(o.out, "preview", mesh, colours, DefaultPreviewViews(), preview);
  // The fields themselves, one row per vertex.
  std::string text;
  const auto names = model.species_names();
  for (std::size_t s = 0; s < names.size(); ++s) text += (s ? "," : "") + names[s];
  text += "\n";
  for (int v = 0; v < mesh.vertex_count(); ++v) {
    for (std::size_t s = 0; s < names.size(); ++s) {
      text += fmt::format("{}{:.6g}", s ? "," : "", result.fields[s][v]);
    }
    text += "\n";
  }
  WriteTextFileAtomically(o.out / "fields.csv", text);
  WriteHistory(o.out / "history.csv", result, names);
  const FemDomain domain = FemDomain::FromMesh(mesh);
  const double k = RmsWavenumber(FemOperators(domain), field);
  nlohmann::json summary = Summary(o, model, result, options.time_step, seconds);
  summary["vertices"] = mesh.vertex_count();
  summary["triangles"] = mesh.triangle_count();
  summary["mean_edge"] = edge;
  summary["rms_wavelength"] = k > 0 ? 2 * std::numbers::pi / k : 0.0;
  WriteJsonFile(o.out / "summary.json", summary);
  fmt::print(
      "{} on {} vertices: {} steps ({}), {} CG iterations, {:.1f} s; wrote pattern.ply, "
      "pattern.glb, previews to {}\n",
      model.name(), mesh.vertex_count(), result.steps, result.settled ? "settled" : "not settled",
      result.total_iterations, seconds, o.out.string());
}

void AddRdOptions(CLI::App& command, RdOptions& o) {
  command.add_option("--mesh", o.mesh,
                     "Mesh file (OBJ, PLY, ...), or sphere[:RADIUS[:LEVEL]], torus[:R:r[:N]]");
  command.add_option("--grid", o.grid, "Periodic grid WIDTHxHEIGHT instead of a mesh");
  command.add_option("--model", o.model, "turk, grayscott, brusselator or fhn")
      ->capture_default_str();
  command.add_option("--steps", o.steps, "Time steps (at most, with --settle)")
      ->capture_default_str();
  command
      .add_option("--settle", o.settle,
                  "Stop once the RMS of du/dt falls below this (0: run all steps)")
      ->capture_default_str();
  command.add_option("--tau", o.tau, "Time step (default: the model's suggestion)");
  command.add_option("--seed", o.seed, "Seed of the random initial state")->capture_default_str();
  command.add_option("--s", o.s, "Turk: reaction rate s (0.025 .. 0.05)")->capture_default_str();
  command.add_option("--beta-noise", o.beta_noise, "Turk: beta = 12 +- this")
      ->capture_default_str();
  command.add_option("--pearson", o.pearson,
                     "Gray-Scott: a Ready pattern file (.vti) with the parameters, e.g. "
                     "Pearson1993.vti");
  command.add_option("--F", o.f, "Gray-Scott: feed rate F (default 0.040)");
  command.add_option("--K", o.k, "Gray-Scott: kill rate K (default 0.060)");
  command.add_option("--delta", o.delta, "Brusselator: diffusion of v")->capture_default_str();
  command.add_option("--gamma", o.gamma, "Brusselator: forcing amplitude")->capture_default_str();
  command.add_flag("--printed-form", o.printed_form,
                   "Brusselator: the paper's printed -d u (its u + v grows without bound)");
  command.add_option("--normalize", o.normalize, "Mesh normalisation: bbox or area")
      ->capture_default_str();
  command.add_option("--size", o.size,
                     "Bounding-box diagonal (or sqrt of the area) after normalisation, in "
                     "pattern units (default 100; Gray-Scott 2.5)");
  command.add_option("--subdivide", o.subdivide, "Loop subdivision levels before solving")
      ->capture_default_str();
  command
      .add_option("--smooth-steps", o.smooth_steps,
                  "Anisotropic geometric diffusion steps coupled with the pattern (noisy "
                  "meshes)")
      ->capture_default_str();
  command.add_option("--noise", o.noise, "Add normal noise, in mean edge lengths (for tests)")
      ->capture_default_str();
  command.add_option("--direction", o.direction,
                     "Anisotropic diffusion along a field: around-x|y|z (rings) or "
                     "along-x|y|z (meridians)");
  command
      .add_option("--anisotropy", o.anisotropy,
                  "Diffusion along the direction field over across it")
      ->capture_default_str();
  command.add_option("--mass", o.mass,
                     "consistent or lumped mass matrix (default: consistent on meshes, lumped on "
                     "grids, where the consistent mass of the one-diagonal split bends patterns "
                     "along the diagonal)");
  command
      .add_option("--cg-tolerance", o.cg_tolerance,
                  "Relative residual at which conjugate gradients stop")
      ->capture_default_str();
  command.add_flag("--gauss-seidel", o.gauss_seidel,
                   "Solve the second species with the first one's new values (allows longer "
                   "steps: Turk tau s < 1/12 instead of 1/28)");
  command.add_option("--colour-map", o.colour_map, "viridis, inferno, turbo or grey")
      ->capture_default_str();
  command.add_option("--preview-size", o.preview_size, "Preview image size")->capture_default_str();
  command.add_option("--relief", o.relief, "Grid: height of the pattern's range, in pixels")
      ->capture_default_str();
  command.add_option("--out", o.out, "Output folder")->required();
}

// The simulation the options ask for, on the periodic grid or on the mesh.
void RunRd(const RdOptions& o) {
  if (o.mesh.empty() == o.grid.empty()) throw Error("give exactly one of --mesh and --grid");
  if (o.steps < 1) throw Error("--steps must be at least 1");
  auto model = MakeModel(o);
  SimulationOptions options;
  options.time_step = o.tau.value_or(model->suggested_time_step());
  options.max_steps = o.steps;
  options.settle_rate = o.settle;
  options.min_steps = std::min(o.steps, 100);
  options.seed = o.seed;
  const std::string mass = o.mass.empty() ? (o.grid.empty() ? "consistent" : "lumped") : o.mass;
  if (mass != "consistent" && mass != "lumped") {
    throw Error(fmt::format("--mass {}: expected consistent or lumped", o.mass));
  }
  options.solver.lumped_mass = mass == "lumped";
  options.solver.tolerance = o.cg_tolerance;
  if (o.gauss_seidel) options.ordering = SpeciesOrdering::kGaussSeidel;
  options.anisotropy = ParseDirection(o);
  if (!o.grid.empty()) {
    RunOnGrid(o, *model, options);
  } else {
    RunOnMesh(o, *model, options);
  }
}

}  // namespace

void AddRdCommand(CLI::App& app) { BindCommand(*AddListedCommand(app, "rd"), AddRdOptions, RunRd); }

}  // namespace photomat::app
