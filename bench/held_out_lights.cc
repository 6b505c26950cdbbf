// Relighting lights that were not captured (issue 19): photomat against relight-cli in one run.
// For each set (default: DiLiGenT cat and ball from $PHOTOMAT_TEST_DATA, and the synthetic
// specular captures synthetic:phong and synthetic:ggx, MakeSyntheticCapture) and each hold-out
// (every K-th light from the first, for each K of --every, default 8 and 10; and a whole slant
// ring, the middle one, where the lights lie on rings of equal slant), every method is fitted on
// the other lights and relit at the held-out ones; relight-cli (when available) builds its rbf,
// bilinear, ptm and hsh folders from the same training images, and photomat's reader relights those
// folders at the same lights (in floats: relight-cli's own -L rendering truncates to bytes, which
// would cost it about 0.2 dB more).
//
// Inputs (default): the photographs as linear 8-bit JPEGs, quality 95 (the 16-bit linear PNG
// values quantised to 8 bits with no transfer curve, no light intensities divided out, as
// bench/peer_table makes them): relight-cli reads them with `-I srgb`, which keeps it from
// re-encoding them (its default converts "sRGB" codes to linear in 8 bits), and photomat reads
// them as linear codes. PSNR (MaskedPsnr, peak 1 = code 255) over the mask and every channel,
// SSIM and mean CIEDE2000 of the sRGB renderings (MaskedSsim, MaskedMeanDeltaE2000), against the
// held-out JPEGs themselves; the means over the held-out lights. Beside them the stored size
// (photomat's float stack as `fit` writes it, relight-cli's folder) and the fit's wall time
// (photomat's fit of the loaded set in this process; relight-cli's and the neural basis's whole
// command, reading the images included). The methods' default list ends with `neural`, trained by
// `photomat fit` (NeuralRow; about 2.5 minutes per hold-out of a DiLiGenT object on 2 cores).
// --float: photomat alone on the original 16-bit images with the light intensities divided out,
// peak = the capture's largest value (the README's first held-out table).
// --calibrated: also the same hold-outs on JPEGs with the lamps' intensities divided out, for
// both tools (PrintCalibratedTables; a diagnosis beside the issue's comparison, which stays the
// raw JPEGs'), photomat alone with them divided out in floats, and photomat with only the
// training lamps' divided out and the held-out lamps' predicted from them
// (PrintPredictedBrightnessTable).
//
//   held_out_lights [SET|synthetic:phong|synthetic:ggx ...] [--every K[,K...]]
//                   [--methods ptm,hsh9,rbf,bilinear,neural,rbf:-1,...]
//                   [--float] [--relight-cli PATH|none] [--planes N] [--grid-size G]
//                   [--rbf-width DEG] [--rbf-regularisation R] [--rbf-tail affine|quadratic]
//                   [--leave-out one|block|edge|side] [--calibrated]
//                   [--neural-options "--neural-epochs 150 ..."]
//   held_out_lights SET --oracle [--residual-of METHOD] | --clamped-score | --blend [--planes -1]
//                   | --polyharmonic (diagnoses: bench/held_out_diagnoses.h)
//
// A method NAME:K fits with K PCA planes per channel (0: uncompressed, -1: chosen by leave-one-out
// on the training lights); a suffix +block, +edge or +side chooses by leave-block-out,
// leave-edge-out or leave-side-out, +quadratic gives rbf the quadratic tail
// (rbf:-1+block+quadratic); the other options apply
// to every light-profile method. relight-cli: --relight-cli, else $PHOTOMAT_RELIGHT_CLI, else the
// build bench/peer_table leaves in ~/.cache/photomat-peers/relight-build.
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>
#include <unistd.h>

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "bench/held_out_diagnoses.h"
#include "bench/relight_cli_peer.h"
#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/error.h"
#include "core/light_direction.h"
#include "relight/formats/stack_file.h"
#include "represent/evaluation/evaluation.h"
#include "represent/evaluation/image_comparison.h"
#include "represent/fitting/fit.h"
#include "represent/fitting/light_profile_fit.h"
#include "represent/fitting/observations.h"
#include "represent/model/light_profile_basis.h"
#include "represent/stack/map_stack.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

// The synthetic specular captures, made here (MakeSyntheticCapture) when a set is named so.
constexpr const char* kSyntheticPhong = "synthetic:phong";
constexpr const char* kSyntheticGgx = "synthetic:ggx";

struct Arguments {
  std::vector<fs::path> sets;
  // IMPLEMENTER CHOICE: every 8th and every 10th light. On DiLiGenT's grid of 12 columns of 8
  // lights every 8th is one whole edge row (extrapolation only), every 10th is 10 lights spread
  // over the grid (the issue's own measurement held out 10), so both are reported.
  std::vector<int> every{8, 10};
  std::string methods = "ptm,hsh9,rbf,bilinear,neural";
  bool linear_jpeg = true;
  bool calibrated = false;
  bool oracle = false;
  bool clamped_score = false;
  bool blend = false;
  bool polyharmonic = false;
  std::optional<std::string> residual_of;
  std::optional<fs::path> relight_cli;
  LightProfileOptions profile;
  // Appended to `photomat fit --method neural` (its own options; empty: the defaults).
  std::string neural_options;
};

