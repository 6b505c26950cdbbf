#include "represent/streaming/band_streamer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "calibrate/radiometry/exposure.h"
#include "core/colour.h"

namespace photomat::streaming_internal {
namespace {

// Each value re-encoded with the sRGB curve, as FitEncoded encodes the in-memory set's images
// (the same bits per value).
void EncodeSrgb(Eigen::MatrixXf& matrix) {
  tbb::parallel_for(Eigen::Index{0}, matrix.cols(), [&](Eigen::Index column) {
    for (float& v : matrix.col(column)) v = static_cast<float>(LinearToSrgb(v));
  });
}

}  // namespace

std::vector<int> AllImages(int count) {
  std::vector<int> all(static_cast<std::size_t>(count));
  std::iota(all.begin(), all.end(), 0);
  return all;
}

bool IsLightProfile(const Method& method) {
  return method.kind == Method::Kind::kRbf || method.kind == Method::Kind::kBilinear;
}

// Methods whose fit needs the Gram matrix of the whole set's profiles (a streamed pass first).
bool NeedsGram(const Method& method) {
  return method.kind == Method::Kind::kEigen || IsLightProfile(method);
}

Streamer::Streamer(StreamedSet& set, std::span<const Method> methods,
                   const StreamedFitOptions& options, bool robust_fit_of_every_image)
    : set_(set),
      options_(options),
      robust_fit_of_every_image_(robust_fit_of_every_image),
      all_(AllImages(set.size())) {
  band_rows_ = options.band_rows > 0
                   ? std::min(options.band_rows, set.height())
                   : StreamedBandRows(options.memory_bytes > 0 ? options.memory_bytes
                                                               : DefaultStreamedBudget(set),
                                      set, methods, options.robust);
  bands_ = (set.height() + band_rows_ - 1) / band_rows_;
}

void Streamer::Read(Band& band) {
  band.first = set_.next_row();
  band.rows = std::min(band_rows_, set_.height() - band.first);
  const std::size_t selected = set_.SelectedPixels(band.first, band.rows);
  if (selected == 0) {
    set_.VisitBand(band.rows, [](int, ConstImageView) {});  // decoded past, nothing kept
    return;
  }
  if (!options_.robust) {
    ReadLeastSquaresBand(band, selected);
    return;
  }
  // Robust: a band set, whose images the robust fit looks at as captured first.
  PhotometricSet raw = set_.ReadBand(band.rows, true);
  band.measured = MeasuredPixelMasks(raw);
  if (set_.apply_intensities()) raw.ApplyIntensities();
  band.set.emplace(std::move(raw));
  band.observations.emplace(*band.set);
  if (!robust_fit_of_every_image_) return;
  RobustFitOptions robust = options_.robust_options;
  robust.measured = band.measured;
  robust.progress = nullptr;
  // The band's lamps (their frame the whole image's, from its first row) for pbr.
  if (band.set->near_lighting()) robust.near_lighting = &*band.set->near_lighting();
  band.robust.emplace(*band.observations, band.set->lights(), all_, robust, set_.source());
}

// A least-squares band decoded straight into the columns of its image data matrix, the
// intensities divided out there: no band images, no zero-filling and no copy, which were a
// quarter of a streamed PTM fit's CPU time beside the decoding (perf, 12 MP x 50 JPEGs). A band
// whose every pixel takes part is decoded into the columns themselves
// (StreamedSet::ReadBandInto); one the mask covers in part has each image's band decoded into a
// scratch band of its thread and its selected pixels gathered (StreamedSet::VisitBand). Robust
// fits (which look at the band's images as captured) read a band set.
void Streamer::ReadLeastSquaresBand(Band& band, std::size_t selected) {
  const int width = set_.width(), rows = band.rows, channels = set_.channels();
  const auto pixels = static_cast<std::ptrdiff_t>(selected);
  Eigen::MatrixXf matrix = TakeSpareMatrix();
  matrix.resize(pixels * channels, set_.size());  // the spare's storage when the size is kept
  std::vector<std::size_t> indices;
  if (selected == static_cast<std::size_t>(width) * static_cast<std::size_t>(rows)) {
    std::vector<ImageView> columns;
    for (int i = 0; i < set_.size(); ++i) {
      columns.emplace_back(matrix.col(i).data(), width, rows, channels, width, pixels);
    }
    set_.ReadBandInto(columns);
  } else {
    indices = set_.SelectedPixelIndices(band.first, rows);
    set_.VisitBand(rows, [&](int i, ConstImageView decoded) {
      for (int c = 0; c < channels; ++c) {
        // VisitBand's bands are contiguous: pixel p of plane c is at c * plane_stride + p.
        const float* plane = decoded.data() + c * decoded.plane_stride();
        float* out = matrix.col(i).data() + c * pixels;
        for (std::ptrdiff_t k = 0; k < pixels; ++k) out[k] = plane[indices[k]];
      }
    });
  }
  if (set_.apply_intensities() && !set_.intensities().empty()) {
    for (int i = 0; i < set_.size(); ++i) {
      for (int c = 0; c < channels; ++c) {
        const float intensity = set_.intensities()[i][static_cast<std::size_t>(c)];
        // As PhotometricSet::ApplyIntensities divides (the same bits as the in-memory fit).
        for (float& v : matrix.col(i).segment(c * pixels, pixels)) v /= intensity;
      }
    }
  }
  if (options_.encoded_values) EncodeSrgb(matrix);
  if (indices.empty()) {
    band.observations.emplace(std::move(matrix), width, rows, channels);
  } else {
    band.observations.emplace(std::move(matrix), std::move(indices), width, rows, channels);
  }
}

Eigen::MatrixXf Streamer::TakeSpareMatrix() {
  const std::lock_guard lock(spare_mutex_);
  return std::move(spare_matrix_);
}

void Streamer::KeepSpareMatrix(Eigen::MatrixXf matrix) {
  const std::lock_guard lock(spare_mutex_);
  spare_matrix_ = std::move(matrix);
}

}  // namespace photomat::streaming_internal
