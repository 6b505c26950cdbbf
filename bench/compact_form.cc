// The compact forms of a stack (issue 19) against the float stack and against relight-cli's own
// folders: size and held-out-light PSNR. Every K-th light of the set is held out; the rest are
// fitted (float stack: photomat's linear fit), written as photomat's compact stack form
// (`WriteCompactStack`, relight/formats/compact_stack.h), exported in relight's web format
// (`RelightWebFromStack`, and `RelightWebFromSet` from the photographs) and built by relight-cli
// from the same photographs (8-bit sRGB JPEGs, quality 95, and an .lp file) when it is available.
// Every result is relit at the held-out lights, decoded to linear, and compared with the
// photographs over the mask, the set first scaled so that its largest value (over the mask) is 1,
// both clamped to [0, 1]: PSNR with peak 1. Sizes are the folders' files (info.json and
// plane_N.jpg; relight-cli's extra materials.png is counted separately; the compact stack: every
// file of its folder). Prints an EXPECTED FAILURE line for each basis whose compact stack misses
// the target (under 0.3 dB loss, within 2 x relight-cli's size).
//
//   compact_form [SET] [--every K] [--methods ptm,hsh,rbf,bilinear] [--relight-cli PATH]
//                [--quality Q] [--relight-planes K] [--resolution R] [--range-quantile Q]
//                [--compact-coding png|jpeg] [--compact-quality Q] [--compact-range-quantile Q]
//                [--compact-pca K] [--compact-only]
//
// (--compact-* set the compact stack's options; --compact-only skips relight's web folders.)
// (--quality, --relight-planes, --resolution and --range-quantile change photomat's folders only,
// relight-cli runs with its defaults.) (default: DiLiGenT cat from $PHOTOMAT_TEST_DATA, K = 10;
// relight-cli from $PHOTOMAT_RELIGHT_CLI or
// ~/.cache/photomat-peers/relight-build.)
#include <fmt/format.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench/relight_cli_peer.h"
#include "capture/io/load_photometric_set.h"
#include "core/colour.h"
#include "core/error.h"
#include "core/image_io.h"
#include "relight/formats/compact_stack.h"
#include "relight/formats/interchange.h"
#include "relight/formats/relight_web_format.h"
#include "relight/formats/stack_file.h"
#include "represent/evaluation/evaluation.h"
#include "represent/evaluation/image_comparison.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;

struct Arguments {
  fs::path set;
  int every = 10;
  std::vector<std::string> methods = {"ptm", "hsh", "rbf", "bilinear"};
  std::optional<fs::path> relight_cli;
  RelightWebOptions web;  // --quality, --relight-planes, --resolution (photomat's folders only)
  CompactStackOptions compact;
  bool compact_only = false;
};

Arguments Parse(int argc, char** argv) {
  Arguments arguments;
  if (const char* data = std::getenv("PHOTOMAT_TEST_DATA")) {
    arguments.set = fs::path(data) / "diligent" / "cat";
  }
  arguments.relight_cli = FindRelightCli();
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw Error(fmt::format("{} needs a value", a));
      return argv[++i];
    };
    if (a == "--every") {
      arguments.every = std::stoi(value());
    } else if (a == "--methods") {
      arguments.methods.clear();
      std::string list = value();
      for (std::size_t start = 0; start <= list.size();) {
        const std::size_t comma = std::min(list.find(',', start), list.size());
        arguments.methods.push_back(list.substr(start, comma - start));
        start = comma + 1;
      }
    } else if (a == "--relight-cli") {
      arguments.relight_cli = value();
    } else if (a == "--quality") {
      arguments.web.quality = std::stoi(value());
    } else if (a == "--relight-planes") {
      arguments.web.planes = std::stoi(value());
    } else if (a == "--range-quantile") {
      arguments.web.range_quantile = std::stod(value());
    } else if (a == "--compact-coding") {
      arguments.compact.coding = ParseCompactPlaneCoding(value());
    } else if (a == "--compact-quality") {
      arguments.compact.jpeg_quality = std::stoi(value());
    } else if (a == "--compact-range-quantile") {
      arguments.compact.range_quantile = std::stod(value());
    } else if (a == "--compact-pca") {
      arguments.compact.pca_planes = std::stoi(value());
    } else if (a == "--compact-only") {
      arguments.compact_only = true;
    } else if (a == "--resolution") {
      arguments.web.resolution = std::stoi(value());
    } else {
      arguments.set = a;
    }
  }
  if (arguments.set.empty()) throw Error("no set given and PHOTOMAT_TEST_DATA is not set");
  if (arguments.every < 2) throw Error("--every must be at least 2");
  return arguments;
}

