#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "relight/formats/positioned_file.h"
#include "represent/model/representation.h"

namespace photomat {

// Hemispherical-harmonics RTI files (.rti, "#HSH1.2", written by RTIBuilder and relight; layout in
// README "Interchange formats"): '#' comment lines, then "3" (the HSH type), "width height
// colours", "terms basis-type element-size", each line ended by CRLF in real files; then `terms`
// float32 scales and `terms` float32 biases (little-endian), then per pixel, rows bottom to top,
// `terms` bytes for each colour in turn. Coefficient = byte / 255 * scale + bias.
//
// Values (IMPLEMENTER CHOICE, as for .ptm files): the harmonics evaluate to sRGB-encoded values in
// [0, 1] (RTIViewer shows value * 255), so a file reads as a representation of sRGB-encoded values.
struct RtiFile {
  int width = 0;
  int height = 0;
  int colours = 3;           // 1 or 3
  int terms = 9;             // 4, 9 or 16
  std::vector<float> scale;  // per term, shared by the colours
  std::vector<float> bias;
  // terms * colours planes of width * height bytes, row 0 at the TOP; plane j * colours + c is
  // term j of colour c (photomat's map order).
  std::vector<std::vector<std::uint8_t>> planes;
  std::vector<std::string> comments;  // the '#' lines, without the '#'

  double Coefficient(int plane, std::size_t pixel) const {
    return planes[plane][pixel] / 255.0 * scale[plane / colours] + bias[plane / colours];
  }
};

// Throws Error naming `file` for anything malformed or truncated, and for RTI types other than
// HSH (3), element sizes other than 1 byte and term counts other than 4, 9 and 16.
RtiFile ParseRti(std::span<const std::uint8_t> data, const std::filesystem::path& file);
RtiFile ReadRtiFile(const std::filesystem::path& path);

// The bytes of the file, header lines ended by CRLF as real files have them ("#HSH1.2" first).
std::string SerializeRti(const RtiFile& rti);
void WriteRtiFile(const std::filesystem::path& path, const RtiFile& rti);

// "hsh4" / "hsh9" / "hsh16" with maps "hsh.hJ.R/G/B" (or ".Y").
Representation RepresentationFromRti(const RtiFile& rti);

// Quantises an HSH representation: per term, bias = the minimum and scale = max - min over all
// pixels and colours (as RTIBuilder), bytes rounded, so every coefficient is within scale / 510.
// Throws Error for representations that are not HSH. The same as RtiTermRanges over the whole
// map, then QuantiseRtiPlanes.
RtiFile RtiFromRepresentation(const Representation& representation);

// The parts of RtiFromRepresentation, for a map given in bands of rows (the streamed export,
// README "Streamed relighting and export"): the file's size, colours and terms (throws Error as
// RtiFromRepresentation for representations that are not HSH), the per-term ranges accumulated
// band by band (scales and biases are global), and a band's bytes under chosen scales and biases.
RtiFile RtiHeaderOf(const Representation& representation);

class RtiTermRanges {
 public:
  RtiTermRanges(int terms, int colours);
  // The coefficients of `band` (any rows); throws Error for a non-finite one or another layout.
  void Add(const Representation& band);
  // Sets rti.scale and rti.bias; throws Error when nothing was added.
  void ChooseScalesAndBiases(RtiFile& rti) const;

 private:
  int colours_;
  std::string method_;
  std::vector<float> low_, high_;
};

// `band`'s terms x colours planes (band rows top to bottom) quantised with rti's scales and biases.
std::vector<std::vector<std::uint8_t>> QuantiseRtiPlanes(const Representation& band,
                                                         const RtiFile& rti);

// An .rti written band by band of rows, top to bottom, each band at its final offset (the file
// holds rows bottom to top) in a file of full size under a temporary name, renamed by Commit().
// The bytes equal SerializeRti's for the same planes; destroyed without Commit(), no file is left.
class RtiBandWriter {
 public:
  // `header`: size, colours, terms, scales, biases and comments (its planes are ignored). Throws
  // Error naming `path` for an invalid header or when the file cannot be created.
  RtiBandWriter(const std::filesystem::path& path, const RtiFile& header);
  int next_row() const { return next_row_; }
  // The next rows: terms x colours planes of rows x width bytes (QuantiseRtiPlanes of a band).
  void WriteNext(const std::vector<std::vector<std::uint8_t>>& planes);
  // Throws Error naming the file unless every row was written, or when renaming fails.
  void Commit();

 private:
  RtiBandWriter(const std::filesystem::path& path, const RtiFile& header, const std::string& text);
  RtiFile header_;
  std::size_t header_bytes_;
  PositionedFileWriter file_;
  int next_row_ = 0;
};

}  // namespace photomat
