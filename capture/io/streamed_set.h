#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "capture/io/load_photometric_set.h"
#include "core/image_band_io.h"
#include "core/photometric_set.h"
#include "core/progress.h"

namespace photomat {

// (Implemented in load_photometric_set.cc: LoadPhotometricSet is this with one band.)
// A photometric set opened for streaming (README, "Streamed fitting"): what LoadPhotometricSet
// reads, with every image held open as an ImageBandReader and decoded band by band in row order,
// so that memory depends on the band, not on the image. Opening reads only the headers, and
// rejects, before any pixel is decoded, images of another size or channel count (naming them).
class StreamedSet {
 public:
  int size() const { return static_cast<int>(readers_.size()); }
  int width() const { return readers_.front().width(); }
  int height() const { return readers_.front().height(); }
  int channels() const { return readers_.front().channels(); }
  const std::vector<LightDirection>& lights() const { return lights_; }
  const std::vector<std::string>& image_names() const { return names_; }
  const std::filesystem::path& source() const { return source_; }
  InputKind kind() const { return kind_; }
  // Whether the set has a mask (bands it covers only in part select some of their pixels).
  bool masked() const { return mask_.has_value(); }
  const std::optional<std::filesystem::path>& ground_truth_normals() const {
    return ground_truth_normals_;
  }
  // The intensities the input gives (empty: none) and whether the options asked to apply them.
  const std::vector<std::vector<float>>& intensities() const { return intensities_; }
  bool apply_intensities() const { return apply_intensities_; }
  int next_row() const { return readers_.front().next_row(); }
  // Per image, how its samples are decoded, decided when its file was opened (the same records
  // LoadPhotometricSet gives in LoadedSet::encodings).
  std::vector<ImageEncodingRecord> encodings() const;

  // The next `rows` rows of every image, decoded in parallel: a set of band images with the
  // lights, names, near lamps (their frame the whole image's), the band of the mask and the
  // intensities (applied if the options said so,
  // unless `raw`: then attached, for callers that look at the values as captured first). Throws
  // Error naming the image for a truncated or corrupt band. `progress` advances once per image.
  PhotometricSet ReadBand(int rows, bool raw = false, Progress* progress = nullptr);
  // The next band of every image decoded straight into caller-owned storage, in parallel:
  // `destinations[i]` (one view per image, of the set's width and channels, as many rows as the
  // band) receives image i's rows as ReadBand would give them raw (no intensities applied). The
  // streamed fit decodes this way into its image data matrix, with no band images and no copy.
  // Throws Error naming the image for a truncated or corrupt band, or for a view of another size.
  void ReadBandInto(std::span<const ImageView> destinations, Progress* progress = nullptr);
  // The next `rows` rows of every image, each handed raw to `use(image, band)` as soon as it is
  // decoded, in parallel (a thread decodes one image at a time into a scratch band it reuses;
  // `band` is contiguous, its row stride the width, and valid during the call only). For callers
  // that keep a part of every band, as a masked fit keeps its selected pixels: no band image per
  // image. Throws Error naming the image for a truncated or corrupt band, and whatever `use`
  // throws.
  void VisitBand(int rows, const std::function<void(int image, ConstImageView band)>& use);
  // Pixels of rows [first, first + rows) the mask selects (all without a mask).
  std::size_t SelectedPixels(int first, int rows) const;
  // Their indices within the band ((y - first) * width + x), ascending.
  std::vector<std::size_t> SelectedPixelIndices(int first, int rows) const;
  // Rows [first, first + rows) of the mask (every pixel set without a mask).
  Mask MaskRows(int first, int rows) const;
  // Back to row 0 (every file reopened): a further streamed pass.
  void Rewind();
  // The images `images` of the set (indices, in that order) opened anew at row 0: their lights,
  // names and intensities, the same mask, near lamps and options. For a pass that needs a few
  // images only (the evaluation report's pictures), without decoding the others. Throws Error
  // naming the set's source for an empty list or an index out of range.
  StreamedSet Subset(std::span<const int> images) const;
  // Per image, the clipped pixels (a channel at full scale) of the rows read so far.
  std::vector<std::size_t> SaturatedPixels() const;

 private:
  friend StreamedSet OpenStreamedSet(const std::filesystem::path& path, const LoadOptions& options);
  StreamedSet() = default;

  std::vector<std::filesystem::path> files_;
  ImageReadOptions read_;
  std::vector<ImageBandReader> readers_;
  std::vector<LightDirection> lights_;
  std::vector<std::string> names_;
  std::filesystem::path source_;
  InputKind kind_ = InputKind::kManifest;
  std::optional<Mask> mask_;
  std::vector<std::vector<float>> intensities_;
  bool apply_intensities_ = true;
  std::optional<std::filesystem::path> ground_truth_normals_;
  std::vector<NearLight> near_lamps_;  // the manifest's "lamp"s; each band gets them
};

// Opens the set at `path` for streaming (DetectInput, then every image's header). Throws Error
// naming the file for every fault LoadPhotometricSet reports before decoding.
StreamedSet OpenStreamedSet(const std::filesystem::path& path, const LoadOptions& options = {});

}  // namespace photomat
