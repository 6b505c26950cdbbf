#include "relight/web/report_pictures.h"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.h"

namespace photomat {

int ReportDisplayFactor(int width, int height) {
  const int side = std::max(width, height);
  return std::max(1, (side + kReportDisplaySide - 1) / kReportDisplaySide);
}

DisplayReduction::DisplayReduction(int width, int height, int channels, int factor,
                                   bool skip_negative)
    : width_(width),
      height_(height),
      channels_(channels),
      factor_(factor),
      skip_negative_(skip_negative),
      display_width_((width + factor - 1) / std::max(factor, 1)),
      display_height_((height + factor - 1) / std::max(factor, 1)) {
  if (width <= 0 || height <= 0 || channels <= 0 || factor <= 0) {
    throw Error(
        fmt::format("cannot reduce a {}x{}x{} picture by {}", width, height, channels, factor));
  }
  const std::size_t size = static_cast<std::size_t>(display_width_) * display_height_ *
                           static_cast<std::size_t>(channels);
  sums_.assign(size, 0.0);
  if (skip_negative_) valid_counts_.assign(size, 0);
  row_added_.assign(static_cast<std::size_t>(height), 0);
}

void DisplayReduction::Add(int first, ConstImageView band) {
  if (band.width() != width_ || band.channels() != channels_ || first < 0 ||
      first + band.height() > height_) {
    throw Error(fmt::format("a {}x{}x{} band at row {} is not part of a {}x{}x{} picture",
                            band.width(), band.height(), band.channels(), first, width_, height_,
                            channels_));
  }
  for (int y = 0; y < band.height(); ++y) {
    if (row_added_[static_cast<std::size_t>(first + y)]) {
      throw Error(fmt::format("row {} of the picture was added before", first + y));
    }
    row_added_[static_cast<std::size_t>(first + y)] = 1;
  }
  rows_added_ += band.height();
  const std::size_t plane = static_cast<std::size_t>(display_width_) * display_height_;
  for (int c = 0; c < channels_; ++c) {
    for (int y = 0; y < band.height(); ++y) {
      const auto row = band.row(c, y);
      const std::size_t offset =
          c * plane + static_cast<std::size_t>((first + y) / factor_) * display_width_;
      for (int x = 0; x < width_; ++x) {
        const float v = row[x];
        if (skip_negative_) {
          if (v < 0.0f) continue;
          ++valid_counts_[offset + x / factor_];
        }
        sums_[offset + x / factor_] += v;
      }
    }
  }
}

void DisplayReduction::CountMissingRowsAsZero() {
  const std::size_t plane = static_cast<std::size_t>(display_width_) * display_height_;
  for (int y = 0; y < height_; ++y) {
    if (row_added_[static_cast<std::size_t>(y)]) continue;
    row_added_[static_cast<std::size_t>(y)] = 1;
    ++rows_added_;
    if (!skip_negative_) continue;  // the count follows from the rows added
    for (int c = 0; c < channels_; ++c) {
      const std::size_t offset = c * plane + static_cast<std::size_t>(y / factor_) * display_width_;
      for (int x = 0; x < width_; ++x) ++valid_counts_[offset + x / factor_];
    }
  }
}

Image DisplayReduction::Result() const {
  // Without skipping, a block's count is its rows added times its columns.
  std::vector<double> rows(static_cast<std::size_t>(display_height_), 0.0);
  for (int y = 0; y < height_; ++y) rows[y / factor_] += row_added_[static_cast<std::size_t>(y)];
  Image out(display_width_, display_height_, channels_);
  const std::size_t plane = static_cast<std::size_t>(display_width_) * display_height_;
  for (int c = 0; c < channels_; ++c) {
    auto values = out.plane(c);
    for (int y = 0; y < display_height_; ++y) {
      for (int x = 0; x < display_width_; ++x) {
        const std::size_t p = static_cast<std::size_t>(y) * display_width_ + x;
        const double columns = std::min(factor_, width_ - x * factor_);
        const double count = skip_negative_ ? valid_counts_[c * plane + p] : rows[y] * columns;
        values[p] = count > 0.0 ? static_cast<float>(sums_[c * plane + p] / count)
                                : (skip_negative_ ? -1.0f : 0.0f);
      }
    }
  }
  return out;
}

}  // namespace photomat
