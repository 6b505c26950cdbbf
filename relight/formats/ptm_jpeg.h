#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace photomat {

// The planes of PTM_FORMAT_JPEG_RGB / _JPEG_LRGB files (HP Labs' PTM 1.2 report; Motta &
// Weinberger, "Compression of Polynomial Texture Maps", HPL-2000-143): every coefficient plane is
// one greyscale JPEG stream, optionally predicted from another plane so that the stream holds only
// the residual. Planes here are numbered as in the file ("streams") and hold the bytes in the
// file's row order (bottom row first); relight/formats/ptm_file.h maps them to PtmFile::planes.
//
// Prediction of a plane from its reference r (decoded before it, side information included):
//   prediction(x, y) = T(r(clamp(x + motion_x), clamp(y + motion_y)))
//   plane(x, y)      = (jpeg(x, y) - 128 + prediction(x, y)) mod 256
// with T(v) = 255 - v for an inverted reference ("plane inversion", transform bit 0) and the
// identity otherwise, and the motion vector used only when the plane is motion compensated
// (transform bit 1). x runs along a stored row, y over the stored rows (bottom to top). Then the
// plane's side information, 5-byte records (big-endian index of the stored pixel, byte), replaces
// the pixels the JPEG could not carry.
// The sources: the inversion and the residual offset of 128 as RTIViewer (its Java port) and
// Perathoner's ptmlib decode them (255 - r, "+ r - 128" modulo 256); the decoding order and the
// side information as relight's legacy reader. IMPLEMENTER CHOICE where no public decoder goes
// (none implements motion compensation): the vector points from the plane to the sample of the
// reference that predicts it, in stored pixels, and samples beyond the image take the nearest edge
// pixel (the choice of video codecs' unrestricted motion vectors). Transform values are bit sets
// (ptmlib tests bit 0); 2 = MOTION_COMPENSATION is named in a reader for Cinema 4D.
using PlaneBytes = std::vector<std::uint8_t>;

struct PtmPlaneCoding {
  bool inverted = false;            // transform bit 0: predict from 255 - reference
  bool motion_compensated = false;  // transform bit 1: predict from the shifted reference
  int motion_x = 0;                 // ignored unless motion compensated (as RTIViewer's port)
  int motion_y = 0;
  int order = 0;       // position of this plane in the decoding sequence (0 = first)
  int reference = -1;  // the plane it is predicted from, -1 for none

  // The header's transform integer (bit 0 inversion, bit 1 motion compensation).
  int Transform() const { return (inverted ? 1 : 0) | (motion_compensated ? 2 : 0); }
  bool operator==(const PtmPlaneCoding&) const = default;
};

struct PtmJpegCoding {
  int quality = 90;  // the header's compression parameter; the JPEG quality the writer uses
  // Writer only: stored pixels that the decoder would get wrong by more than this many codes are
  // sent as side information (255: none). Prediction wraps modulo 256, so a residual beyond
  // +-127 comes out near 255 codes off; a tolerance catches those pixels.
  int side_information_tolerance = 255;
  std::vector<PtmPlaneCoding> planes;  // one per stream

  // No prediction, planes decoded in file order.
  static PtmJpegCoding Unpredicted(int plane_count, int quality);
};

// Throws Error naming `file` (when not empty) and the faulty field unless `coding` describes
// `plane_count` planes of `width` x `height` that can be decoded: a permutation for the order,
// references to other planes that are decoded before them (no cycles), motion vectors shorter
// than the image.
void CheckPtmJpegCoding(const PtmJpegCoding& coding, int plane_count, int width, int height,
                        const std::filesystem::path& file);

// What `plane` is predicted from: the reference's bytes through the plane's transform (above).
// `reference` holds width * height stored bytes.
PlaneBytes PredictPtmPlane(const PlaneBytes& reference, const PtmPlaneCoding& plane, int width,
                           int height);

// One plane as the file carries it.
struct PtmJpegStream {
  std::span<const std::uint8_t> jpeg;
  std::span<const std::uint8_t> side_information;
};

// Decodes the planes of a checked coding (CheckPtmJpegCoding) from their streams, in the coding's
// order; faults (an unreadable JPEG, a side record beyond the image) name `file`.
std::vector<PlaneBytes> DecodePtmJpegPlanes(const PtmJpegCoding& coding,
                                            std::span<const PtmJpegStream> streams, int width,
                                            int height, const std::filesystem::path& file);

struct EncodedPtmPlane {
  std::string jpeg;
  std::string side_information;
};
// Encodes stored planes with `coding` (checked here). Closed loop: each residual is taken against
// the prediction from the reference as the decoder will reconstruct it, so JPEG errors do not
// accumulate along chains of references.
std::vector<EncodedPtmPlane> EncodePtmJpegPlanes(const PtmJpegCoding& coding,
                                                 const std::vector<PlaneBytes>& planes, int width,
                                                 int height);

}  // namespace photomat
