#include "apps/export_command.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>

#include "apps/cli_main.h"
#include "apps/cli_support.h"
#include "apps/streamed_capture.h"
#include "capture/io/streamed_set.h"
#include "core/colour.h"
#include "core/disk_space.h"
#include "core/error.h"
#include "core/memory_limits.h"
#include "core/scratch_folder.h"
#include "relight/export/export.h"
#include "relight/export/streamed_interchange.h"
#include "relight/formats/compact_stack.h"
#include "relight/formats/interchange.h"
#include "relight/formats/ptm_file.h"
#include "relight/formats/relight_web_format.h"
#include "relight/formats/rti_file.h"
#include "relight/formats/stack_file.h"
#include "relight/web/published_name.h"
#include "relight/web/viewer_export.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_reader.h"
#include "represent/streaming/streamed_fit.h"

namespace photomat::app {
namespace {

struct ExportCommandOptions {
  std::filesystem::path input;
  std::string method;
  std::filesystem::path out;
  std::string normal_convention = "opengl";
  std::string height = "poisson";
  bool no_gltf = false;
  std::filesystem::path ptm;
  std::string ptm_format;
  std::filesystem::path rti;
  int hsh_terms = 0;
  std::string colour_space;
  bool raw_intensities = false;
  std::filesystem::path viewer;
  std::string viewer_tiles = "auto";
  int viewer_tile_size = kViewerTileSize;
  bool viewer_without_maps = false;
  std::size_t memory_mb = 0;
  bool stream = false;
  std::filesystem::path relight_web;
  std::string relight_basis;
  int relight_planes = 9;
  int relight_quality = 95;
  std::filesystem::path compact;
  std::string compact_coding = "png";
  int compact_quality = 100;
  double compact_range_quantile = 1.0;
  int compact_pca = CompactStackOptions{}.pca_planes;
};

// relight's basis for --relight-web: --relight-basis, else the input's own (ptm, hsh4/9, rbf,
// bilinear), else ptm.
RelightWebOptions RelightWebOptionsFor(const ExportCommandOptions& options,
                                       const std::string& input_method) {
  RelightWebOptions web;
  web.planes = options.relight_planes;
  web.quality = options.relight_quality;
  std::string basis = options.relight_basis;
  if (basis.empty()) {
    if (input_method.starts_with("hsh"))
      basis = "hsh";
    else if (input_method == "rbf" || input_method == "relight-rbf")
      basis = "rbf";
    else if (input_method == "bilinear" || input_method == "relight-bilinear")
      basis = "bilinear";
    else
      basis = "ptm";
  }
  if (basis == "ptm")
    web.basis = RelightWebBasis::kPtm;
  else if (basis == "hsh")
    web.basis = RelightWebBasis::kHsh;
  else if (basis == "rbf")
    web.basis = RelightWebBasis::kRbf;
  else if (basis == "bilinear")
    web.basis = RelightWebBasis::kBilinear;
  else
    throw Error(
        fmt::format("--relight-basis: expected ptm, hsh, rbf or bilinear, not \"{}\"", basis));
  if (options.hsh_terms != 0)
    web.hsh_terms = options.hsh_terms;
  else if (input_method == "hsh4")
    web.hsh_terms = 4;
  return web;
}

// Whether --relight-web asks relight's rbf or bilinear basis (a PCA of every pixel's profile at
// the nodes, made in bands) rather than its ptm or hsh one (a refit of the whole stack).
bool IsMrgbRelightWeb(const ExportCommandOptions& options, const std::string& input_method) {
  const RelightWebBasis basis = RelightWebOptionsFor(options, input_method).basis;
  return basis == RelightWebBasis::kRbf || basis == RelightWebBasis::kBilinear;
}

using MakeRelightWeb =
    std::function<RelightWebStack(const RelightWebBands&, RelightWebBandsReport*)>;

// Makes relight's planes with `make` (rbf and bilinear in bands of the --memory budget, with a
// progress bar), writes them to --relight-web and says what it wrote and in what bands.
void WriteRelightWebFolder(const ExportCommandOptions& options, const MakeRelightWeb& make) {
  TerminalProgressBar bar;
  RelightWebBands bands;
  bands.memory_bytes = options.memory_mb << 20;
  bands.progress = &bar;
  RelightWebBandsReport made_in;
  const RelightWebStack web = make(bands, &made_in);
  WriteRelightWeb(options.relight_web, web);
  const std::string banding = made_in.passes > 0
                                  ? fmt::format("; {} passes in bands of {} of {} rows",
                                                made_in.passes, made_in.band_rows, web.height)
                                  : "";
  fmt::print("wrote {} (relight web format: {} {}, {} planes, {}x{}{})\n",
             options.relight_web.string(), ToString(web.basis), ToString(web.colour_space),
             web.PlaneCount(), web.width, web.height, banding);
}

void WriteCompact(const ExportCommandOptions& options, const LoadedStack& stack) {
  if (options.compact.empty()) return;
  CompactStackOptions compact;
  compact.coding = ParseCompactPlaneCoding(options.compact_coding);
  compact.jpeg_quality = options.compact_quality;
  compact.range_quantile = options.compact_range_quantile;
  compact.pca_planes = options.compact_pca;
  WriteCompactStack(options.compact, stack, compact);
  fmt::print("wrote {} (photomat compact stack: {}, {} planes of 8 bits as {})\n",
             options.compact.string(), stack.representation.method(),
             CompactPlaneCount(stack.representation, compact), ToString(compact.coding));
}

// The .ptm method: what --ptm-format asks, else the input's own PTM form, else LRGB (PTMfitter's).
Method PtmMethod(const ExportCommandOptions& options, const std::string& input_method,
                 int channels) {
  if (options.ptm_format == "rgb") return Method::Parse("ptm");
  if (options.ptm_format == "lrgb") {
    if (channels != 3) throw Error("--ptm-format lrgb needs colour (3-channel) data");
    return Method::Parse("ptm-lrgb");
  }
  if (!options.ptm_format.empty()) throw Error("--ptm-format: expected rgb or lrgb");
  if (input_method == "ptm" || channels != 3) return Method::Parse("ptm");
  return Method::Parse("ptm-lrgb");
}

Method HshMethod(const ExportCommandOptions& options, const std::string& input_method) {
  if (options.hsh_terms != 0) return Method::Parse(fmt::format("hsh{}", options.hsh_terms));
  return Method::Parse(input_method.starts_with("hsh") ? input_method : "hsh9");
}

void WriteInterchangeFiles(const ExportCommandOptions& options, const std::string& input_method,
                           int channels, const std::function<Representation(const Method&)>& make) {
  if (!options.ptm.empty()) {
    const Method method = PtmMethod(options, input_method, channels);
    const PtmFile ptm = PtmFromRepresentation(make(method));
    WritePtmFile(options.ptm, ptm);
    fmt::print("wrote {} ({}, {}x{})\n", options.ptm.string(), ToString(ptm.format), ptm.width,
               ptm.height);
  }
  if (!options.rti.empty()) {
    const Method method = HshMethod(options, input_method);
    const RtiFile rti = RtiFromRepresentation(make(method));
    WriteRtiFile(options.rti, rti);
    fmt::print("wrote {} (HSH, {} terms, {}x{})\n", options.rti.string(), rti.terms, rti.width,
               rti.height);
  }
}

ExportOptions MapOptions(const ExportCommandOptions& options) {
  ExportOptions export_options;
  export_options.normal_convention = ParseNormalConvention(options.normal_convention);
  export_options.height = ParseHeightIntegrator(options.height);
  export_options.gltf = !options.no_gltf;
  return export_options;
}

std::size_t MemoryBudget(const ExportCommandOptions& options) {
  return options.memory_mb > 0 ? options.memory_mb << 20
                               : DefaultMemoryBudget(kMinimumExportMemory);
}

// IMPLEMENTER CHOICE: a stack is exported streamed (ExportMapsStreamed, ExportPtmStreamed,
// ExportRtiStreamed) when asked (--stream) or when the in-memory export would not fit the memory
// budget, and it can be: a map stack (.exr), and no compact stack form or relight web folder of
// relight's ptm or hsh basis asked (those are made from the whole stack: the compact form's PCA,
// the ptm/hsh planes' refit and ranges; relight's rbf and bilinear planes are made in bands,
// RelightWebBands). Streamed maps take the tiled Poisson height, or with --height fc the same
// whole-map FFT as in memory (the gradient field alone held whole). Otherwise in memory, whose
// Poisson height is the exact solve; the .ptm and .rti files are the same bytes either way.
bool StreamsStack(const ExportCommandOptions& options, const std::filesystem::path& stack_path,
                  const StackBandReader& stack) {
  const bool relight_web_mrgb = !options.relight_web.empty() &&
                                IsMrgbRelightWeb(options, stack.header().representation.method());
  if ((!options.relight_web.empty() && !relight_web_mrgb) || !options.compact.empty() ||
      !IsStreamableStack(stack_path)) {
    return false;
  }
  if (options.out.empty() && options.ptm.empty() && options.rti.empty() && !relight_web_mrgb) {
    return false;
  }
  if (options.stream) return true;
  const Representation& r = stack.header().representation;
  return InMemoryExportBytes(stack.width(), stack.height(), r.maps().channels(),
                             r.output_channels()) > MemoryBudget(options);
}

void CheckExportDiskSpace(const ExportCommandOptions& options, const Representation& r, int width,
                          int height) {
  CheckDiskSpace(
      options.out,
      ExportOutputBytes(width, height, r.maps().channels(), r.output_channels(), !options.no_gltf),
      "the export");
}

void WriteMapsStreamed(const ExportCommandOptions& options, StackBandReader& stack) {
  CheckExportDiskSpace(options, stack.header().representation, stack.width(), stack.height());
  CreateFolder(options.out);
  StreamedExportOptions streamed;
  streamed.maps = MapOptions(options);
  // Without --memory the bands take DefaultBandBudget's few tens of MB, not the whole budget.
  streamed.memory_bytes = options.memory_mb << 20;
  TerminalProgressBar bar;
  streamed.progress = &bar;
  StreamedExportReport report;
  const nlohmann::json description = ExportMapsStreamed(stack, options.out, streamed, &report);
  const bool poisson = streamed.maps.height == HeightIntegrator::kPoisson;
  fmt::print(
      "wrote the {} maps of {} to {} (normals from {}; streamed in bands of {} rows, height by "
      "{})\n",
      stack.header().representation.method(), stack.header().provenance.source,
      options.out.string(), description["normals"]["source"].get<std::string>(), report.band_rows,
      poisson ? "tiled Poisson" : "Frankot-Chellappa, a whole-map FFT");
}

std::filesystem::path FolderOf(const std::filesystem::path& file) {
  return file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
}

StreamedInterchangeOptions InterchangeOptions(const ExportCommandOptions& options,
                                              Progress& progress) {
  StreamedInterchangeOptions streamed;
  // Without --memory the bands take DefaultBandBudget's few tens of MB, not the whole budget.
  streamed.memory_bytes = options.memory_mb << 20;
  streamed.progress = &progress;
  return streamed;
}

// --ptm of a stack read in bands (ExportPtmStreamed), as `method`.
void WritePtmFileStreamed(const ExportCommandOptions& options, StackBandReader& stack,
                          const Method& method) {
  const std::size_t pixels = static_cast<std::size_t>(stack.width()) * stack.height();
  // At most 18 bytes per pixel (RGB) and the header.
  CheckDiskSpace(FolderOf(options.ptm), pixels * 18 + kImageFileOverhead, "the .ptm file");
  TerminalProgressBar bar;
  StreamedInterchangeReport report;
  const PtmFile ptm =
      ExportPtmStreamed(stack, options.ptm, method, InterchangeOptions(options, bar), &report);
  fmt::print("wrote {} ({}, {}x{}; streamed in bands of {} rows)\n", options.ptm.string(),
             ToString(ptm.format), ptm.width, ptm.height, report.band_rows);
}

// --rti of a stack read in bands (ExportRtiStreamed), as `method`.
void WriteRtiFileStreamed(const ExportCommandOptions& options, StackBandReader& stack,
                          const Method& method) {
  const std::size_t pixels = static_cast<std::size_t>(stack.width()) * stack.height();
  const auto channels = static_cast<std::size_t>(stack.header().representation.output_channels());
  CheckDiskSpace(FolderOf(options.rti), pixels * 16 * channels + kImageFileOverhead,
                 "the .rti file");
  TerminalProgressBar bar;
  StreamedInterchangeReport report;
  const RtiFile rti =
      ExportRtiStreamed(stack, options.rti, method, InterchangeOptions(options, bar), &report);
  fmt::print("wrote {} (HSH, {} terms, {}x{}; streamed in bands of {} rows)\n",
             options.rti.string(), rti.terms, rti.width, rti.height, report.band_rows);
}

// The .ptm and .rti files of a stack read in bands.
void WriteInterchangeFilesStreamed(const ExportCommandOptions& options, StackBandReader& stack) {
  const Representation& r = stack.header().representation;
  if (!options.ptm.empty()) {
    WritePtmFileStreamed(options, stack, PtmMethod(options, r.method(), r.output_channels()));
  }
  if (!options.rti.empty()) WriteRtiFileStreamed(options, stack, HshMethod(options, r.method()));
}

void WriteMaps(const ExportCommandOptions& options, const LoadedStack& stack) {
  if (options.out.empty()) return;
  CheckExportDiskSpace(options, stack.representation, stack.representation.width(),
                       stack.representation.height());
  CreateFolder(options.out);
  const ExportOptions export_options = MapOptions(options);
  TerminalProgressBar bar;
  const nlohmann::json description = ExportMaps(stack, options.out, export_options, &bar);
  fmt::print("wrote the {} maps of {} to {} (normals from {})\n", stack.representation.method(),
             stack.provenance.source, options.out.string(),
             description["normals"]["source"].get<std::string>());
}

ViewerExportOptions ViewerOptions(const ExportCommandOptions& options) {
  ViewerExportOptions viewer;
  viewer.title = PublishedName(options.input);
  viewer.tiling = ParseViewerTiling(options.viewer_tiles);
  viewer.tile_size = options.viewer_tile_size;
  viewer.display_maps = !options.viewer_without_maps;
  viewer.memory_bytes = options.memory_mb << 20;
  return viewer;
}

void PrintViewerWritten(const ExportCommandOptions& options, std::size_t methods, bool tiled) {
  fmt::print(
      "wrote the web viewer ({} method(s){}) to {}: serve that folder with any static file "
      "server (e.g. python3 -m http.server --directory {} 8000) and open it\n",
      methods, tiled ? ", as deep-zoom tiles" : "", options.viewer.string(),
      options.viewer.string());
}

// The web viewer of `stacks` (relight/viewer_export.h), loaded whole.
void WriteViewer(const ExportCommandOptions& options, const std::vector<LoadedStack>& stacks) {
  std::vector<Representation> representations;
  ViewerExportOptions viewer = ViewerOptions(options);
  for (const LoadedStack& stack : stacks) {
    representations.push_back(stack.representation);
    viewer.value_encodings[stack.representation.method()] = StackValueEncoding(stack.provenance);
    if (viewer.capture_lights.empty()) viewer.capture_lights = stack.provenance.capture_lights;
  }
  TerminalProgressBar bar;
  viewer.progress = &bar;
  ExportViewer(options.viewer, representations, viewer);
  PrintViewerWritten(
      options, representations.size(),
      !representations.empty() && UsesViewerTiles(viewer.tiling, representations.front().width(),
                                                  representations.front().height()));
}

// A fit folder's methods in photomat's method order, others after.
std::vector<std::string> ViewerMethodOrder(const std::filesystem::path& folder) {
  const auto files = ReadFitManifest(folder);
  std::vector<std::string> order;
  for (const Method& m : AllMethods()) {
    if (files.contains(m.Name())) order.push_back(m.Name());
  }
  for (const auto& [name, file] : files) {
    if (std::find(order.begin(), order.end(), name) == order.end()) order.push_back(name);
  }
  return order;
}

bool ShowsEveryMethod(const std::filesystem::path& input,
                      const std::optional<std::string>& method) {
  return !method && std::filesystem::is_directory(input) && !IsRelightWebFolder(input) &&
         !IsCompactStackFolder(input);
}

// Every stack of a fit folder (in photomat's method order), or the one `method` or the file names.
std::vector<LoadedStack> ViewerStacks(const std::filesystem::path& input,
                                      const std::optional<std::string>& method) {
  if (!ShowsEveryMethod(input, method)) return {LoadStackFile(input, method)};
  std::vector<LoadedStack> stacks;
  for (const std::string& name : ViewerMethodOrder(input)) {
    stacks.push_back(LoadStackFile(input, name));
  }
  return stacks;
}

// The stack files of ViewerStacks, when every one is a map stack read in bands; else none.
std::vector<std::filesystem::path> StreamableViewerStacks(
    const std::filesystem::path& input, const std::optional<std::string>& method) {
  if (IsReadWholeStackInput(input)) return {};
  std::vector<std::filesystem::path> paths;
  if (!ShowsEveryMethod(input, method)) {
    paths.push_back(ResolveStack(input, method));
  } else {
    for (const std::string& name : ViewerMethodOrder(input)) {
      paths.push_back(ResolveStack(input, name));
    }
  }
  for (const auto& path : paths) {
    if (!IsStreamableStack(path)) return {};
  }
  return paths;
}

// The viewer of the map stacks at `paths` when it is tiled (--viewer-tiles, viewer_pyramid.h):
// every stack read in bands, never whole (ExportViewerStreamed). Returns false, writing nothing,
// when the viewer is not tiled.
bool WriteTiledViewerOfStackFiles(const ExportCommandOptions& options,
                                  const std::vector<std::filesystem::path>& paths) {
  ViewerExportOptions viewer = ViewerOptions(options);
  bool tiled = false;
  int maps = 0;
  std::size_t pixels = 0;
  for (const auto& path : paths) {
    const StackBandReader stack(path);
    tiled = UsesViewerTiles(viewer.tiling, stack.width(), stack.height());
    pixels = static_cast<std::size_t>(stack.width()) * static_cast<std::size_t>(stack.height());
    const Representation& r = stack.header().representation;
    maps += r.maps().channels();
    viewer.value_encodings[r.method()] = StackValueEncoding(stack.header().provenance);
    if (viewer.capture_lights.empty())
      viewer.capture_lights = stack.header().provenance.capture_lights;
  }
  // IMPLEMENTER CHOICE: auto tiling also tiles a viewer below the size threshold when making it in
  // memory would not fit the memory budget (--memory, else half of the machine's or the process's
  // limits), so that the viewer adapts to a process's limits (a Slurm task's --mem) as the other
  // exports do.
  if (!tiled && viewer.tiling == ViewerTiling::kAuto &&
      InMemoryViewerBytes(pixels, maps) > MemoryBudget(options)) {
    tiled = true;
    fmt::print("the viewer in memory would take about {} MB, over the {} MB budget: tiling it\n",
               InMemoryViewerBytes(pixels, maps) >> 20, MemoryBudget(options) >> 20);
  }
  if (!tiled) return false;
  viewer.tiling = ViewerTiling::kAlways;
  TerminalProgressBar bar;
  viewer.progress = &bar;
  ExportViewerStreamed(options.viewer, paths, viewer);
  PrintViewerWritten(options, paths.size(), true);
  return true;
}

// IMPLEMENTER CHOICE: a stack that is tiled (--viewer-tiles, viewer_pyramid.h) is read in bands
// when it is a map stack (.exr, fit folder), never whole; a .ptm, .rti or relight web folder is in
// memory anyway and tiles from there. (A photometric set's viewer: ExportCaptureStreamed, or its
// fits in memory.)
void WriteViewerOfStacks(const ExportCommandOptions& options,
                         const std::optional<std::string>& method) {
  const std::vector<std::filesystem::path> paths = StreamableViewerStacks(options.input, method);
  if (!paths.empty() && WriteTiledViewerOfStackFiles(options, paths)) return;
  WriteViewer(options, ViewerStacks(options.input, method));
}

// IMPLEMENTER CHOICE: a photometric set's exports are made from scratch stacks fitted in bands
// (ExportCaptureStreamed) when asked (--stream) or when holding the whole set
// (kWholeSetBytesPerPixelImage per pixel and image) would not fit the memory budget. The .ptm,
// .rti, maps and viewer then read the stacks in bands too (the maps' --height fc holds the
// gradient field whole for its FFT); what is made from a whole stack (the compact form's PCA,
// relight's ptm and hsh planes and their ranges) loads its scratch stack, a fraction of the set
// (Gradient: 6 floats per pixel against 3 per pixel and image, twice). relight's rbf and bilinear
// planes are made in bands (RelightWebBands): rbf from the photographs, bilinear from its scratch
// stack. CaptureCanStream is what the options alone decide (the set is opened only then).
bool CaptureCanStream(const ExportCommandOptions& options) {
  return !options.out.empty() || !options.ptm.empty() || !options.rti.empty() ||
         !options.viewer.empty() || !options.relight_web.empty() || !options.compact.empty();
}

bool StreamsCapture(const ExportCommandOptions& options, const StreamedSet& set) {
  if (!CaptureCanStream(options)) return false;
  return options.stream || HoldingSetExceeds(set, MemoryBudget(options));
}

// The streamed export of a photometric set (StreamsCapture): its photographs are fitted in bands
// (FitStreamed) into scratch map stacks, which the stacks' exports read: the encoded fits the
// .ptm, .rti and relight's ptm / hsh planes are made from (FitEncoded's domain: `encoded_values`,
// provenance "srgb", which the exports take as they are) in one pass over the photographs, the
// linear fits the maps, the compact form and the viewer come from (--method, else Gradient for
// the maps and the compact form and every method for the viewer, as in memory) in another. The
// .ptm, .rti, maps and a tiled viewer read the stacks in bands; the compact form, relight's ptm
// and hsh planes and a viewer below the tiling threshold load their stack whole
// (CaptureCanStream); relight's rbf planes read the photographs
// in bands, its bilinear planes their stack. IMPLEMENTER CHOICE: scratch stacks rather than a fit
// per pass of the exports: a .ptm takes two passes (the coefficients' ranges, then the bytes) and
// decoding the photographs costs several times reading a float stack back. The scratch folder is
// beside the first output (on its disk, whose free space is checked) and is removed at the end,
// however the export ends. The files equal the in-memory export's to float rounding (a fit's
// matrix product rounds by band, streamed_interchange.h), so a quantised coefficient may differ
// by one code.
// What a streamed export of a photometric set fits: the encoded fits, each method once (.ptm,
// .rti, then relight's planes; none for rbf, whose planes come from the photographs), and the
// linear fits (the maps' and compact form's method first, then the viewer's others).
struct CaptureExportFits {
  std::vector<Method> encoded;
  std::optional<std::size_t> ptm_fit, rti_fit, relight_fit;  // indices into `encoded`
  std::optional<RelightWebOptions> relight;
  std::vector<Method> linear;
  std::vector<Method> viewer_methods;
};

// The index of `method` (by name) in `methods`, appended when missing: each method is fitted once.
std::size_t IndexOfOrAppend(std::vector<Method>& methods, const Method& method) {
  for (std::size_t k = 0; k < methods.size(); ++k) {
    if (methods[k].Name() == method.Name()) return k;
  }
  methods.push_back(method);
  return methods.size() - 1;
}

CaptureExportFits PlanCaptureExportFits(const ExportCommandOptions& options,
                                        const StreamedSet& set) {
  CaptureExportFits fits;
  const auto encoded_index = [&](const Method& method) {
    return IndexOfOrAppend(fits.encoded, method);
  };
  if (!options.ptm.empty()) fits.ptm_fit = encoded_index(PtmMethod(options, "", set.channels()));
  if (!options.rti.empty()) fits.rti_fit = encoded_index(HshMethod(options, ""));
  if (!options.relight_web.empty()) {
    fits.relight = RelightWebOptionsFor(options, "");
    if (const std::optional<Method> method = RelightWebFitMethod(*fits.relight)) {
      fits.relight_fit = encoded_index(*method);  // as RelightWebFromSet
    }
  }
  const Method maps_method = Method::Parse(options.method.empty() ? "gradient" : options.method);
  fits.viewer_methods = options.method.empty() ? AllMethods() : std::vector{maps_method};
  if (!options.out.empty() || !options.compact.empty()) fits.linear.push_back(maps_method);
  if (!options.viewer.empty()) {
    for (const Method& m : fits.viewer_methods) IndexOfOrAppend(fits.linear, m);
  }
  return fits;
}

// The .ptm, .rti and relight's planes, from the encoded fits' scratch stacks (rbf's planes from
// the photographs).
void WriteEncodedExports(const ExportCommandOptions& options, StreamedSet& set,
                         const CaptureExportFits& fits, const std::filesystem::path& scratch,
                         StreamedFitOptions fit) {
  if (!fits.encoded.empty()) {
    fit.encoded_values = true;
    const std::vector<std::filesystem::path> stacks =
        FitIntoFolder(set, fits.encoded, scratch, options.input.string(), fit, true);
    if (fits.ptm_fit) {
      StackBandReader stack(stacks[*fits.ptm_fit]);
      WritePtmFileStreamed(options, stack, fits.encoded[*fits.ptm_fit]);
    }
    if (fits.rti_fit) {
      StackBandReader stack(stacks[*fits.rti_fit]);
      WriteRtiFileStreamed(options, stack, fits.encoded[*fits.rti_fit]);
    }
    if (fits.relight_fit) {
      StackBandReader stack(stacks[*fits.relight_fit]);
      WriteRelightWebFolder(options,
                            [&](const RelightWebBands& bands, RelightWebBandsReport* made) {
                              return RelightWebFromStack(stack, *fits.relight, bands, made);
                            });
    }
  }
  if (fits.relight && !fits.relight_fit) {  // rbf: the photographs are the node values
    WriteRelightWebFolder(options, [&](const RelightWebBands& bands, RelightWebBandsReport* made) {
      return RelightWebFromSet(set, *fits.relight, bands, made);
    });
  }
}

// The maps, the compact form and the viewer, from the linear fits' scratch stacks.
void WriteLinearExports(const ExportCommandOptions& options, StreamedSet& set,
                        const CaptureExportFits& fits, const std::filesystem::path& scratch,
                        const StreamedFitOptions& fit) {
  if (fits.linear.empty()) return;
  const std::vector<std::filesystem::path> stacks =
      FitIntoFolder(set, fits.linear, scratch, options.input.string(), fit,
                    /*warn_clipped=*/fits.encoded.empty());
  if (!options.out.empty()) {
    StackBandReader stack(stacks.front());
    WriteMapsStreamed(options, stack);
  }
  if (!options.compact.empty()) WriteCompact(options, LoadRepresentation(stacks.front()));
  if (options.viewer.empty()) return;
  // In photomat's method order, as a fit folder's viewer.
  std::vector<std::filesystem::path> viewer_stacks;
  for (const Method& m : fits.viewer_methods) {
    for (std::size_t k = 0; k < fits.linear.size(); ++k) {
      if (fits.linear[k].Name() == m.Name()) viewer_stacks.push_back(stacks[k]);
    }
  }
  if (!WriteTiledViewerOfStackFiles(options, viewer_stacks)) {
    std::vector<LoadedStack> loaded;
    for (const auto& path : viewer_stacks) loaded.push_back(LoadRepresentation(path));
    WriteViewer(options, loaded);
  }
}

void ExportCaptureStreamed(const ExportCommandOptions& options, StreamedSet& set) {
  const CaptureExportFits fits = PlanCaptureExportFits(options, set);
  std::filesystem::path beside = FolderOf(options.viewer);
  for (const std::filesystem::path& output :
       {options.compact, options.relight_web, options.rti, options.ptm, options.out}) {
    if (!output.empty()) beside = FolderOf(output);
  }
  CreateFolder(beside);
  const ScratchFolder scratch(beside, "photomat-export");
  TerminalProgressBar bar;
  StreamedFitOptions fit;
  fit.memory_bytes = options.memory_mb << 20;
  fit.progress = &bar;
  WriteEncodedExports(options, set, fits, scratch.path(), fit);
  WriteLinearExports(options, set, fits, scratch.path(), fit);
}

// A map stack streamed band by band, when it can be and should (StreamsStack). Returns whether
// it was.
bool ExportStackStreamed(const ExportCommandOptions& options,
                         const std::optional<std::string>& method) {
  if (IsReadWholeStackInput(options.input)) return false;
  const std::filesystem::path stack_path = ResolveStack(options.input, method);
  if (!IsStreamableStack(stack_path)) return false;
  StackBandReader stack(stack_path);
  if (!StreamsStack(options, stack_path, stack)) return false;
  if (!options.out.empty()) WriteMapsStreamed(options, stack);
  WriteInterchangeFilesStreamed(options, stack);
  if (!options.relight_web.empty()) {  // rbf or bilinear (StreamsStack)
    const RelightWebOptions web =
        RelightWebOptionsFor(options, stack.header().representation.method());
    WriteRelightWebFolder(options, [&](const RelightWebBands& bands, RelightWebBandsReport* made) {
      return RelightWebFromStack(stack, web, bands, made);
    });
  }
  return true;
}

// A stack, a .ptm or .rti file, a compact or relight web folder, read whole.
void ExportWholeStack(const ExportCommandOptions& options,
                      const std::optional<std::string>& method) {
  const LoadedStack stack = LoadStackFile(options.input, method);
  const Representation& r = stack.representation;
  // By rows, as the streamed export, so both write the same bytes (streamed_interchange.h).
  WriteInterchangeFiles(options, r.method(), r.output_channels(),
                        [&](const Method& target) { return RefitEncodedByRows(stack, target); });
  if (!options.relight_web.empty()) {
    const RelightWebOptions web = RelightWebOptionsFor(options, r.method());
    WriteRelightWebFolder(options, [&](const RelightWebBands& bands, RelightWebBandsReport* made) {
      return RelightWebFromStack(stack, web, bands, made);
    });
  }
  WriteCompact(options, stack);
  WriteMaps(options, stack);
}

// A photometric set: .ptm/.rti fitted to its encoded values (as PTMfitter and RTIBuilder do),
// maps from a linear fit (Gradient unless --method says otherwise); streamed when it should be
// (StreamsCapture).
void ExportCapture(const ExportCommandOptions& options, const std::optional<std::string>& method) {
  const LoadOptions load =
      SetInputOptions{options.input, options.raw_intensities, options.colour_space}.ToLoadOptions();
  if (CaptureCanStream(options)) {
    StreamedSet set = OpenStreamedSet(options.input, load);
    if (StreamsCapture(options, set)) {
      ExportCaptureStreamed(options, set);
      return;
    }
  }
  const LoadedSet loaded = LoadSetForCommand(options.input, load);
  const StackProvenance provenance{loaded.set.lights(), "linear", options.input.string(),
                                   loaded.encodings};
  if (!options.viewer.empty()) {
    // A photometric set: the viewer shows the --method fit, or every method.
    std::vector<LoadedStack> fits;
    for (const Method& m : method ? std::vector{Method::Parse(*method)} : AllMethods()) {
      fits.push_back({Fit(loaded.set, m), provenance});
    }
    WriteViewer(options, fits);
  }
  WriteInterchangeFiles(options, "", loaded.set.channels(),
                        [&](const Method& target) { return FitEncoded(loaded.set, target); });
  if (!options.relight_web.empty()) {
    const RelightWebOptions web = RelightWebOptionsFor(options, "");
    WriteRelightWebFolder(options, [&](const RelightWebBands& bands, RelightWebBandsReport* made) {
      return RelightWebFromSet(loaded.set, web, bands, made);
    });
  }
  if (options.out.empty() && options.compact.empty()) return;
  const LoadedStack fit{Fit(loaded.set, Method::Parse(method.value_or("gradient"))), provenance};
  WriteCompact(options, fit);
  WriteMaps(options, fit);
}

// Whether anything but the viewer is asked for.
bool WritesMoreThanTheViewer(const ExportCommandOptions& options) {
  return !options.out.empty() || !options.ptm.empty() || !options.rti.empty() ||
         !options.relight_web.empty() || !options.compact.empty();
}

void RunExport(const ExportCommandOptions& options) {
  if (!WritesMoreThanTheViewer(options) && options.viewer.empty()) {
    throw Error(
        "nothing to write: give --out DIR (maps), --ptm FILE, --rti FILE, --relight-web DIR, "
        "--compact DIR and/or --viewer DIR");
  }
  const std::optional<std::string> method =
      options.method.empty() ? std::nullopt : std::optional(options.method);
  if (!IsStackInput(options.input)) {
    ExportCapture(options, method);
    return;
  }
  if (!options.viewer.empty()) {
    WriteViewerOfStacks(options, method);
    if (!WritesMoreThanTheViewer(options)) return;
  }
  if (!ExportStackStreamed(options, method)) ExportWholeStack(options, method);
}

void AddExportOptions(CLI::App& command, ExportCommandOptions& options) {
  command
      .add_option("input", options.input,
                  "A map stack (.exr or fit folder), a .ptm or .rti file, a relight web folder, or "
                  "a photometric set (folder, .lp, manifest, DiLiGenT)")
      ->required();
  command.add_option("--method", options.method,
                     "Which stack of a fit folder; for a photometric set, the method the maps "
                     "come from (default gradient)");
  command.add_option("--out", options.out, "Folder for the maps and the glTF tile");
  command
      .add_option("--normal-convention", options.normal_convention,
                  "opengl (+Y up: glTF, Blender) or directx (+Y down)")
      ->capture_default_str();
  command
      .add_option("--height", options.height,
                  "Height integrator: poisson (masked least squares, non-periodic samples) or "
                  "fc (Frankot-Chellappa, periodic samples)")
      ->capture_default_str();
  command.add_flag("--no-gltf", options.no_gltf, "Do not write the glTF tile");
  command.add_option("--ptm", options.ptm, "Also write a .ptm file (sRGB-encoded coefficients)");
  command.add_option("--ptm-format", options.ptm_format,
                     "rgb or lrgb (default: lrgb for colour data, as PTMfitter)");
  command.add_option("--rti", options.rti, "Also write an HSH .rti file");
  command.add_option("--hsh-terms", options.hsh_terms, "4, 9 or 16 (default 9)");
  command.add_option("--colour-space", options.colour_space,
                     "For a photometric set: how untagged integer images encode light (linear "
                     "or srgb; a file's own colour tags come first)");
  command.add_flag("--ignore-intensities", options.raw_intensities,
                   "For a photometric set: do not divide by the light intensities it gives");
  command.add_option("--relight-web", options.relight_web,
                     "Also write relight's web format (info.json + plane_N.jpg, the interchange "
                     "format relight and OpenLIME read) into this folder");
  command.add_option("--relight-basis", options.relight_basis,
                     "ptm, hsh, rbf or bilinear (default: the input's own, else ptm)");
  command.add_option("--relight-planes", options.relight_planes,
                     "rbf/bilinear: PCA planes (default 9)");
  command.add_option("--relight-quality", options.relight_quality,
                     "JPEG quality of the planes (default 95)");
  command.add_option("--compact", options.compact,
                     "Also write photomat's compact stack form (linear maps as 8-bit planes with "
                     "per-plane scale and bias + compact_stack.json; photomat-only, read by "
                     "relight and export like a stack) into this folder");
  command
      .add_option("--compact-coding", options.compact_coding,
                  "png (lossless planes) or jpeg (greyscale, --compact-quality)")
      ->capture_default_str();
  command.add_option("--compact-quality", options.compact_quality, "JPEG quality of the planes")
      ->capture_default_str();
  command
      .add_option("--compact-range-quantile", options.compact_range_quantile,
                  "Quantise each plane over its (1 - q) to q quantiles over the mask (tails "
                  "clipped); 1: minimum to maximum")
      ->capture_default_str();
  command
      .add_option("--compact-pca", options.compact_pca,
                  "Store the maps' principal components: K the K largest (all when the stack has "
                  "no more maps), -1 all, 0 the maps themselves")
      ->capture_default_str();
  command.add_option("--viewer", options.viewer,
                     "Also write the web relighting viewer into this folder: every stack of a fit "
                     "folder (or --method's), or for a photometric set every method's fit");
  command
      .add_option("--viewer-tiles", options.viewer_tiles,
                  "auto: the viewer gets stacks of more than 4096 x 4096 pixels as deep-zoom "
                  "tiles (read in bands, never whole); always; never")
      ->capture_default_str();
  command
      .add_option("--viewer-tile-size", options.viewer_tile_size,
                  "Pixels a side of the viewer's tiles")
      ->capture_default_str();
  command.add_flag("--viewer-without-maps", options.viewer_without_maps,
                   "Leave the normal, albedo and height views out of the viewer (for deep-zoom "
                   "tiles they take a streamed export of the maps, whose tiled Poisson height "
                   "costs more than the tiles themselves)");
  command.add_option(
      "--memory", options.memory_mb,
      fmt::format("Memory in MB for the maps of a stack (and the viewer's tiles); a stack or "
                  "photometric set whose export does not fit is exported streamed, in bands "
                  "(default: half the "
                  "physical memory or of this process's memory limits, here {} MB, of which "
                  "streamed bands take {} MB)",
                  DefaultMemoryBudget(kMinimumExportMemory) >> 20, kFastBandMemory >> 20));
  command.add_flag("--stream", options.stream,
                   "Export a stack's maps, .ptm and .rti streamed, in bands, whatever its size; "
                   "a photometric set is fitted in bands into scratch stacks beside the outputs "
                   "first, which its exports read (in bands, or the one stack whole for --height "
                   "fc, --compact and --relight-web; not for relight's rbf and bilinear bases)");
}

}  // namespace

void AddExportCommand(CLI::App& app) {
  BindCommand(*AddListedCommand(app, "export"), AddExportOptions, RunExport);
}

}  // namespace photomat::app
