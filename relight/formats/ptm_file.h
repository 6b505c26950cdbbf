#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "relight/formats/positioned_file.h"
#include "relight/formats/ptm_jpeg.h"
#include "represent/model/representation.h"

namespace photomat {

// Polynomial texture map files (.ptm, HP Labs' PTM_1.2, Malzbender & Gelb 2001; layout in
// README "Interchange formats"): a text header (version, format, width, height, 6 scales,
// 6 biases) and 8-bit coefficient bytes, a_i = (byte_i - bias_i) * scale_i, rows bottom to top.
//
// Values (IMPLEMENTER CHOICE): a PTM's polynomial evaluates to the 8-bit display code of the
// sRGB-encoded images it was fitted from, which is what PTMfitter fits and what PTM viewers show.
// photomat reads a file as a representation whose relit values are those codes / 255 (sRGB-encoded
// values in [0, 1]; the stack's colour space says "srgb"), and writes a file from such a
// representation. A linear stack is first refitted in the sRGB-encoded domain
// (relight/interchange.h), never stored as if it were encoded.

enum class PtmFormat {
  kRgb,       // PTM_FORMAT_RGB: per channel, 6 coefficients
  kLum,       // PTM_FORMAT_LUM: one channel, 6 coefficients
  kLrgb,      // PTM_FORMAT_LRGB: 6 luminance coefficients + 8-bit RGB per pixel
  kJpegRgb,   // PTM_FORMAT_JPEG_RGB: the RGB planes as JPEG streams (relight/formats/ptm_jpeg.h)
  kJpegLrgb,  // PTM_FORMAT_JPEG_LRGB: the LRGB planes as JPEG streams
};
std::string_view ToString(PtmFormat format);  // "PTM_FORMAT_RGB", ...

// What a .ptm holds, decoded to coefficient bytes (JPEG planes decompressed) but not dequantised.
struct PtmFile {
  std::string version = "PTM_1.2";
  PtmFormat format = PtmFormat::kRgb;
  int width = 0;
  int height = 0;
  std::array<double, 6> scale{};
  std::array<int, 6> bias{};
  // Coefficient planes of width * height bytes each, row 0 at the TOP (photomat's image order;
  // readers and writers flip the file's bottom-to-top rows). RGB: 18 planes, plane 3 j + c is
  // a_j of channel c; LUM: 6 planes a0..a5; LRGB: 9 planes, a0..a5 of the luminance then R, G, B.
  std::vector<std::vector<std::uint8_t>> planes;
  // The JPEG variants: how the file codes its planes (read from the header; what the writer
  // does). Streams are numbered as in the file: LRGB as `planes`, RGB channel by channel (stream
  // 6 c + j is a_j of channel c, plane 3 j + c here; see JpegStreamPlane). An empty coding writes
  // unpredicted planes at quality 90.
  PtmJpegCoding jpeg;

  int PlaneCount() const;
  // Dequantised a_j of `plane` (its coefficient is j = plane / 3 for RGB, plane for LUM/LRGB).
  double Coefficient(int plane, std::size_t pixel) const;
};

// The PtmFile plane that stream `stream` of a JPEG variant holds.
int JpegStreamPlane(PtmFormat format, int stream);

// Parses a whole .ptm file image; `file` names it in errors. Throws Error for anything malformed
// or truncated, and for the formats photomat does not read (lookup-table and JPEG-LS variants).
PtmFile ParsePtm(std::span<const std::uint8_t> data, const std::filesystem::path& file);
PtmFile ReadPtmFile(const std::filesystem::path& path);

// The bytes of a PTM_1.2 file; the JPEG variants coded as `ptm.jpeg` says.
std::string SerializePtm(const PtmFile& ptm);
// Atomic write; throws Error naming `path`.
void WritePtmFile(const std::filesystem::path& path, const PtmFile& ptm);

// The file as a representation: "ptm" (RGB; LUM as one channel "Y") or "ptm-lrgb" with maps in
// photomat's layout (README, "Representations"), values scaled by 1/255 as described above.
// LRGB: colour_c = (RGB_c / 255) * (L / 255), pinned by the PTMfitter fixture.
Representation RepresentationFromPtm(const PtmFile& ptm);

enum class PtmLayout { kRgb, kLrgb };
// Quantises a "ptm" (RGB or one channel) or "ptm-lrgb" representation of sRGB-encoded values:
// per coefficient, the scale is the smallest 6-decimal value >= (max - min) / 254 over all pixels
// and channels and the bias the integer ceil(-min / scale), so every value is representable and
// quantised within scale / 2. LRGB: each pixel's chroma is normalised so that its largest channel
// is 255 (the luminance carries the rest), and the luminance is quantised; the chroma bytes are
// within 1/2 of exact. Throws Error for other methods. The same as PtmCoefficientRanges over the
// whole map, then QuantisePtmPlanes.
PtmFile PtmFromRepresentation(const Representation& representation);

// The parts of PtmFromRepresentation, for a map given in bands of rows (the streamed export, README
// "Streamed relighting and export"): the format a representation is stored in (throws Error as
// PtmFromRepresentation for other methods), the per-coefficient ranges accumulated band by band
// (the scales and biases are global), and a band's coefficient bytes under chosen scales and
// biases. Every pixel's bytes depend on its own maps and the ranges only, so bands give the bytes
// of the whole map.
PtmFormat PtmFormatOf(const Representation& representation);

class PtmCoefficientRanges {
 public:
  explicit PtmCoefficientRanges(PtmFormat format);
  // The coefficients of `band` (any rows of the map); throws Error for a non-finite one or a band
  // of another format.
  void Add(const Representation& band);
  // Sets ptm.scale and ptm.bias from the ranges; throws Error when nothing finite was added.
  void ChooseScalesAndBiases(PtmFile& ptm) const;

 private:
  PtmFormat format_;
  std::string method_;
  std::array<double, 6> low_{}, high_{};
};

// `band`'s planes (PlaneCount of ptm.format, band rows top to bottom) quantised with ptm's scales
// and biases.
std::vector<std::vector<std::uint8_t>> QuantisePtmPlanes(const Representation& band,
                                                         const PtmFile& ptm);

// A raw .ptm (RGB, LUM or LRGB, PTM_1.2) written band by band of rows, top to bottom: the file's
// size is known from its header, so each band is written at its final offset (the file holds rows
// bottom to top) into a file of full size under a temporary name, renamed by Commit(). The bytes
// equal SerializePtm's for the same planes. Destroyed without Commit(), it leaves no file.
class PtmBandWriter {
 public:
  // `header`: version, format, size, scales and biases (its planes are ignored). Throws Error
  // naming `path` for a JPEG format or when the file cannot be created.
  PtmBandWriter(const std::filesystem::path& path, const PtmFile& header);
  int next_row() const { return next_row_; }
  // The next rows: PlaneCount planes of rows x width bytes (QuantisePtmPlanes of a band).
  void WriteNext(const std::vector<std::vector<std::uint8_t>>& planes);
  // Throws Error naming the file unless every row was written, or when renaming fails.
  void Commit();

 private:
  PtmBandWriter(const std::filesystem::path& path, const PtmFile& header, const std::string& text);
  PtmFile header_;
  std::size_t header_bytes_;
  PositionedFileWriter file_;
  int next_row_ = 0;
};

}  // namespace photomat