RelightWebBasis BasisNamed(const std::string& name) {
  if (name == "ptm") return RelightWebBasis::kPtm;
  if (name == "hsh") return RelightWebBasis::kHsh;
  if (name == "rbf") return RelightWebBasis::kRbf;
  if (name == "bilinear") return RelightWebBasis::kBilinear;
  throw Error(fmt::format("unknown basis {}", name));
}

std::string FloatMethod(const std::string& basis) { return basis == "hsh" ? "hsh9" : basis; }

std::uintmax_t FolderBytes(const fs::path& folder, bool materials) {
  std::uintmax_t bytes = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const std::string name = entry.path().filename().string();
    const bool web = name == "info.json" || (name.starts_with("plane_") && name.ends_with(".jpg"));
    if (materials ? name == "materials.png" : web) bytes += entry.file_size();
  }
  return bytes;
}

struct HeldOut {
  const PhotometricSet* set;
  std::vector<int> lights;
  Mask mask;
};

// Mean PSNR (peak 1, MaskedPsnr) over the held-out lights; `encoded` results are decoded to
// linear first.
double Psnr(const Representation& r, const HeldOut& held_out, bool encoded) {
  double total = 0;
  for (int i : held_out.lights) {
    Image relit = r.Relight(held_out.set->light(i));
    if (encoded) {
      for (float& v : relit.values()) v = SrgbToLinear(v);
    }
    total += MaskedPsnr(relit, held_out.set->images()[i], held_out.mask, 1.0);
  }
  return total / held_out.lights.size();
}

// A web folder's PSNR, decoded as its colour profile says (relight-cli's default: linear codes).
double PsnrOfFolder(const fs::path& folder, const HeldOut& held_out) {
  const LoadedStack stack = LoadStackFile(folder);
  return Psnr(stack.representation, held_out,
              StackValueEncoding(stack.provenance) == ColourSpace::kSrgb);
}

// The set scaled so that its largest value over the mask is 1, split into every `every`-th light
// held out and the rest.
struct Split {
  std::unique_ptr<PhotometricSet> all;  // held_out points at it
  HeldOut held_out;
  PhotometricSet train;
  float peak;
};

Split SplitScaledSet(const Arguments& arguments) {
  const LoadedSet loaded = LoadPhotometricSet(arguments.set);
  const Mask mask = loaded.set.MaskOrAll();
  float peak = 0;
  for (const Image& image : loaded.set.images()) {
    for (int c = 0; c < image.channels(); ++c) {
      const auto plane = image.plane(c);
      for (std::size_t p = 0; p < image.pixel_count(); ++p) {
        if (mask[p]) peak = std::max(peak, plane[p]);
      }
    }
  }
  std::vector<Image> scaled = loaded.set.images();
  for (Image& image : scaled) {
    for (float& v : image.values()) v /= peak;
  }
  auto all = std::make_unique<PhotometricSet>(scaled, loaded.set.lights(), loaded.set.image_names(),
                                              arguments.set);
  std::vector<Image> train_images;
  std::vector<LightDirection> train_lights;
  HeldOut held_out{all.get(), {}, mask};
  for (int i = 0; i < all->size(); ++i) {
    if (i % arguments.every == 0) {
      held_out.lights.push_back(i);
    } else {
      train_images.push_back(scaled[i]);
      train_lights.push_back(all->light(i));
    }
  }
  PhotometricSet train(std::move(train_images), train_lights, {}, arguments.set);
  train.set_mask(mask);
  return {std::move(all), std::move(held_out), std::move(train), peak};
}

