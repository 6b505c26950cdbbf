#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "capture/io/streamed_set.h"
#include "core/photometric_set.h"
#include "core/progress.h"
#include "represent/model/light_basis.h"
#include "represent/model/method.h"
#include "represent/model/representation.h"
#include "represent/stack/map_stack.h"
#include "represent/stack/stack_band_reader.h"

namespace photomat {

// relight's web format (cnr-isti-vclab/relight: written by relight-cli and RelightLab, read by
// relight's viewer and OpenLIME; layout in README "Interchange files and exports"): a folder
// holding `info.json` and `plane_N.jpg`, each JPEG carrying three coefficient planes as its R, G
// and B (plane 3N + k in channel k), rows top to bottom. A plane's bytes b dequantise to
//   value = scale * (b - 255 bias)            (relight's Material::Plane)
// in display codes (0..255 for a relit value). Bases:
//   ptm (colorspace rgb: 9 or 18 planes, plane 3j + c is term j of colour c, terms 1, lx, ly,
//        lx^2, lx ly, ly^2; lrgb: planes 0..2 the chroma bytes, then 3 or 6 luminance terms,
//        colour_c = L / 255 * byte_c),
//   hsh (rgb: 12 or 27 planes, the 4 or 9 hemispherical harmonics of represent/model/hsh.h),
//   rbf and bilinear (colorspace mrgb: each plane one scalar per pixel; relit colour
//        = mean(l) + sum_p value_p E_p(l), where mean and the E_p are RGB functions of the light
//        stored in "basis" as integers: mean in codes, E_p as 127 + range_p E_p; rbf interpolates
//        them between "lights" with normalised Gaussians exp(-|l - l_i|^2 / sigma^2) (weights of
//        0.001 or less dropped), bilinear on a resolution^2 octahedral grid of the hemisphere).
//
// Values (IMPLEMENTER CHOICE, as for .ptm and .rti files, relight/formats/interchange.h): the
// codes are sRGB-encoded display values unless "colorprofile" says "RGB" (relight-cli's default:
// linear codes), so a folder reads as a representation of values in [0, 1] (codes / 255) with the
// stack colour space "srgb" or "linear", and is written from a fit in the encoded domain.
//
// This is the interchange format for relight and OpenLIME (`photomat export --relight-web DIR`);
// photomat's own compact form, which keeps photomat's bases and linear values, is
// compact_stack.h (`photomat export --compact DIR`).

enum class RelightWebBasis { kPtm, kHsh, kRbf, kBilinear };
enum class RelightWebColourSpace { kRgb, kLrgb, kMrgb };
std::string_view ToString(RelightWebBasis basis);               // "ptm", "hsh", "rbf", "bilinear"
std::string_view ToString(RelightWebColourSpace colour_space);  // "rgb", "lrgb", "mrgb"

struct RelightWebStack {
  RelightWebBasis basis = RelightWebBasis::kPtm;
  RelightWebColourSpace colour_space = RelightWebColourSpace::kRgb;
  int width = 0;
  int height = 0;
  int quality = 95;  // JPEG quality of the planes
  // Planes of width * height bytes, row 0 at the top.
  std::vector<std::vector<std::uint8_t>> planes;
  std::vector<double> scale;  // per plane
  std::vector<double> bias;   // per plane
  std::vector<double> range;  // per plane, mrgb only: E_p = (stored - 127) / range_p
  // mrgb only: (planes + 1) x dimensions x 3 integers, first the mean then each plane's E_p;
  // dimension i is light i (rbf) or grid node x + y resolution (bilinear).
  std::vector<int> basis_values;
  std::vector<Eigen::Vector3d> lights;  // rbf: the interpolation nodes; others: optional
  double sigma = 0.125;                 // rbf
  int resolution = 8;                   // bilinear
  // "colorprofile": what the codes encode. relight-cli writes "RGB" (linear codes, its default),
  // "sRGB" or "P3"; files without it (older relight, OpenLIME's samples) hold sRGB display codes.
  // photomat writes "sRGB" and reads "RGB" as linear, "sRGB" or none as sRGB-encoded; "P3" is
  // rejected (other primaries).
  bool linear = false;