Arguments Parse(int argc, char** argv) {
  Arguments arguments;
  arguments.relight_cli = FindRelightCli();
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error(fmt::format("{} needs a value", a));
      return argv[++i];
    };
    if (a == "--every") {
      arguments.every.clear();
      std::stringstream list(value());
      for (std::string k; std::getline(list, k, ',');) arguments.every.push_back(std::stoi(k));
    } else if (a == "--methods") {
      arguments.methods = value();
    } else if (a == "--oracle") {
      arguments.oracle = true;
    } else if (a == "--blend") {
      arguments.blend = true;
    } else if (a == "--polyharmonic") {
      arguments.polyharmonic = true;
    } else if (a == "--clamped-score") {
      arguments.clamped_score = true;
    } else if (a == "--residual-of") {
      arguments.residual_of = value();
    } else if (a == "--calibrated") {
      arguments.calibrated = true;
    } else if (a == "--neural-options") {
      arguments.neural_options = value();
    } else if (a == "--float") {
      arguments.linear_jpeg = false;
    } else if (a == "--relight-cli") {
      const std::string path = value();
      arguments.relight_cli = path == "none" ? std::nullopt : std::optional<fs::path>(path);
    } else if (a == "--planes") {
      arguments.profile.planes = std::stoi(value());
    } else if (a == "--grid-size") {
      arguments.profile.grid_size = std::stoi(value());
    } else if (a == "--rbf-width") {
      arguments.profile.rbf_width_degrees = std::stod(value());
    } else if (a == "--rbf-regularisation") {
      arguments.profile.rbf_regularisation = std::stod(value());
    } else if (a == "--rbf-tail") {
      arguments.profile.rbf_tail = RbfTailFromString(value());
    } else if (a == "--leave-out") {
      const std::string scheme = value();
      if (scheme != "one" && scheme != "block" && scheme != "edge" && scheme != "side") {
        throw Error("--leave-out: expected one, block, edge or side");
      }
      arguments.profile.leave_out = scheme == "block"  ? LeaveOut::kBlock
                                    : scheme == "edge" ? LeaveOut::kEdge
                                    : scheme == "side" ? LeaveOut::kSide
                                                       : LeaveOut::kOne;
    } else if (a.starts_with("--")) {
      throw Error(fmt::format("unknown option {}", a));
    } else {
      arguments.sets.push_back(a);
    }
  }
  if (arguments.sets.empty()) {
    const char* data = std::getenv("PHOTOMAT_TEST_DATA");
    if (!data) throw Error("no set given and PHOTOMAT_TEST_DATA is not set");
    for (const char* object : {"cat", "ball"}) {
      arguments.sets.push_back(fs::path(data) / "diligent" / object);
    }
    arguments.sets.emplace_back(kSyntheticPhong);
    arguments.sets.emplace_back(kSyntheticGgx);
  }
  if (arguments.calibrated && !arguments.linear_jpeg) {
    throw Error("--calibrated compares the two tools on JPEGs; it cannot go with --float");
  }
  if (arguments.every.empty() ||
      *std::min_element(arguments.every.begin(), arguments.every.end()) < 2) {
    throw Error("--every must list values of at least 2");
  }
  return arguments;
}

// "NAME" or "NAME:K" (K PCA planes per channel) with the common profile options.
std::vector<Method> ParseMethods(const std::string& list, const LightProfileOptions& profile) {
  std::vector<Method> methods;
  for (std::size_t start = 0; start <= list.size();) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string item = list.substr(start, comma - start);
    start = comma + 1;
    // Suffixes "+block", "+edge" (LeaveOut::kBlock, kEdge) and "+quadratic" (the RBF's quadratic
    // tail).
    std::string name = item;
    LightProfileOptions options = profile;
    for (const auto& [suffix, apply] : std::vector<std::pair<std::string, std::function<void()>>>{
             {"+block", [&] { options.leave_out = LeaveOut::kBlock; }},
             {"+edge", [&] { options.leave_out = LeaveOut::kEdge; }},
             {"+side", [&] { options.leave_out = LeaveOut::kSide; }},
             {"+quadratic", [&] { options.rbf_tail = RbfTail::kQuadratic; }}}) {
      if (const std::size_t at = name.find(suffix); at != std::string::npos) {
        name.erase(at, suffix.size());
        apply();
      }
    }
    const std::size_t colon = name.find(':');
    Method method = Method::Parse(name.substr(0, colon));
    method.profile = options;
    if (colon != std::string::npos) method.profile.planes = std::stoi(name.substr(colon + 1));
    methods.push_back(method);
  }
  return methods;
}