// The training photographs as 8-bit sRGB JPEGs with an .lp file, relight-cli's input.
void WriteTrainingJpegs(const PhotometricSet& train, const fs::path& folder) {
  fs::create_directories(folder);
  std::ofstream lp(folder / "lights.lp");
  lp << train.size() << "\n";
  ImageWriteOptions jpeg;
  jpeg.sample_type = SampleType::kUint8;
  jpeg.encoding = ColourSpace::kSrgb;
  for (int i = 0; i < train.size(); ++i) {
    const std::string name = fmt::format("img{:03d}.jpg", i);
    WriteImage(folder / name, train.images()[i], jpeg);
    const auto& l = train.light(i);
    lp << fmt::format("{} {:.6f} {:.6f} {:.6f}\n", name, l.x(), l.y(), l.z());
  }
}

// The relight web columns of a basis: the encoded refit (ptm and hsh), the folders from the
// float stack and from the photographs.
struct WebColumns {
  std::string refit = "-";
  std::string from_stack = "-";
  std::string from_photos = "-";
  std::uintmax_t photos_bytes = 0;
};

WebColumns MeasureRelightWeb(const Arguments& arguments, const std::string& basis,
                             const LoadedStack& float_stack, double float_db, const Split& split,
                             const fs::path& work) {
  WebColumns columns;
  // The float stack refitted in sRGB-encoded values (what ptm/hsh folders hold), before any
  // quantisation: how much of the loss is the change of domain.
  if (basis == "ptm" || basis == "hsh") {
    const Representation encoded = ConvertToEncoded(float_stack, Method::Parse(FloatMethod(basis)));
    columns.refit = fmt::format("{:.2f}", Psnr(encoded, split.held_out, true));
  }
  RelightWebOptions options = arguments.web;
  options.basis = BasisNamed(basis);
  const fs::path from_stack = work / (basis + "-stack");
  WriteRelightWeb(from_stack, RelightWebFromStack(float_stack, options));
  const double stack_db = PsnrOfFolder(from_stack, split.held_out);
  columns.from_stack = fmt::format("{:.2f}, {:+.2f}, {:.0f}", stack_db, stack_db - float_db,
                                   FolderBytes(from_stack, false) / 1024.0);
  const fs::path from_photos = work / (basis + "-photos");
  WriteRelightWeb(from_photos, RelightWebFromSet(split.train, options));
  columns.photos_bytes = FolderBytes(from_photos, false);
  columns.from_photos = fmt::format("{:.2f}, {:.0f}", PsnrOfFolder(from_photos, split.held_out),
                                    columns.photos_bytes / 1024.0);
  return columns;
}

// relight-cli's folder of a basis from the training JPEGs: its PSNR and size, and the size
// ratios of photomat's folders to it.
struct RelightCliColumns {
  std::string theirs = "-";
  std::string ratio = "-";
  std::string compact_ratio = "-";
  double compact_over_theirs = 0;
};

RelightCliColumns MeasureRelightCli(const Arguments& arguments, const std::string& basis,
                                    const fs::path& photos, const HeldOut& held_out,
                                    std::uintmax_t photos_bytes, std::uintmax_t compact_bytes,
                                    const fs::path& work) {
  RelightCliColumns columns;
  const fs::path folder = work / (basis + "-relight-cli");
  const std::string command = fmt::format("{} {} {} {} > {} 2>&1", arguments.relight_cli->string(),
                                          RelightCliArguments(basis), photos.string(),
                                          folder.string(), (work / "relight-cli.log").string());
  if (std::system(command.c_str()) != 0) throw Error("relight-cli failed: " + command);
  const double db = PsnrOfFolder(folder, held_out);
  const auto bytes = FolderBytes(folder, false);
  columns.theirs = fmt::format("{:.2f}, {:.0f} (+ {:.0f})", db, bytes / 1024.0,
                               FolderBytes(folder, true) / 1024.0);
  if (photos_bytes > 0) {
    columns.ratio = fmt::format("{:.2f}", static_cast<double>(photos_bytes) / bytes);
  }
  columns.compact_over_theirs = static_cast<double>(compact_bytes) / bytes;
  columns.compact_ratio = fmt::format("{:.2f}", columns.compact_over_theirs);
  return columns;
}