  int PlaneCount() const { return static_cast<int>(planes.size()); }
  int Dimensions() const;  // rbf: lights, bilinear: resolution^2, else 0
  double Value(int plane, std::size_t pixel) const {
    return scale[plane] * (planes[plane][pixel] - 255.0 * bias[plane]);
  }
};

// True for a folder holding an info.json (what ReadRelightWeb reads).
bool IsRelightWebFolder(const std::filesystem::path& path);

// Reads `folder`/info.json and its plane_N.jpg. Throws Error naming the file and the fault (a
// missing member, an unknown basis or colour space, plane or basis counts that do not match,
// a JPEG of the wrong size); ycc and mycc stacks are rejected with the colour space named.
RelightWebStack ReadRelightWeb(const std::filesystem::path& folder);
// Writes the folder whole or not at all (relight/render/output_folder.h; an existing folder is
// replaced only when it is empty or another relight web folder, whose info.json says
// "format": "jpg"). Throws Error naming the folder.
void WriteRelightWeb(const std::filesystem::path& folder, const RelightWebStack& stack);

// The stack as a representation of sRGB-encoded values: ptm/ptm-lrgb (first-degree files get
// zero quadratic maps), hsh4/hsh9, and for rbf/bilinear the method "relight-rbf" /
// "relight-bilinear" with a RelightWebLightBasis (below).
Representation RepresentationFromRelightWeb(const RelightWebStack& stack);

// rbf/bilinear read from a relight web folder: the light coefficients are relight's RGB basis
// functions, c_(3 p + o)(l) = E_p,o(l) (p = 0 the mean / 255), and the maps are per channel,
// B_(3 p + o'),o = value_p / 255 where o = o' and 0 elsewhere (value_0 = 255): the sum
// sum_p value_p E_p,o(l) of relight's renderer in photomat's MapLayout, at the cost of 9 maps per
// plane (most zero). Not stored in map stacks (LightBasisFromJson has no such kind).
class RelightWebLightBasis final : public LightBasis {
 public:
  // Takes the stack's basis, lights, sigma and resolution (not its planes).
  explicit RelightWebLightBasis(const RelightWebStack& stack);
  std::string_view kind() const override { return "relight-web"; }
  int size() const override { return 3 * (planes_ + 1); }
  Eigen::VectorXd Coefficients(const LightDirection& light) const override;
  nlohmann::json ToJson() const override;

  // relight's interpolation weights of the dimensions at `light` (index, weight).
  std::vector<std::pair<int, double>> DimensionWeights(const LightDirection& light) const;