// The method's name; with `:K` for rbf and bilinear (K = -1: planes chosen by leave-one-out, 0: no
// PCA). The planes a fit took are printed from its details.
std::string MethodLabel(const Method& method) {
  const bool profile = method.kind == Method::Kind::kRbf || method.kind == Method::Kind::kBilinear;
  if (!profile) return method.Name();
  std::string label = method.Name();
  if (method.profile.planes != LightProfileOptions::kDefaultPlanes) {
    label += fmt::format(":{}", method.profile.planes);
  }
  if (method.profile.leave_out == LeaveOut::kBlock) label += "+block";
  if (method.profile.leave_out == LeaveOut::kEdge) label += "+edge";
  if (method.profile.leave_out == LeaveOut::kSide) label += "+side";
  if (method.kind == Method::Kind::kRbf && method.profile.rbf_tail == RbfTail::kQuadratic) {
    label += "+quadratic";
  }
  return label;
}

std::vector<HoldOut> HoldOuts(const std::vector<LightDirection>& lights,
                              const std::vector<int>& everies) {
  std::vector<HoldOut> hold_outs;
  for (int every : everies) {
    HoldOut hold_out{fmt::format("every {}th", every), {}, {}};
    for (int i = 0; i < static_cast<int>(lights.size()); ++i) {
      (i % every == 0 ? hold_out.held_out : hold_out.selected).push_back(i);
    }
    hold_outs.push_back(std::move(hold_out));
  }
  const LightInterpolator interpolator(lights);
  if (interpolator.scheme() == LightInterpolator::Scheme::kSlantRings &&
      interpolator.rings().size() >= 3) {
    const auto& ring = interpolator.rings()[interpolator.rings().size() / 2];
    HoldOut slant{fmt::format("slant ring {:.0f} deg", ring.slant), {}, {}};
    for (const auto& [tilt, node] : ring.by_tilt) slant.held_out.push_back(node);
    std::sort(slant.held_out.begin(), slant.held_out.end());
    for (int i = 0; i < static_cast<int>(lights.size()); ++i) {
      if (!std::binary_search(slant.held_out.begin(), slant.held_out.end(), i)) {
        slant.selected.push_back(i);
      }
    }
    hold_outs.push_back(std::move(slant));
  }
  return hold_outs;
}

// The set as both tools see it: linear 8-bit JPEGs (quality 95) of the raw photographs, with a
// .lp of every light, read back as linear codes / 255.
void WriteLinearJpeg(const fs::path& path, const Image& image) {
  const std::size_t pixels = image.pixel_count();
  const int channels = image.channels();
  std::vector<std::uint8_t> bytes(pixels * channels);
  for (int c = 0; c < channels; ++c) {
    const auto plane = image.plane(c);
    for (std::size_t p = 0; p < pixels; ++p) {
      bytes[p * channels + c] =
          static_cast<std::uint8_t>(std::lround(std::clamp(plane[p], 0.0f, 1.0f) * 255.0f));
    }
  }
  auto output = OIIO::ImageOutput::create(path.string());
  OIIO::ImageSpec spec(image.width(), image.height(), channels, OIIO::TypeDesc::UINT8);
  spec.attribute("Compression", "jpeg:95");
  if (!output || !output->open(path.string(), spec) ||
      !output->write_image(OIIO::TypeDesc::UINT8, bytes.data()) || !output->close()) {
    throw Error(path, "cannot write the JPEG");
  }
}

void WriteLightPositions(const fs::path& path, const PhotometricSet& set,
                         const std::vector<int>& images) {
  std::ofstream lp(path);
  lp << images.size() << "\n";
  for (int i : images) {
    const LightDirection& l = set.light(i);
    lp << fmt::format("img{:03d}.jpg {:.6f} {:.6f} {:.6f}\n", i, l.x(), l.y(), l.z());
  }
  if (!lp) throw Error(path, "cannot write the light positions");
}

PhotometricSet LinearJpegSet(const PhotometricSet& raw, const fs::path& folder) {
  fs::create_directories(folder);
  std::vector<int> every(raw.size());
  for (int i = 0; i < raw.size(); ++i) {
    every[i] = i;
    WriteLinearJpeg(folder / fmt::format("img{:03d}.jpg", i), raw.images()[i]);
  }
  WriteLightPositions(folder / "all.lp", raw, every);
  LoadOptions options;
  options.colour_space = ColourSpace::kLinear;
  PhotometricSet set = LoadPhotometricSet(folder / "all.lp", options).set;
  fs::remove(folder / "all.lp");
  set.set_mask(raw.MaskOrAll());
  return set;
}

// The photographs with their lamps' intensities divided out, written as linear 8-bit JPEGs that
// both tools read: image i, channel c is raw / scale[i][c], where scale = intensity / k and k is
// the largest factor that clips no sample (so no image is clipped and the brightest calibrated
// sample is code 255).
struct CalibratedJpegs {
  PhotometricSet set;                     // the JPEGs read back
  std::vector<std::vector<float>> scale;  // per image and channel: raw = set x scale
  fs::path folder;                        // where they are
};