// One row of the table; returns the EXPECTED FAILURE line when the compact stack misses the
// target, else nothing.
std::optional<std::string> MeasureBasis(const Arguments& arguments, const std::string& basis,
                                        const Split& split, const std::optional<fs::path>& photos,
                                        const fs::path& work) {
  const Representation fit = Fit(split.train, Method::Parse(FloatMethod(basis)));
  const double float_db = Psnr(fit, split.held_out, false);
  const LoadedStack float_stack{fit, StackProvenance(split.train.lights(), "linear")};
  const fs::path compact_folder = work / (basis + "-compact");
  WriteCompactStack(compact_folder, float_stack, arguments.compact);
  const double compact_db =
      Psnr(ReadCompactStack(compact_folder).representation, split.held_out, false);
  const auto compact_bytes = StoredBytes(compact_folder);
  const WebColumns web = arguments.compact_only ? WebColumns{}
                                                : MeasureRelightWeb(arguments, basis, float_stack,
                                                                    float_db, split, work);
  const RelightCliColumns theirs =
      photos ? MeasureRelightCli(arguments, basis, *photos, split.held_out, web.photos_bytes,
                                 compact_bytes, work)
             : RelightCliColumns{};
  const double loss = float_db - compact_db;
  fmt::print("| {} | {:.2f} | {:.2f}, {:+.2f}, {:.0f} | {} | {} | {} | {} | {} | {} |\n", basis,
             float_db, compact_db, -loss, compact_bytes / 1024.0, theirs.compact_ratio, web.refit,
             web.from_stack, web.from_photos, theirs.theirs, theirs.ratio);
  if (loss < 0.3 && theirs.compact_over_theirs <= 2.0) return std::nullopt;
  return fmt::format(
      "EXPECTED FAILURE: target \"{} compact stack under 0.3 dB loss against the float stack, "
      "within 2 x relight-cli's size\" not met (measured loss {:.2f} dB, {} x relight-cli's "
      "size) because 8-bit planes over the mask's range at this coding lose that much",
      basis, loss, theirs.compact_ratio);
}

int Run(int argc, char** argv) {
  const Arguments arguments = Parse(argc, argv);
  const Split split = SplitScaledSet(arguments);
  fmt::print("{}: {} images {}x{}, {} held out (every {}th), scaled by 1 / {:.4g}\n",
             arguments.set.string(), split.all->size(), split.all->width(), split.all->height(),
             split.held_out.lights.size(), arguments.every, split.peak);
  const fs::path work = fs::temp_directory_path() / fmt::format("compact_form.{}", ::getpid());
  fs::create_directories(work);
  std::optional<fs::path> photos;
  if (arguments.relight_cli) {
    photos = work / "photos";
    WriteTrainingJpegs(split.train, *photos);
  } else {
    fmt::print("relight-cli: not available (set PHOTOMAT_RELIGHT_CLI), its columns are empty\n");
  }
  fmt::print(
      "| basis | float stack dB | photomat compact stack: dB, loss, KB | compact stack / "
      "relight-cli size | encoded refit, unquantised dB | relight web (from stack) dB, loss, KB "
      "| relight web (from photos) dB, KB | relight-cli dB, KB (+ materials.png) | relight web "
      "(photos) / relight-cli size |\n"
      "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  std::vector<std::string> failures;
  for (const std::string& basis : arguments.methods) {
    if (auto failure = MeasureBasis(arguments, basis, split, photos, work)) {
      failures.push_back(std::move(*failure));
    }
  }
  for (const std::string& failure : failures) fmt::print("{}\n", failure);
  fs::remove_all(work);
  return 0;
}

}  // namespace
}  // namespace photomat

int main(int argc, char** argv) {
  try {
    return photomat::Run(argc, argv);
  } catch (const std::exception& error) {
    fmt::print(stderr, "compact_form: {}\n", error.what());
    return 1;
  }
}
