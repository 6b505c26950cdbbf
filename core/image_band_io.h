#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/atomic_file.h"
#include "core/image.h"
#include "core/image_io.h"

namespace photomat {

// Image files read and written band by band of rows (implemented in image_io.cc, beside the
// whole-image ReadImage and WriteImage, which are these with one band).

// One image file read in order, band by band: what streamed fitting holds open for every image
// of a set (README, "Streamed fitting"). Rows come in file order only (JPEG and PNG decoders are
// sequential); memory is one decoding chunk (16 rows, or a row of tiles) of file samples. Values
// are the same as ReadImage's: ReadImage is this reader with one band of every row.
class ImageBandReader {
 public:
  // Opens the file and reads its header. Throws Error naming `path` as ReadImage does.
  explicit ImageBandReader(const std::filesystem::path& path, const ImageReadOptions& options = {});
  // No file (a place to move an open reader into).
  ImageBandReader();
  ~ImageBandReader();
  ImageBandReader(ImageBandReader&&) noexcept;
  ImageBandReader& operator=(ImageBandReader&&) noexcept;

  const std::filesystem::path& path() const { return path_; }
  int width() const { return width_; }
  int height() const { return height_; }
  // Channels kept (alpha dropped unless ImageReadOptions::keep_alpha).
  int channels() const { return kept_; }
  // The file's format, attributes and encoding (decided once, when the file is opened, by
  // core/sample_encoding; every band is converted by it); saturated_pixels counts the rows read
  // so far.
  const ImageFileInfo& info() const { return info_; }
  int next_row() const { return next_row_; }
  // The file's channel names when every channel is kept; empty otherwise.
  const std::vector<std::string>& channel_names() const { return channel_names_; }

  // Decodes the next band.rows() rows into `band` (width() x rows, channels() planes). Throws
  // Error naming the file when they run past the end, the file is truncated or corrupt there, or
  // a sample is NaN or infinite.
  void ReadNext(ImageView band);

 private:
  struct Decoder;
  std::filesystem::path path_;
  std::unique_ptr<Decoder> decoder_;
  int width_ = 0;
  int height_ = 0;
  int kept_ = 0;
  int next_row_ = 0;
  std::vector<std::string> channel_names_;
  ImageFileInfo info_;
};

// Whether `path`'s extension (any case) names an image format the installed OpenImageIO reads
// (PNG, TIFF, JPEG, EXR, PNM, camera RAW such as .dng/.cr2/.nef, ...): how photomat picks the
// images out of a folder of frames. OpenImageIO's own list, so RAW and other plugins count.
bool IsReadableImageFileName(const std::filesystem::path& path);

// "img.2.png" before "img.10.png": runs of digits compare as numbers (leading zeros aside), the
// rest character by character; the order of numbered frames however they are padded.
bool NaturalLess(std::string_view a, std::string_view b);

// The image files (IsReadableImageFileName) directly inside `folder`, in NaturalLess order of
// their names; subfolders and other files are skipped. Throws Error naming the folder when it is
// not a readable folder (an empty list is not an error here: callers say what they expected).
std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& folder);

// A mask image: a pixel is set where any channel is above half of full scale (thresholding the
// anti-aliased masks of real data sets at 50 %).
Mask ReadMask(const std::filesystem::path& path);

// The channel names an image without names is written with: Y, Y A, R G B, R G B A, else
// channel0, channel1, ...
std::vector<std::string> DefaultChannelNames(int channels);

// An image file written in order, band by band, to a temporary name (PendingFile) that Commit()
// renames: a map stack written straight from a streamed fit. WriteImage is this writer with one
// band. Float, half or integer samples as ImageWriteOptions say.
class ImageBandWriter {
 public:
  // Throws Error naming `path` when the format has no writer or the file cannot be opened.
  ImageBandWriter(const std::filesystem::path& path, int width, int height,
                  std::vector<std::string> channel_names, const ImageWriteOptions& options = {});
  ~ImageBandWriter();

  const std::filesystem::path& path() const { return file_.path(); }
  int next_row() const { return next_row_; }
  // Writes band.rows() rows after those written so far (width and channels as opened).
  void WriteNext(ConstImageView band);
  // Every row written: closes the file and renames it into place. Throws Error naming path().
  // `before_rename`, if given, is called with the closed temporary file first (to patch a header
  // value that only the last band decides; an Error it throws leaves nothing at path()).
  void Commit(const std::function<void(const std::filesystem::path& temp)>& before_rename = {});

 private:
  struct Encoder;
  PendingFile file_;
  std::unique_ptr<Encoder> encoder_;
  int width_ = 0;
  int height_ = 0;
  int channels_ = 0;
  int next_row_ = 0;
  ImageWriteOptions options_;
};

}  // namespace photomat