 private:
  RelightWebBasis basis_;
  int planes_;
  int dimensions_;
  std::vector<double> functions_;  // (planes + 1) x dimensions x 3, dequantised, mean / 255
  std::vector<Eigen::Vector3d> lights_;
  double sigma_;
  int resolution_;
};

struct RelightWebOptions {
  // ptm, hsh (harmonics from the stack's method when it is hsh4/hsh9, else 9), rbf or bilinear.
  RelightWebBasis basis = RelightWebBasis::kPtm;
  int quality = 95;
  int planes = 9;        // rbf, bilinear: PCA planes (relight-cli's default 9)
  int hsh_terms = 9;     // hsh: 4 or 9 (relight has no 16-term HSH)
  double sigma = 0.125;  // rbf (relight-cli's default)
  int resolution = 8;    // bilinear grid side (relight-cli's default)
  // Each plane is quantised over the range from its (1 - q) to its q quantile over the pixels,
  // values outside clipped (relight-cli's -Q, default 0.995); 1 (the default): min to max, no
  // value clipped.
  double range_quantile = 1.0;
};

// How relight's rbf and bilinear planes are made band by band (below). A PCA of every pixel's
// RGB profile at the nodes would hold the profiles of the whole image (3 floats per pixel and
// node: a 48 MP capture of 50 lights, 29 GB); instead the nodes' values are made a band of rows
// at a time, three times: (1) the profiles' mean, (2) their covariance about it (RowGram,
// represent/fitting/observations.h), (3) each pixel's coefficients on the PCA axes. Only the
// coefficient planes are held whole (4 bytes per pixel and plane, then their bytes), because a
// plane's quantisation range is over all its pixels. Every sum is made in a fixed order (per
// image row, the rows in order), so the planes do not depend on the band height.
struct RelightWebBands {
  // Bytes the bands may hold (beyond the whole planes); 0: DefaultBandBudget(
  // kMinimumRelightWebMemory).
  std::size_t memory_bytes = 0;
  // > 0: exactly this many rows per band (tests).
  int band_rows = 0;
  // One phase per pass.
  Progress* progress = nullptr;
};
inline constexpr std::size_t kMinimumRelightWebMemory = std::size_t{16} << 20;

// How rbf or bilinear planes were made: rows per band, and passes over the bands (3); both 0 for
// ptm and hsh.
struct RelightWebBandsReport {
  int band_rows = 0;
  int passes = 0;
};

// The stack in relight's web format. ptm/hsh: ConvertToEncoded (relight/formats/interchange.h;
// the stack itself when it already is such a fit of encoded values). rbf/bilinear: the stack
// relit at the nodes (rbf: its capture lights, or RefitLights() when it records none; bilinear:
// the grid's directions), sRGB-encoded when linear, and, as relight's builder does, a PCA of
// the pixels' RGB profiles (mean + `planes` axes), made in `bands`; the node values are what
// relight interpolates. Planes are quantised over their whole range (min to max: no value is
// clipped) and the coefficients are projected onto the basis as stored (after its integer
// rounding). Throws Error for pbr (a nonlinear shading) and for option values relight does not
// read.
RelightWebStack RelightWebFromStack(const LoadedStack& stack, const RelightWebOptions& options,
                                    const RelightWebBands& bands = {},
                                    RelightWebBandsReport* report = nullptr);
// The same from a map stack read band by band: rbf and bilinear never hold the stack whole (the
// same planes as from the loaded stack, byte for byte); ptm and hsh load it (their planes are
// the stack's own maps, refitted).
RelightWebStack RelightWebFromStack(StackBandReader& stack, const RelightWebOptions& options,
                                    const RelightWebBands& bands = {},
                                    RelightWebBandsReport* report = nullptr);

// The method relight's ptm, hsh or bilinear planes are made from when built from photographs,
// fitted to their encoded values (ptm, hsh4, hsh9 or bilinear): what RelightWebFromSet fits, and
// what a streamed export fits in bands before RelightWebFromStack. None for rbf, whose node
// values are the photographs themselves. Throws Error for options relight does not read (JPEG
// quality, range quantile, HSH other than 4 or 9 terms).
std::optional<Method> RelightWebFitMethod(const RelightWebOptions& options);

// The same from photographs, as relight-cli builds from them: ptm/hsh fitted to the sRGB-encoded
// values (FitEncoded), rbf with the encoded photographs themselves as the node values, bilinear
// from photomat's bilinear fit of the encoded values read at the octahedral grid's directions.
RelightWebStack RelightWebFromSet(const PhotometricSet& set, const RelightWebOptions& options,
                                  const RelightWebBands& bands = {},
                                  RelightWebBandsReport* report = nullptr);
// rbf from photographs read band by band (the same planes as from the loaded set, byte for
// byte). The other bases are made from a fit of the encoded photographs (RelightWebFitMethod):
// fit it in bands (FitStreamed with encoded_values) and give its stack to RelightWebFromStack;
// this throws Error for them, saying so.
RelightWebStack RelightWebFromSet(StreamedSet& set, const RelightWebOptions& options,
                                  const RelightWebBands& bands = {},
                                  RelightWebBandsReport* report = nullptr);

}  // namespace photomat