CalibratedJpegs CalibratedJpegSet(const PhotometricSet& raw, const fs::path& folder) {
  PhotometricSet calibrated = raw;
  calibrated.ApplyIntensities();
  float largest = 0.0f;
  for (const Image& image : calibrated.images()) {
    for (float v : image.values()) largest = std::max(largest, v);
  }
  std::vector<std::vector<float>> scale = raw.intensities();
  for (auto& row : scale) {
    for (float& v : row) v *= largest;
  }
  std::vector<Image> images;
  for (int i = 0; i < raw.size(); ++i) {
    Image image = calibrated.images()[i];
    for (float& v : image.values()) v /= largest;
    images.push_back(std::move(image));
  }
  PhotometricSet normalised(std::move(images), raw.lights());
  normalised.set_mask(raw.MaskOrAll());
  return {LinearJpegSet(normalised, folder), std::move(scale), folder};
}

// The means over the held-out lights of the three comparisons (represent/evaluation/
// image_comparison.h): PSNR of the linear values, SSIM and CIEDE2000 of the sRGB renderings.
struct Scores {
  double psnr = 0.0, ssim = 0.0, delta_e = 0.0;
};

struct Row {
  std::string tool, method;
  int planes = 0;
  Scores scores;
  // What the benchmark measured where it could (the issue's table): the stored size in bytes
  // (photomat: the float stack as `photomat fit` writes it; relight-cli: its folder) and the
  // fit's wall time in seconds.
  std::optional<std::uintmax_t> bytes;
  std::optional<double> seconds;
  std::string failure = {};  // not empty: the method could not be fitted, and why
};

