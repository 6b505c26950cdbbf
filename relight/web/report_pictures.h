#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"

namespace photomat {

// The evaluation report's pictures (evaluation_report.h) at display size, made band by band.

// IMPLEMENTER CHOICE: the report shows its pictures at most this many pixels on their longer
// side. A larger capture's pictures are reduced by a whole factor (ReportDisplayFactor), each
// display pixel the mean of a block: a 48 MP capture's full-size PNGs would be about 100 MB each,
// two dozen of them on one page, and a picture a few times the screen's size shows no more.
inline constexpr int kReportDisplaySide = 1024;

// The smallest whole factor that brings width x height within kReportDisplaySide (1 for images
// that fit: those are shown pixel for pixel).
int ReportDisplayFactor(int width, int height);

// A picture reduced by a whole factor, accumulated band by band: display pixel (X, Y) is the mean
// of the pixels x / factor = X, y / factor = Y (blocks at the right and bottom edges may be
// smaller). With `skip_negative`, values below 0 (undefined, as AngularErrorMap's -1) are left
// out of the means and a block without any other reads -1. Sums are in double, added in the
// order the rows arrive, so bands given in row order make the same picture whatever their height.
// Memory: 8 bytes per display value (12 with skip_negative): 19 MB for an RGB picture of 1024 x
// 768, whatever the image's size.
class DisplayReduction {
 public:
  DisplayReduction(int width, int height, int channels, int factor, bool skip_negative = false);

  int factor() const { return factor_; }
  // Rows [first, first + band.height()) of the picture, every channel. Throws Error for a band
  // of another width or channel count, or outside the picture.
  void Add(int first, ConstImageView band);
  // Whether any row was added.
  bool has_rows() const { return rows_added_ > 0; }
  // Counts every row not added as zeros (a fit's value outside its mask, for a picture whose
  // bands without any masked pixel were skipped). Adding zeros changes no sum, so this gives the
  // means of those rows added in order.
  void CountMissingRowsAsZero();
  // The reduced picture: ceil(width / factor) x ceil(height / factor).
  Image Result() const;

 private:
  int width_, height_, channels_, factor_;
  bool skip_negative_;
  int display_width_, display_height_;
  std::vector<double> sums_;                 // planar, display size
  std::vector<std::uint32_t> valid_counts_;  // with skip_negative only

  std::vector<char> row_added_;
  int rows_added_ = 0;
};

}  // namespace photomat
