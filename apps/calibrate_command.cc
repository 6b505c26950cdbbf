// photomat calibrate: light directions from a mirror sphere, flat-fields, light intensities,
// camera response, and applying them to a capture.
#include "apps/calibrate_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <tuple>
#include <utility>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "calibrate/lights/calibration_report.h"
#include "calibrate/lights/light_list.h"
#include "calibrate/lights/mirror_sphere.h"
#include "calibrate/lights/mirror_sphere_refinement.h"
#include "calibrate/radiometry/capture_corrections.h"
#include "calibrate/radiometry/exposure.h"
#include "calibrate/radiometry/flat_field.h"
#include "calibrate/radiometry/near_light.h"
#include "calibrate/radiometry/response_curve.h"
#include "calibrate/radiometry/semi_calibrated.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/lp_file.h"
#include "capture/io/streamed_set.h"
#include "core/atomic_file.h"
#include "core/colour.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/memory_limits.h"
#include "core/progress.h"
#include "core/text_parsing.h"
#include "represent/fitting/robust_intensities.h"

namespace photomat::app {
namespace {

namespace fs = std::filesystem;

// The least memory `calibrate apply`'s bands may be given (--memory).
constexpr std::size_t kMinimumApplyMemory = std::size_t{16} << 20;

bool IsMaskName(const fs::path& path) {
  return ToLower(path.stem().string()).find("mask") != std::string::npos;
}

// The image files of a folder in natural order, and the mask among them (a name with "mask").
struct ImageFolder {
  std::vector<fs::path> images;
  std::optional<fs::path> mask;
};

ImageFolder ListImageFolder(const fs::path& folder) {
  ImageFolder listing;
  for (const fs::path& file : ListImageFiles(folder)) {
    if (!IsMaskName(file)) {
      listing.images.push_back(file);
    } else if (listing.mask) {
      throw Error(folder, fmt::format("two masks ({} and {}); give one with --mask",
                                      listing.mask->filename().string(), file.filename().string()));
    } else {
      listing.mask = file;
    }
  }
  if (listing.images.empty()) throw Error(folder, "no images in the folder");
  return listing;
}

// `path` relative to `base` (so that the light file and its images move together), or absolute
// when there is no relative path.
std::string RelativeName(const fs::path& path, const fs::path& base) {
  const fs::path absolute = fs::absolute(path).lexically_normal();
  const fs::path relative = absolute.lexically_relative(fs::absolute(base).lexically_normal());
  return relative.empty() ? absolute.generic_string() : relative.generic_string();
}

std::optional<ColourSpace> ParseColourSpaceOption(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const auto space = ParseColourSpace(text);
  if (!space) throw Error("--colour-space: expected linear or srgb");
  return space;
}

// The sphere images: a plain folder of images (natural order, a "mask" file as the sphere's mask)
// or any photometric set photomat reads (its lights then serve as the reference).
struct SphereCapture {
  std::vector<Image> images;
  std::vector<fs::path> files;
  std::vector<std::string> names;
  std::optional<Image> mask;           // coverage in [0, 1]
  std::vector<LightDirection> lights;  // of a photometric set; empty for a plain folder
};

SphereCapture ReadSphereCapture(const fs::path& input, const std::optional<ColourSpace>& space) {
  SphereCapture capture;
  bool plain_folder = false;
  if (fs::is_directory(input)) {
    try {
      DetectInput(input);
    } catch (const Error&) {
      plain_folder = true;
    }
  }
  ImageReadOptions coverage;
  coverage.colour_space = ColourSpace::kLinear;
  if (plain_folder) {
    const ImageFolder folder = ListImageFolder(input);
    ImageReadOptions read;
    read.untagged_colour_space = space;
    TerminalProgressBar bar;
    bar.Start("load", folder.images.size());
    for (const fs::path& file : folder.images) {
      capture.images.push_back(ReadImage(file, read).image);
      capture.files.push_back(file);
      capture.names.push_back(file.filename().string());
      bar.Advance();
    }
    bar.Finish();
    if (folder.mask) capture.mask = ReadImage(*folder.mask, coverage).image;
    return capture;
  }
  LoadOptions load;
  load.untagged_colour_space = space;
  const LoadedSet loaded = LoadSetForCommand(input, load);
  const fs::path base = DetectInput(input).file;
  const fs::path folder = fs::is_directory(base) ? base : base.parent_path();
  for (int i = 0; i < loaded.set.size(); ++i) {
    capture.images.push_back(loaded.set.image(i));
    capture.names.push_back(loaded.set.image_name(i));
    capture.files.push_back(ResolveImagePath(folder, loaded.set.image_name(i)));
  }
  if (loaded.set.mask()) {
    Image mask(loaded.set.width(), loaded.set.height(), 1);
    for (std::size_t p = 0; p < mask.pixel_count(); ++p) {
      mask.pixel(p)[0] = (*loaded.set.mask())[p] ? 1.0f : 0.0f;
    }
    capture.mask = std::move(mask);
  }
  capture.lights = loaded.set.lights();
  return capture;
}

// Near lamps as calibrate apply --near-lights reads them: "x y z intensity" a line (the
// intensity is unknown here: 1).
void WriteLampPositions(const fs::path& path, const std::vector<Eigen::Vector3d>& lamps) {
  std::string text =
      "# near lamps triangulated from the mirror spheres: x y z intensity (sample frame, pixels)\n";
  for (const Eigen::Vector3d& lamp : lamps) {
    text += fmt::format("{:.4f} {:.4f} {:.4f} 1\n", lamp.x(), lamp.y(), lamp.z());
  }
  WriteTextFileAtomically(path, text);
}

// Without --refine or --no-refine the lights are refined when this build can; a build without
// Ceres says once that it gives the unrefined sphere.
bool RefineByDefault() {
  if (MirrorSphereRefinementAvailable()) return true;
  spdlog::warn("{}: the lights come from the unrefined sphere", MirrorSphereRefinementAbsence());
  return false;
}

struct LightsCommandOptions {
  fs::path input;
  fs::path out;
  fs::path mask;
  fs::path reference;
  fs::path report;
  fs::path camera;
  fs::path images_for;
  std::string colour_space;
  std::string light_model = "distant";
  bool refine = false;
  bool no_refine = false;
};

void AddLightsOptions(CLI::App& command, LightsCommandOptions& options) {
  command
      .add_option("sphere", options.input,
                  "The sphere images: a folder of images (natural order; a file named *mask* "
                  "is the sphere's mask) or a photometric set (.lp, manifest, DiLiGenT)")
      ->required();
  command.add_option("--out", options.out, "The .lp file to write")->required();
  command.add_option("--mask", options.mask,
                     "The sphere's mask (anti-aliased or binary); default: the folder's *mask* "
                     "file or the set's mask; without one the sphere is detected (Hough)");
  command.add_option("--reference", options.reference,
                     "Lights to compare with (.lp, manifest, DiLiGenT, or a list of \"x y z\" "
                     "lines with an optional count line); default: the set's own lights");
  command.add_option("--report", options.report,
                     "The report's SVG (default: <out stem>_report.svg; JSON beside it)");
  command.add_option("--camera", options.camera,
                     "3x3 intrinsics (K.txt) of a perspective camera; default orthographic");
  command.add_option("--images-for", options.images_for,
                     "Name the lights after the images of this folder (natural order, same "
                     "count): the sample captured under the same lights");
  command.add_option("--colour-space", options.colour_space,
                     "How untagged integer images encode light: linear or srgb (a file's own "
                     "colour tags come first; default: 8-bit sRGB, 16-bit linear)");
  CLI::Option* refine = command.add_flag(
      "--refine", options.refine,
      "Refine the sphere jointly with the lights (Ceres; the default when this build has Ceres, "
      "an error when it has not)");
  command.add_flag("--no-refine", options.no_refine, "Skip the Ceres refinement")->excludes(refine);
  command
      .add_option("--light-model", options.light_model,
                  "distant, or near: point lamps triangulated from two or more spheres in the "
                  "mask (resting on the sample plane; orthographic camera), their positions "
                  "written to <out stem>_lamps.txt for calibrate apply --near-lights")
      ->capture_default_str();
}

MirrorSphereCalibration CalibrateSphere(const LightsCommandOptions& options,
                                        SphereCapture& capture) {
  if (!options.mask.empty()) {
    ImageReadOptions coverage;
    coverage.colour_space = ColourSpace::kLinear;
    capture.mask = ReadImage(options.mask, coverage).image;
  }
  MirrorSphereOptions sphere_options;
  sphere_options.refine = options.refine || (!options.no_refine && RefineByDefault());
  sphere_options.light_model = ParseLightModel(options.light_model);
  if (!options.camera.empty()) sphere_options.camera = ReadCameraIntrinsics(options.camera);
  TerminalProgressBar bar;
  sphere_options.progress = &bar;
  const MirrorSphereCalibration result = CalibrateLightsFromMirrorSphere(
      capture.images, capture.names, capture.mask, sphere_options, options.input);
  if (result.refinement.requested && !result.refinement.used) {
    spdlog::warn("the refinement was not used ({}): the lights come from the unrefined sphere",
                 result.refinement.status);
  }
  return result;
}

// The lights' files: the .lp, the manifest beside it (whose provenance describes the sphere)
// and, for near lamps, their positions. Returns the manifest's path and the lamps' (or empty).
std::pair<fs::path, fs::path> WriteLightFiles(const LightsCommandOptions& options,
                                              const SphereCapture& capture,
                                              const MirrorSphereCalibration& result,
                                              CaptureManifest& manifest) {
  // The images the lights belong to.
  std::vector<fs::path> files = capture.files;
  if (!options.images_for.empty()) {
    files = ListImageFolder(options.images_for).images;
    if (files.size() != result.lights.size()) {
      throw Error(options.images_for, fmt::format("{} images, but the sphere gave {} lights",
                                                  files.size(), result.lights.size()));
    }
  }
  const fs::path out_folder =
      options.out.parent_path().empty() ? fs::path(".") : options.out.parent_path();
  CreateFolder(out_folder);
  std::vector<std::string> names;
  for (const fs::path& file : files) names.push_back(RelativeName(file, out_folder));
  WriteLpFile(options.out, names, result.lights);
  fs::path manifest_path = options.out;
  manifest_path.replace_extension(".json");
  for (std::size_t i = 0; i < names.size(); ++i) {
    manifest.images.push_back({names[i], result.lights[i], {}, {}});
  }
  manifest.provenance = {{"calibration", "mirror sphere"},
                         {"sphere_images", fs::absolute(options.input).generic_string()},
                         {"sphere",
                          {{"centre", {result.sphere.centre.x(), result.sphere.centre.y()}},
                           {"radius", result.sphere.radius},
                           {"edge_rms_px", result.edge_rms_pixels},
                           {"camera", result.perspective ? "perspective" : "orthographic"}}},
                         {"spheres", MirrorSpheresJson(result)},
                         {"light_model", ToString(result.light_model)},
                         {"refinement", MirrorSphereRefinementJson(result.refinement)}};
  WriteCaptureManifest(manifest_path, manifest);
  fs::path lamps_path;
  if (!result.lamp_positions.empty()) {
    lamps_path = options.out;
    lamps_path.replace_filename(options.out.stem().string() + "_lamps.txt");
    WriteLampPositions(lamps_path, result.lamp_positions);
  }
  return {manifest_path, lamps_path};
}

// The report: the recovered lights against the reference (the set's own, or --reference), as an
// SVG and JSON (with the manifest's description of the sphere). Returns the report and its SVG's
// and JSON's paths.
std::tuple<LightCalibrationReport, fs::path, fs::path> WriteLightReport(
    const LightsCommandOptions& options, const SphereCapture& capture,
    const MirrorSphereCalibration& result, const CaptureManifest& manifest) {
  LightCalibrationReport report;
  report.title = fmt::format("mirror-sphere lights: {}", options.input.filename().string());
  report.names = capture.names;
  report.recovered = result.lights;
  report.uncertainty_degrees = result.light_uncertainty_degrees;
  report.notes = MirrorSphereNotes(result);
  report.reference = options.reference.empty() ? capture.lights : ReadLightList(options.reference);
  if (!report.reference.empty() && report.reference.size() != report.recovered.size()) {
    throw Error(options.reference.empty() ? options.input : options.reference,
                fmt::format("{} reference lights for {} sphere images", report.reference.size(),
                            report.recovered.size()));
  }
  fs::path svg = options.report;
  if (svg.empty()) {
    svg = options.out;
    svg.replace_filename(options.out.stem().string() + "_report.svg");
  }
  WriteLightCalibrationSvg(svg, report);
  fs::path json = svg;
  json.replace_extension(".json");
  nlohmann::json details = report.ToJson();
  for (const char* key : {"sphere", "spheres", "light_model", "refinement"}) {
    details[key] = manifest.provenance[key];
  }
  WriteJsonFile(json, details);
  return {std::move(report), svg, json};
}

void RunLights(const LightsCommandOptions& options) {
  const std::optional<ColourSpace> space = ParseColourSpaceOption(options.colour_space);
  SphereCapture capture = ReadSphereCapture(options.input, space);
  const MirrorSphereCalibration result = CalibrateSphere(options, capture);
  CaptureManifest manifest;
  const auto [manifest_path, lamps_path] = WriteLightFiles(options, capture, result, manifest);
  const auto [report, svg, json] = WriteLightReport(options, capture, result, manifest);
  fmt::print(
      "sphere: centre ({:.2f}, {:.2f}) px, radius {:.2f} px, outline RMS {:.3f} px from "
      "{} edge points ({})\n{}",
      result.sphere.centre.x(), result.sphere.centre.y(), result.sphere.radius,
      result.edge_rms_pixels, result.edge_points,
      result.perspective ? "perspective" : "orthographic", report.ToTable());
  fmt::print("wrote {}, {}, {}, {}{}\n", options.out.string(), manifest_path.string(), svg.string(),
             json.string(), lamps_path.empty() ? "" : ", " + lamps_path.string());
}

void AddLightsCommand(CLI::App& calibrate) {
  CLI::App* command = calibrate.add_subcommand(
      "lights",
      "Light directions from a mirror (chrome) sphere photographed under each light: writes a "
      ".lp file, the same lights as a manifest (.json beside it) and a report (hemisphere plot "
      "SVG, JSON, and a table on standard output).");
  BindCommand(*command, AddLightsOptions, RunLights);
}

void AddFlatFieldCommand(CLI::App& calibrate) {
  struct Options {
    fs::path input;
    fs::path out;
    std::string model = "polynomial";
    int degree = 4;
    double sigma = 3.0;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = calibrate.add_subcommand(
      "flatfield",
      "Per-light gain maps from a flat uniform matte target captured under the sample's lights "
      "(its mask selects the target); `calibrate apply --flat-field` divides a capture by them.");
  command->add_option("target", options->input, "The target's photometric set")->required();
  command->add_option("--out", options->out, "Output folder (flatfield.json, gain_NNN.exr)")
      ->required();
  command
      ->add_option("--model", options->model,
                   "polynomial (low-order fit of the log: noisy targets) or smoothed "
                   "(Gaussian: keeps fine lamp patterns)")
      ->capture_default_str();
  command->add_option("--degree", options->degree, "Polynomial degree")->capture_default_str();
  command->add_option("--sigma", options->sigma, "Smoothing sigma in pixels")
      ->capture_default_str();
  command->callback([options] {
    FlatFieldOptions flat;
    const auto model = ParseFlatFieldModel(options->model);
    if (!model) throw Error("--model: expected polynomial or smoothed");
    flat.model = *model;
    flat.polynomial_degree = options->degree;
    flat.smoothing_sigma = options->sigma;
    TerminalProgressBar bar;
    flat.progress = &bar;
    LoadOptions load;
    load.apply_intensities = false;  // the gains take the lamps' brightness in
    // One image per thread at a time, whatever the target's size (EstimateFlatFieldStreamed).
    StreamedSet target = OpenStreamedSet(options->input, load);
    EstimateFlatFieldStreamed(target, options->out, flat);
    WarnAboutClippedPixels(target.SaturatedPixels(), target.image_names());
    fmt::print("{} gain maps ({} model) -> {}\n", target.size(), ToString(flat.model),
               options->out.string());
  });
}

void AddIntensitiesCommand(CLI::App& calibrate) {
  struct Options {
    fs::path input;
    fs::path out;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = calibrate.add_subcommand(
      "intensities",
      "Semi-calibrated photometric stereo: estimate each light's RGB intensity from the capture "
      "itself (known directions), written as light_intensities.txt (\"r g b\" a line).");
  command->add_option("input", options->input, "Photometric set")->required();
  command->add_option("--out", options->out, "Intensities file to write")->required();
  command->callback([options] {
    LoadOptions load;
    load.apply_intensities = false;
    const LoadedSet loaded = LoadSetForCommand(options->input, load);
    SemiCalibratedOptions semi;
    TerminalProgressBar bar;
    semi.progress = &bar;
    const SemiCalibratedResult result = EstimateLightIntensitiesRobust(loaded.set, semi);
    WriteLightIntensities(options->out, result.intensities);
    fmt::print("{} intensities ({} iterations) -> {}\n", result.intensities.size(),
               result.iterations, options->out.string());
    const auto& given = loaded.set.intensities();
    if (given.size() == result.intensities.size() &&
        given.front().size() == result.intensities.front().size()) {
      double worst = 0.0;
      for (std::size_t c = 0; c < given.front().size(); ++c) {
        double mean = 0.0;
        for (const auto& row : given) mean += row[c] / static_cast<double>(given.size());
        for (std::size_t i = 0; i < given.size(); ++i) {
          worst = std::max(worst, std::abs(result.intensities[i][c] / (given[i][c] / mean) - 1.0));
        }
      }
      fmt::print("the input's own intensities (normalised alike) differ by at most {:.2f} %\n",
                 100 * worst);
    }
  });
}

void AddResponseCommand(CLI::App& calibrate) {
  struct Options {
    std::vector<fs::path> images;
    std::string times;
    fs::path out;
    double smoothness = 10.0;
  };
  auto options = std::make_shared<Options>();
  CLI::App* command = calibrate.add_subcommand(
      "response",
      "Recover an 8-bit camera's response curve from an exposure series of a static scene "
      "(Debevec and Malik, OpenCV); `calibrate apply --response` linearises with it.");
  command->add_option("images", options->images, "The exposures (8-bit images)")->required();
  command
      ->add_option("--times", options->times,
                   "Exposure times, comma-separated, one per image (e.g. 1/30 as 0.0333)")
      ->required();
  command->add_option("--out", options->out, "Response curve JSON to write")->required();
  command->add_option("--smoothness", options->smoothness, "Debevec's lambda")
      ->capture_default_str();
  command->callback([options] {
    std::vector<double> times;
    std::string rest = options->times;
    while (!rest.empty()) {
      const auto comma = rest.find(',');
      const std::string token = rest.substr(0, comma);
      const auto value = ParseNumber(token);
      if (!value) throw Error(fmt::format("--times: '{}' is not a number", token));
      times.push_back(*value);
      rest = comma == std::string::npos ? "" : rest.substr(comma + 1);
    }
    if (times.size() != options->images.size()) {
      throw Error(
          fmt::format("--times: {} times for {} images", times.size(), options->images.size()));
    }
    ImageReadOptions codes;
    codes.colour_space = ColourSpace::kLinear;
    std::vector<Image> exposures;
    for (const fs::path& file : options->images) {
      LoadedImage loaded = ReadImage(file, codes);
      if (loaded.info.bits_per_sample != 8 || loaded.info.floating_point) {
        throw Error(file, "response recovery needs 8-bit images");
      }
      exposures.push_back(std::move(loaded.image));
    }
    const ResponseCurve curve = RecoverResponseDebevec(exposures, times, options->smoothness);
    WriteResponseCurve(options->out, curve);
    fmt::print("response curve ({}) -> {}\ncode:   ", curve.source(), options->out.string());
    for (int code : {32, 64, 128, 192, 255}) fmt::print("{:>8}", code);
    fmt::print("\nlinear: ");
    for (int code : {32, 64, 128, 192, 255}) fmt::print("{:>8.4f}", curve.table(0)[code]);
    fmt::print("\nsRGB:   ");
    for (int code : {32, 64, 128, 192, 255}) fmt::print("{:>8.4f}", SrgbToLinear(code / 255.0));
    fmt::print("\n");
  });
}

// IMPLEMENTER CHOICE: the rows `calibrate apply` corrects at a time: a band of every image, its
// corrected copies (each correction makes one; two are alive at once) and, with a flat-field or
// near lamps, the band's gain maps, as float; `budget` beyond the fixed buffers (the dark frame;
// a target's gain maps are read band by band from their folder, FlatFieldBandReader).
int ApplyBandRows(std::size_t budget, const StreamedSet& set, const CaptureCorrections& c) {
  const auto samples = static_cast<std::size_t>(set.size()) * set.channels();
  const std::size_t copies = 3 + (c.flat_field || c.near_lights ? 1 : 0);
  const std::size_t per_row = copies * samples * 4 * static_cast<std::size_t>(set.width());
  return static_cast<int>(std::clamp<std::size_t>(budget / std::max<std::size_t>(per_row, 1), 1,
                                                  static_cast<std::size_t>(set.height())));
}

// Semi-calibrated intensities of the corrected capture (EstimateLightIntensitiesRobust of the
// whole, as `calibrate intensities` estimates them): the estimate uses a few thousand sampled
// pixels only, so a first streamed pass corrects every band and keeps its sampled pixels
// (SemiCalibratedSamples), and the intensities come from those, bit for bit the whole capture's.
std::vector<std::vector<float>> SemiCalibratedIntensities(StreamedSet& set, int rows,
                                                          CaptureCorrections& corrections,
                                                          Progress& progress) {
  SemiCalibratedOptions options;
  options.weigher = RobustObservationWeigher();
  SemiCalibratedSamples samples(SemiCalibratedPixels(set.MaskRows(0, set.height()), options),
                                set.width());
  progress.Start("calibrate apply: samples for the intensities",
                 static_cast<std::size_t>((set.height() + rows - 1) / rows));
  for (int first = 0; first < set.height(); first += rows) {
    const int count = std::min(rows, set.height() - first);
    samples.Add(CorrectCaptureBand(set.ReadBand(count, true), first, set.height(), corrections),
                first);
    progress.Advance();
  }
  progress.Finish();
  return EstimateLightIntensitiesFromSamples(samples.samples(), options).intensities;
}

struct ApplyCommandOptions {
  fs::path input;
  fs::path out;
  fs::path response;
  fs::path dark;
  fs::path flat_field;
  fs::path near_lights;
  fs::path intensities;
  bool semi_calibrated = false;
  bool ignore_intensities = false;
  bool png16 = false;
  std::size_t memory_mb = 0;
};

void AddApplyOptions(CLI::App& command, ApplyCommandOptions& options) {
  command.add_option("input", options.input, "Photometric set")->required();
  command.add_option("--out", options.out, "Output folder")->required();
  command.add_option("--response", options.response,
                     "Response curve JSON (calibrate response): images are read as codes and "
                     "linearised with it instead of the default decoding");
  command.add_option("--dark", options.dark, "Dark frame: an image or a folder of them (mean)");
  command.add_option("--flat-field", options.flat_field, "Flat-field folder (calibrate flatfield)");
  command.add_option("--near-lights", options.near_lights,
                     "Lamp positions, \"x y z [intensity]\" a line in pixel units (origin at the "
                     "image centre, y up): divide by their inverse-square fall-off");
  command.add_option("--intensities", options.intensities,
                     "Light intensities file (\"r g b\" a line) to divide by");
  command.add_flag("--semi-calibrated", options.semi_calibrated,
                   "Estimate the intensities from the capture (calibrate intensities)");
  command.add_flag("--ignore-intensities", options.ignore_intensities,
                   "Do not divide by the intensities the input gives");
  command.add_flag("--png16", options.png16, "16-bit linear PNG (clips at 1) instead of float EXR");
  AddBandMemoryOption(command, options.memory_mb, "the bands of rows corrected at a time",
                      kMinimumApplyMemory);
}

// The corrections the options name, each recorded as a step of the output's provenance.
CaptureCorrections CorrectionsFor(const ApplyCommandOptions& options, const StreamedSet& set,
                                  nlohmann::json& steps) {
  CaptureCorrections corrections;
  if (!options.response.empty()) {
    corrections.response = ReadResponseCurve(options.response);
    steps.push_back({{"response", fs::absolute(options.response).generic_string()}});
  }
  if (!options.dark.empty()) {
    corrections.dark = ReadDarkFrame(options.dark);
    steps.push_back({{"dark", fs::absolute(options.dark).generic_string()}});
  }
  if (!options.flat_field.empty()) {
    corrections.flat_field.emplace(options.flat_field);
    steps.push_back({{"flat_field", fs::absolute(options.flat_field).generic_string()}});
  }
  if (!options.near_lights.empty()) {
    const auto lamps = ReadNearLights(options.near_lights);
    if (static_cast<int>(lamps.size()) != set.size()) {
      throw Error(options.near_lights,
                  fmt::format("{} lamps for {} images", lamps.size(), set.size()));
    }
    corrections.near_lights.emplace(lamps, set.width(), set.height(), set.channels());
    steps.push_back({{"near_lights", fs::absolute(options.near_lights).generic_string()}});
  }
  return corrections;
}

// The intensities each band is divided by, after the corrections: a file's, none, or (nullopt)
// the input's own; semi-calibrated ones are estimated later, in a pass of their own.
std::optional<std::vector<std::vector<float>>> IntensitiesFor(const ApplyCommandOptions& options,
                                                              const StreamedSet& set,
                                                              nlohmann::json& steps) {
  std::optional<std::vector<std::vector<float>>> intensities;
  if (!options.intensities.empty()) {
    intensities = ReadLightIntensities(options.intensities);
    steps.push_back({{"intensities", fs::absolute(options.intensities).generic_string()}});
  } else if (options.ignore_intensities) {
    intensities.emplace();
  } else if (options.semi_calibrated) {
    steps.push_back({{"intensities", "semi-calibrated"}});
  } else if (!set.intensities().empty()) {
    steps.push_back({{"intensities", "the input's"}});
  }
  return intensities;
}

void RunApply(const ApplyCommandOptions& options) {
  const int sources = !options.intensities.empty() + options.semi_calibrated;
  if (sources > 1) throw Error("give at most one of --intensities and --semi-calibrated");
  if (!options.flat_field.empty() && !options.near_lights.empty()) {
    throw Error("give at most one of --flat-field and --near-lights");
  }
  LoadOptions load;
  load.apply_intensities = false;
  if (!options.response.empty()) load.colour_space = ColourSpace::kLinear;
  StreamedSet set = OpenStreamedSet(options.input, load);
  nlohmann::json steps = nlohmann::json::array();
  CaptureCorrections corrections = CorrectionsFor(options, set, steps);
  std::optional<std::vector<std::vector<float>>> intensities = IntensitiesFor(options, set, steps);
  SaveSetOptions save;
  save.sample_type = options.png16 ? SampleType::kUint16 : SampleType::kFloat;
  save.provenance = {{"source", fs::absolute(options.input).generic_string()},
                     {"calibration", steps}};
  const std::size_t bytes_per_sample = options.png16 ? 2 : 4;
  CheckDiskSpace(options.out,
                 static_cast<std::size_t>(set.size()) * set.channels() * bytes_per_sample *
                     static_cast<std::size_t>(set.width()) * set.height(),
                 "the corrected capture");
  const std::size_t budget =
      options.memory_mb > 0 ? options.memory_mb << 20 : DefaultBandBudget(kMinimumApplyMemory);
  const int rows = ApplyBandRows(budget, set, corrections);
  const std::size_t bands = static_cast<std::size_t>((set.height() + rows - 1) / rows);
  TerminalProgressBar bar;
  if (options.semi_calibrated) {
    intensities = SemiCalibratedIntensities(set, rows, corrections, bar);
    set.Rewind();
    // The flat-field's gain maps are read again, from the top.
    if (!options.flat_field.empty()) corrections.flat_field.emplace(options.flat_field);
  }
  CaptureBandWriter writer(options.out, set.height(), save);
  bar.Start("calibrate apply", bands);
  while (writer.rows_written() < set.height()) {
    const int first = writer.rows_written();
    PhotometricSet band = CorrectCaptureBand(
        set.ReadBand(std::min(rows, set.height() - first), true), first, set.height(), corrections);
    if (intensities) band.set_intensities(*intensities);
    band.ApplyIntensities();
    writer.WriteNext(band);
    bar.Advance();
  }
  bar.Finish();
  WarnAboutClippedPixels(set.SaturatedPixels(), set.image_names());
  CaptureManifest manifest = writer.Finish();
  if (set.ground_truth_normals()) {
    manifest.ground_truth_normals = fs::absolute(*set.ground_truth_normals()).generic_string();
    WriteCaptureManifest(options.out / kCaptureManifestName, manifest);
  }
  fmt::print("{} images, {} step(s), bands of {} rows -> {}\n", set.size(), steps.size(), rows,
             options.out.string());
}

void AddApplyCommand(CLI::App& calibrate) {
  CLI::App* command = calibrate.add_subcommand(
      "apply",
      "Write a corrected copy of a capture: linearise (--response), subtract a dark frame, "
      "divide by a flat-field (a target's or near lamps'), and by light intensities (a file, "
      "semi-calibrated estimates, or the input's own); the result is a manifest set. Streamed "
      "in bands of rows (two passes with --semi-calibrated: its samples, then the copy).");
  BindCommand(*command, AddApplyOptions, RunApply);
}

}  // namespace

void AddCalibrateCommand(CLI::App& app) {
  CLI::App* calibrate = AddListedCommand(app, "calibrate");
  calibrate->require_subcommand(1);
  AddLightsCommand(*calibrate);
  AddFlatFieldCommand(*calibrate);
  AddIntensitiesCommand(*calibrate);
  AddResponseCommand(*calibrate);
  AddApplyCommand(*calibrate);
}

}  // namespace photomat::app