// With `scale` (per image, per channel), each relit image is multiplied by its light's scale
// before it is compared: a representation fitted to intensity-calibrated images predicts a
// photograph of a held-out lamp as its relit image times that lamp's intensity.
Scores MeanScores(const Representation& r, const PhotometricSet& set,
                  const std::vector<int>& lights, double peak,
                  const std::vector<std::vector<float>>& scale = {}) {
  Scores total;
  const Mask mask = set.MaskOrAll();
  for (int i : lights) {
    Image predicted = r.Relight(set.light(i));
    if (!scale.empty()) {
      for (int c = 0; c < predicted.channels(); ++c) {
        for (float& v : predicted.plane(c)) v *= scale[i][static_cast<std::size_t>(c)];
      }
    }
    total.psnr += MaskedPsnr(predicted, set.images()[i], mask, peak);
    total.ssim += MaskedSsim(predicted, set.images()[i], mask, peak);
    total.delta_e += MaskedMeanDeltaE2000(predicted, set.images()[i], mask, peak);
  }
  const auto n = static_cast<double>(lights.size());
  return {total.psnr / n, total.ssim / n, total.delta_e / n};
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The last line of `log` that is not empty (what a failed command said last).
std::string LastLine(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  return last;
}

// A command run with its output in `log`: its wall time, or why it failed (the command and the
// last line it wrote).
struct CommandRun {
  double seconds = 0.0;
  std::string failure;  // empty: it succeeded
};

CommandRun RunLogged(const std::string& command, const fs::path& log) {
  const auto start = std::chrono::steady_clock::now();
  if (std::system(fmt::format("{} > {} 2>&1", command, log.string()).c_str()) != 0) {
    return {0.0, fmt::format("{}: {}", command, LastLine(log))};
  }
  return {SecondsSince(start), ""};
}

// The size of `r` as `photomat fit` stores it: its float stack, rle-compressed as fit's default
// does for a masked set (`--exr-compression auto`).
std::uintmax_t StackBytes(const Representation& r, const fs::path& work) {
  const fs::path path = work / "stack.exr";
  SaveRepresentation(path, r, StackProvenance{}, ExrCompression::kRle);
  const std::uintmax_t bytes = fs::file_size(path);
  fs::remove(path);
  return bytes;
}

// relight-cli's four bases (RelightCliArguments), `-I srgb`.
std::vector<Row> RelightCliRows(const fs::path& relight_cli, const PhotometricSet& set,
                                const fs::path& jpegs, const HoldOut& hold_out,
                                const fs::path& work,
                                const std::vector<std::vector<float>>& scale = {}) {
  const fs::path training = work / "training";
  fs::remove_all(training);
  fs::create_directories(training);
  for (int i : hold_out.selected) {
    const std::string name = fmt::format("img{:03d}.jpg", i);
    fs::create_symlink(jpegs / name, training / name);
  }
  WriteLightPositions(training / "lights.lp", set, hold_out.selected);
  std::vector<Row> rows;
  for (const std::string basis : {"ptm", "hsh", "rbf", "bilinear"}) {
    const std::string arguments = RelightCliArguments(basis);
    const fs::path folder = work / ("relight-" + basis);
    fs::remove_all(folder);
    const CommandRun run = RunLogged(fmt::format("{} {} -I srgb {} {}", relight_cli.string(),
                                                 arguments, training.string(), folder.string()),
                                     work / "relight-cli.log");
    Row row{"relight-cli", fmt::format("{} ({})", basis, arguments), 0, {}, {}, {}};
    if (!run.failure.empty()) {
      row.failure = run.failure;
      rows.push_back(std::move(row));
      continue;
    }
    const LoadedStack stack = LoadStackFile(folder);
    row.planes = stack.representation.maps().channels();
    row.scores = MeanScores(stack.representation, set, hold_out.held_out, 1.0, scale);
    row.bytes = StoredBytes(folder);
    row.seconds = run.seconds;
    rows.push_back(std::move(row));
  }
  return rows;
}

// The neural basis, trained by `photomat fit --method neural` (photomat-neural, the one program
// that loads libtorch; PHOTOMAT_BINARY, else the photomat beside this program) with its defaults
// and `options` (--neural-options), on the training lights' images written as a photomat capture
// (float EXR: the values the other methods fit, the set's mask), its stack loaded back here. Its
// time is the whole command's (the images read, libtorch loaded, the training, the stack written).
// Nothing when the fit fails (a build without libtorch): a row that says why.
Row NeuralRow(const PhotometricSet& set, const HoldOut& hold_out, double peak,
              const std::string& options, const fs::path& work) {
  const fs::path training = work / "neural-training", out = work / "neural-fit";
  fs::remove_all(training);
  fs::remove_all(out);
  SaveSetOptions save;
  save.sample_type = SampleType::kFloat;
  SavePhotometricSet(training, set.Subset(hold_out.selected), save);
  const char* binary = std::getenv("PHOTOMAT_BINARY");
  const fs::path photomat =
      binary ? fs::path(binary) : fs::read_symlink("/proc/self/exe").parent_path() / "photomat";
  const CommandRun run =
      RunLogged(fmt::format("{} fit {} --method neural --out {} {}", photomat.string(),
                            training.string(), out.string(), options),
                work / "neural.log");
  const std::string label = options.empty() ? "neural" : fmt::format("neural {}", options);
  if (!run.failure.empty()) {
    Row row{"photomat", label, 0, {}, {}, {}};
    row.failure = run.failure;
    return row;
  }
  const fs::path stack = out / "neural.exr";
  const LoadedStack loaded = LoadStackFile(stack);
  const nlohmann::json& report = loaded.representation.details()["neural_training"];
  Row row{"photomat",
          fmt::format("{} [{} epochs, best {}, training {:.0f} s]", label, report["epochs"].dump(),
                      report["best_epoch"].dump(), report["seconds"].get<double>()),
          loaded.representation.maps().channels(),
          MeanScores(loaded.representation, set, hold_out.held_out, peak),
          StoredBytes(stack),
          run.seconds};
  fs::remove_all(training);
  fs::remove_all(out);
  return row;
}

// `issue_target`: the table is the issue's comparison (the raw JPEGs of DiLiGenT cat or ball),
// which prints the target's verdict; other tables (--calibrated, other sets) print their best rows
// and the margin only.
void PrintTable(const std::string& title, const std::vector<Row>& rows, bool issue_target) {
  fmt::print(
      "\n{}\n| tool | method | maps | PSNR dB | SSIM | mean Delta E 2000 | stored MB | fit s |\n"
      "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
      title);
  const Row* ours = nullptr;
  const Row* theirs = nullptr;
  for (const Row& row : rows) {
    if (!row.failure.empty()) {
      fmt::print("| {} | {} | - | not fitted: {} | - | - | - | - |\n", row.tool, row.method,
                 row.failure);
      continue;
    }
    fmt::print("| {} | {} | {} | {:.2f} | {:.4f} | {:.3f} | {} | {} |\n", row.tool, row.method,
               row.planes, row.scores.psnr, row.scores.ssim, row.scores.delta_e,
               row.bytes ? fmt::format("{:.2f}", *row.bytes / 1e6) : "-",
               row.seconds ? fmt::format("{:.2f}", *row.seconds) : "-");
    const Row*& best = row.tool == "photomat" ? ours : theirs;
    if (!best || row.scores.psnr > best->scores.psnr) best = &row;
  }
  if (ours && theirs) {
    const double margin = ours->scores.psnr - theirs->scores.psnr;
    fmt::print("best: photomat {} {:.2f} dB, relight-cli {} {:.2f} dB: {:+.2f} dB\n", ours->method,
               ours->scores.psnr, theirs->method, theirs->scores.psnr, margin);
    if (!issue_target) return;
    if (margin >= 1.0) {
      fmt::print("target met: at least 1 dB above relight-cli's best\n");
    } else {
      fmt::print(
          "EXPECTED FAILURE: target \"photomat's best at least 1 dB PSNR above relight-cli's "
          "best\" not met (measured {:+.2f} dB, {:.2f} dB short) because no method photomat "
          "chooses on the training lights predicts these held-out lights better (on DiLiGenT ball "
          "an rbf set by hand would; no score on the training lights, leave-side-out and the "
          "rbf/bilinear blend (--blend) included, picks it; with the lamps' intensities divided "
          "out "
          "(--calibrated) both tools reach about the same PSNR on ball: README \"Relighting "
          "held-out lights against relight-cli\")\n",
          margin, 1.0 - margin);
    }
  }
}

// The best a tool could do that calibrated its lamps itself from the photographs: the training
// lamps' published intensities divided out exactly, the held-out lamps' predicted from them (a
// polyharmonic spline of the log intensity over the light directions, per channel). The held-out
// lamps' own intensities choose the spline (ORACLE: this bounds such a tool from above, it is not
// a method), and the prediction's relative error is printed for each spline.
template <typename PhotomatRows>
void PrintPredictedBrightnessTable(const PhotometricSet& set,
                                   const std::vector<std::vector<float>>& published,
                                   const HoldOut& hold_out, const fs::path& path,
                                   const PhotomatRows& photomat_rows) {
  const std::vector<LightDirection> training = LightsOf(set.lights(), hold_out.selected);
  const std::vector<LightDirection> held = LightsOf(set.lights(), hold_out.held_out);
  std::vector<std::vector<float>> best;
  double best_error = std::numeric_limits<double>::infinity();
  for (int order : {1, 2, 3}) {
    for (double regularisation : {0.0, 1e-3, 1e-2, 1e-1}) {
      const Eigen::MatrixXd w = PolyharmonicWeights(training, held, order, regularisation);
      std::vector<std::vector<float>> predicted = published;
      double squared = 0.0;
      for (std::size_t c = 0; c < published.front().size(); ++c) {
        Eigen::VectorXd log_training(static_cast<Eigen::Index>(training.size()));
        for (std::size_t t = 0; t < hold_out.selected.size(); ++t) {
          log_training[static_cast<Eigen::Index>(t)] =
              std::log(published[static_cast<std::size_t>(hold_out.selected[t])][c]);
        }
        const Eigen::VectorXd log_held = w * log_training;
        for (std::size_t h = 0; h < hold_out.held_out.size(); ++h) {
          const auto i = static_cast<std::size_t>(hold_out.held_out[h]);
          predicted[i][c] = static_cast<float>(std::exp(log_held[static_cast<Eigen::Index>(h)]));
          squared += std::pow(predicted[i][c] / published[i][c] - 1.0, 2);
        }
      }
      const double error =
          std::sqrt(squared / static_cast<double>(held.size() * published.front().size()));
      fmt::print(
          "held-out lamps' intensity from the training lamps', polyharmonic order {} "
          "regularisation {}: relative RMS error {:.3f}\n",
          order, regularisation, error);
      if (error < best_error) {
        best_error = error;
        best = predicted;
      }
    }
  }
  PhotometricSet divided = set;
  divided.set_intensities(best);
  divided.ApplyIntensities();
  PrintTable(
      fmt::format("{}, {} held out ({}), photomat on the raw JPEGs with the training "
                  "lamps' intensities divided out, the held-out lamps' predicted (error "
                  "{:.3f}, ORACLE choice of spline)",
                  path.filename().string(), hold_out.held_out.size(), hold_out.name, best_error),
      photomat_rows(divided, best), false);
}

// --calibrated (diagnosis): the same hold-out with each lamp's published intensity divided out.
// DiLiGenT's lamps differ in brightness by up to 6 times (ball: 0.30 to 1.76), so a tool that
// interpolates the raw photographs must also guess the held-out lamp's brightness from its
// neighbours'. Here both tools read the calibrated JPEGs (CalibratedJpegSet) and each prediction
// is multiplied by its lamp's scale before it is compared with the raw held-out JPEG; photomat
// alone also fits the raw JPEGs with the intensities divided out in floats (what `fit` does with a
// capture that gives intensities; relight's .lp has no field for them).
void PrintCalibratedTables(const CalibratedJpegs& calibrated, const PhotometricSet& raw,
                           const PhotometricSet& set, const std::vector<Method>& methods,
                           const HoldOut& hold_out, const Arguments& arguments,
                           const fs::path& work, const fs::path& path) {
  // photomat's rows: each method fitted to `fitted`, its predictions times `scale` scored against
  // the raw held-out JPEGs.
  const auto photomat_rows = [&](const PhotometricSet& fitted,
                                 const std::vector<std::vector<float>>& scale) {
    const Observations observations(fitted);
    std::vector<Row> rows;
    for (const Method& method : methods) {
      if (method.kind == Method::Kind::kNeural) continue;  // trained for the issue's table only
      const Representation r =
          FitObservations(observations, set.lights(), method, hold_out.selected, path);
      rows.push_back({"photomat", MethodLabel(method), r.maps().channels(),
                      MeanScores(r, set, hold_out.held_out, 1.0, scale), std::nullopt,
                      std::nullopt});
    }
    return rows;
  };
  std::vector<Row> rows = photomat_rows(calibrated.set, calibrated.scale);
  if (arguments.relight_cli) {
    const auto theirs = RelightCliRows(*arguments.relight_cli, set, calibrated.folder, hold_out,
                                       work, calibrated.scale);
    rows.insert(rows.end(), theirs.begin(), theirs.end());
  }
  PrintTable(fmt::format("{}, {} held out ({}), both tools on the calibrated JPEGs",
                         path.filename().string(), hold_out.held_out.size(), hold_out.name),
             rows, false);
  PhotometricSet divided = set;
  divided.set_intensities(raw.intensities());
  const std::vector<std::vector<float>> intensities = divided.intensities();
  divided.ApplyIntensities();
  PrintTable(fmt::format("{}, {} held out ({}), photomat on the raw JPEGs with the intensities "
                         "divided out",
                         path.filename().string(), hold_out.held_out.size(), hold_out.name),
             photomat_rows(divided, intensities), false);
  PrintPredictedBrightnessTable(set, raw.intensities(), hold_out, path, photomat_rows);
}

// One method of photomat fitted to the training lights and scored on the held-out ones, with the
// choices its fit made (planes, widths) in its label. A method the training lights cannot
// determine (hsh9 on two slant rings) is a row that says why.
Row PhotomatRow(const Observations& observations, const PhotometricSet& set, const Method& method,
                const HoldOut& hold_out, double peak, const fs::path& work, const fs::path& path) {
  const auto start = std::chrono::steady_clock::now();
  std::optional<Representation> fitted;
  try {
    fitted = FitObservations(observations, set.lights(), method, hold_out.selected, path);
  } catch (const Error& error) {
    Row row{"photomat", MethodLabel(method), 0, {}, std::nullopt, std::nullopt};
    row.failure = error.what();
    return row;
  }
  const double seconds = SecondsSince(start);
  const Representation& r = *fitted;
  Row row{"photomat",          MethodLabel(method),
          r.maps().channels(), MeanScores(r, set, hold_out.held_out, peak),
          StackBytes(r, work), seconds};
  if (r.details().contains("pca")) {
    row.method += fmt::format(" [planes {}]", r.details()["pca"]["planes"].dump());
  }
  if (r.details().contains("bilinear")) {
    const nlohmann::json& bilinear = r.details()["bilinear"];
    row.method += fmt::format(
        " [smoothness {:.3g}, grid {}, score {:.3f} dB]", bilinear["smoothness"].get<double>(),
        bilinear["grid_size"].get<int>(),
        bilinear["mean_snr_db"].is_number() ? bilinear["mean_snr_db"].get<double>() : std::nan(""));
  }
  if (r.details().contains("rbf")) {
    const nlohmann::json& rbf = r.details()["rbf"];
    row.method += fmt::format(" [width {:.3g} deg, regularisation {:.3g}, tail {}]",
                              rbf["width_deg"].get<double>(), rbf["regularisation"].get<double>(),
                              rbf["tail"].get<std::string>());
  }
  return row;
}

void RunSet(const fs::path& path, const Arguments& arguments, const fs::path& work) {
  LoadOptions raw_options;
  raw_options.apply_intensities = !arguments.linear_jpeg;
  const LoadedSet raw = LoadPhotometricSet(path, raw_options);
  const fs::path jpegs = work / "jpegs";
  const PhotometricSet set =
      arguments.linear_jpeg ? LinearJpegSet(raw.set, jpegs) : PhotometricSet(raw.set);
  std::optional<CalibratedJpegs> calibrated;
  // Only a capture that publishes its lamps' intensities (DiLiGenT) has them to divide out.
  if (arguments.calibrated && !raw.set.intensities().empty()) {
    calibrated = CalibratedJpegSet(raw.set, work / "calibrated-jpegs");
  }
  const Observations observations(set);
  const double peak = arguments.linear_jpeg ? 1.0 : double{observations.matrix().maxCoeff()};
  fmt::print("\n{}: {} images, {} pixels in the mask, {}; PSNR peak {:.4g}\n", path.string(),
             set.size(), observations.pixels(),
             arguments.linear_jpeg ? "linear 8-bit JPEGs q95" : "16-bit, intensities divided out",
             peak);
  const std::vector<Method> methods = ParseMethods(arguments.methods, arguments.profile);
  for (const HoldOut& hold_out : HoldOuts(set.lights(), arguments.every)) {
    if (arguments.blend) {
      PrintBlend(observations, set.lights(), hold_out, peak, arguments.profile);
      continue;
    }
    if (arguments.polyharmonic) {
      PrintPolyharmonic(observations, set.lights(), hold_out, peak);
      continue;
    }
    if (arguments.clamped_score) {
      PrintClampedScores(observations, set.lights(), hold_out, peak);
      continue;
    }
    if (arguments.oracle && arguments.residual_of) {
      // The same, on what a base method fitted to the training lights leaves (its prediction
      // plus the interpolated residual predicts a held-out light; errors as above).
      const Representation base =
          FitObservations(observations, set.lights(), Method::Parse(*arguments.residual_of),
                          hold_out.selected, path);
      std::vector<Image> residuals;
      for (int i = 0; i < set.size(); ++i) {
        Image residual = set.images()[i];
        const Image predicted = base.Relight(set.light(i));
        for (std::size_t v = 0; v < residual.values().size(); ++v) {
          residual.values()[v] -= predicted.values()[v];
        }
        residuals.push_back(std::move(residual));
      }
      PhotometricSet residual_set(std::move(residuals), set.lights());
      residual_set.set_mask(set.MaskOrAll());
      fmt::print("{}: held-out PSNR {:.2f} alone; with its residual interpolated:\n",
                 *arguments.residual_of, MeanScores(base, set, hold_out.held_out, peak).psnr);
      PrintOracle(Observations(residual_set), set.lights(), hold_out, peak,
                  arguments.profile.grid_size);
      continue;
    }
    if (arguments.oracle) {
      PrintOracle(observations, set.lights(), hold_out, peak, arguments.profile.grid_size);
      continue;
    }
    std::vector<Row> rows;
    for (const Method& method : methods) {
      if (method.kind == Method::Kind::kNeural) {
        rows.push_back(NeuralRow(set, hold_out, peak, arguments.neural_options, work));
        continue;
      }
      rows.push_back(PhotomatRow(observations, set, method, hold_out, peak, work, path));
    }
    if (arguments.linear_jpeg && arguments.relight_cli) {
      const auto theirs = RelightCliRows(*arguments.relight_cli, set, jpegs, hold_out, work);
      rows.insert(rows.end(), theirs.begin(), theirs.end());
    }
    // The issue states its target for DiLiGenT's cat and ball; other sets print the margin only.
    const bool target_set = path.filename() == "cat" || path.filename() == "ball";
    PrintTable(fmt::format("{}, {} held out ({}), {} fitted", path.filename().string(),
                           hold_out.held_out.size(), hold_out.name, hold_out.selected.size()),
               rows, target_set);
    if (calibrated) {
      PrintCalibratedTables(*calibrated, raw.set, set, methods, hold_out, arguments, work, path);
    }
  }
  if (!LightInterpolator(set.lights()).rings().size()) {
    fmt::print("(no slant-ring hold-out: the lights do not lie on rings of equal slant)\n");
  }
}

// A synthetic specular capture (capture/synthetic): 256 x 256 bricks with slopes up to 55
// degrees (attached and cast shadows), noise 0.005 of full scale, seed 1, under the thesis grid
// (12 tilts on the slant rings 30, 45 and 60 degrees, so the middle ring is a hold-out too);
// `phong`: white Blinn-Phong highlights (k_s 0.4, shininess 30), `ggx`: the GGX material with its
// roughness (0.35-0.65) and F0 (0.04-0.08) maps. Written as 16-bit PNGs with a manifest into
// `work`, the folder returned.
fs::path MakeSyntheticCapture(const std::string& name, const fs::path& work) {
  SyntheticMaterialOptions material_options;
  material_options.width = material_options.height = 256;
  material_options.max_slope_degrees = 55.0;
  const SyntheticMaterial material = MakeSyntheticMaterial(material_options);
  SyntheticRenderOptions render;
  render.shadows = true;
  render.noise_sigma = 0.005;
  if (name == kSyntheticGgx) {
    render.microfacet = true;
  } else {
    render.specular = 0.4;
    render.shininess = 30.0;
  }
  const fs::path folder = work / name.substr(name.find(':') + 1);
  WriteSyntheticCapture(folder, material,
                        RenderSyntheticCapture(material, ThesisLightGrid(), render));
  return folder;
}

int Run(int argc, char** argv) {
  const Arguments arguments = Parse(argc, argv);
  if (arguments.linear_jpeg && !arguments.relight_cli) {
    fmt::print("relight-cli: not available (--relight-cli, PHOTOMAT_RELIGHT_CLI), photomat only\n");
  }
  const fs::path work = fs::temp_directory_path() / fmt::format("held_out_lights.{}", ::getpid());
  fs::create_directories(work);
  try {
    for (const fs::path& set : arguments.sets) {
      const bool synthetic = set == kSyntheticPhong || set == kSyntheticGgx;
      RunSet(synthetic ? MakeSyntheticCapture(set.string(), work) : set, arguments, work);
    }
  } catch (...) {
    fs::remove_all(work);
    throw;
  }
  fs::remove_all(work);
  return 0;
}

}  // namespace
}  // namespace photomat

int main(int argc, char** argv) {
  try {
    return photomat::Run(argc, argv);
  } catch (const std::exception& error) {
    fmt::print(stderr, "held_out_lights: {}\n", error.what());
    return 1;
  }
}
