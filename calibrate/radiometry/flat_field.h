#pragma once

#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "calibrate/radiometry/near_light.h"
#include "core/image.h"
#include "core/image_band_io.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"
#include "core/progress.h"

namespace photomat {

class StreamedSet;  // capture/io/streamed_set.h

// Per-light gain maps that turn a capture with uneven lighting (near lamps with fall-off,
// vignetting, lamps of unequal brightness or colour) into what equal distant lights would give.
//
// Gain of light i at pixel p, channel c: what a flat matte target of uniform albedo shows there,
// divided by what a distant light of unit intensity from the nominal direction l_i would show
// (l_i.z). Dividing the sample's image i by it removes the light's fall-off, its brightness and
// colour. The gains are normalised to a mean of 1 per channel over all lights and pixels: the
// target's own colour and absolute brightness drop out, relative differences between lights stay.
// (Exact for a flat sample; for relief the remaining error is the change of light direction over
// the sample, which a flat-field cannot correct.)

enum class FlatFieldModel {
  // Gaussian-smoothed target images (normalised convolution inside the target's mask): keeps
  // vignetting and lamp patterns, for clean targets.
  kSmoothed,
  // exp of a least-squares polynomial in x and y of low degree fitted to the log of the target,
  // per light and channel (fall-off and vignetting are multiplicative and span a large range):
  // for noisy or textured targets, and to extend the gains beyond the target's mask.
  kPolynomial,
};
std::string_view ToString(FlatFieldModel model);
std::optional<FlatFieldModel> ParseFlatFieldModel(std::string_view name);

struct FlatFieldOptions {
  FlatFieldModel model = FlatFieldModel::kPolynomial;
  double smoothing_sigma = 3.0;  // pixels, kSmoothed
  int polynomial_degree = 4;     // kPolynomial (and kSmoothed outside the target's mask)
  Progress* progress = nullptr;
};

class FlatField {
 public:
  FlatField(std::vector<Image> gains, std::vector<LightDirection> lights);

  int size() const { return static_cast<int>(gains_.size()); }
  const Image& gain(int i) const { return gains_[i]; }
  const std::vector<Image>& gains() const { return gains_; }
  // The nominal light of each gain map (for checking a sample set against it).
  const std::vector<LightDirection>& lights() const { return lights_; }
  // Rows [first, first + count) of every gain map: the flat-field of a band of a capture.
  FlatField Rows(int first, int count) const;

 private:
  std::vector<Image> gains_;
  std::vector<LightDirection> lights_;
};

// From captures of a flat uniform matte target under the sample's lights (its mask, if any,
// selects the target). Throws Error naming the set's source for a target that is dark
// somewhere under some light (non-positive gains) or a light at or below the horizon.
FlatField EstimateFlatField(const PhotometricSet& target, const FlatFieldOptions& options = {});

// `photomat calibrate flatfield` of a target of any size (README "Calibration"): what
// SaveFlatField(folder, EstimateFlatField(whole target)) writes, the same gain maps, from a target
// read one image per thread at a time (StreamedSet::VisitBand of every row; each light's gain
// comes from its own image). Two passes over the images: (1) each light's gain, for the
// per-light sums that normalise them all (and the faults, before anything is written); (2) the
// gains made again, normalised and written. IMPLEMENTER CHOICE: a gain is computed twice rather
// than kept between the passes, in memory (as large as the target as float) or in scratch files
// (as large again on disk); its cost is about the image's decoding. The files are written into a
// scratch folder beside `folder` (its free space checked for them first) and moved in when all
// are written, flatfield.json last: a fault leaves no gain map and no description. Memory: an
// image and its gain per thread.
void EstimateFlatFieldStreamed(StreamedSet& target, const std::filesystem::path& folder,
                               const FlatFieldOptions& options = {});

// The gains near lights at known positions would give on a flat target (no target needed):
// intensity * P.z / |P - p|^3 / l.z, for `channels` channels, normalised as every flat-field.
// Computed band by band (a streamed `calibrate apply`): the normalisation over every light and
// pixel is summed once, from the lamps alone, so the gains of any band equal those rows of the
// whole field bit for bit.
class NearLightGains {
 public:
  // Throws Error when there are no lights.
  NearLightGains(std::vector<NearLight> lights, int width, int height, int channels);
  const std::vector<NearLight>& lights() const { return lights_; }
  // The gains of rows [first, first + count).
  FlatField Rows(int first, int count) const;

 private:
  // Light i's gain at pixel (x, y) before the normalisation.
  float Unnormalised(std::size_t i, int x, int y) const;

  std::vector<NearLight> lights_;
  std::vector<double> nominal_z_;
  int width_ = 0, height_ = 0, channels_ = 0;
  float scale_ = 1.0f;
};

// The whole field: NearLightGains(...).Rows(0, height).
FlatField FlatFieldFromNearLights(const std::vector<NearLight>& lights, int width, int height,
                                  int channels);

// Divides each image of `set` by its light's gains. Throws Error naming the set's source when the
// counts or sizes differ, or a light differs by more than `max_light_difference_degrees` from the
// flat-field's (the flat-field belongs to another light set).
PhotometricSet ApplyFlatField(const PhotometricSet& set, const FlatField& flat_field,
                              double max_light_difference_degrees = 2.0);

// A folder with flatfield.json and one half-float EXR per light (gain_000.exr, ...), written
// atomically file by file.
void SaveFlatField(const std::filesystem::path& folder, const FlatField& flat_field);

// A flat-field folder (SaveFlatField's) read band by band, in row order: what a streamed
// `calibrate apply` holds instead of the whole field, whose gain maps (one per light, each of the
// capture's size) are as large as the capture itself. Every gain map is opened once (an
// ImageBandReader each, core/image_band_io.h); ReadNext decodes the next rows of every one, in
// parallel. The rows equal LoadFlatField's, which is this reader with one band.
class FlatFieldBandReader {
 public:
  // Reads the folder's flatfield.json (or `path` itself when it is that file) and opens its gain
  // maps. Throws Error naming the file at fault: a malformed description, a gain map missing or
  // unreadable, gain maps of different sizes or channel counts.
  explicit FlatFieldBandReader(const std::filesystem::path& path);

  int size() const { return static_cast<int>(readers_.size()); }
  int width() const { return readers_.front().width(); }
  int height() const { return readers_.front().height(); }
  int channels() const { return readers_.front().channels(); }
  const std::vector<LightDirection>& lights() const { return lights_; }
  // The first row the next ReadNext reads.
  int next_row() const { return readers_.front().next_row(); }
  // The next `rows` rows of every gain map. Throws Error naming the gain map at fault (rows past
  // its end, a file truncated or corrupt there).
  FlatField ReadNext(int rows);

 private:
  std::vector<ImageBandReader> readers_;
  std::vector<LightDirection> lights_;
};

// Reads a folder (or its flatfield.json) whole. Throws Error naming the file at fault.
FlatField LoadFlatField(const std::filesystem::path& path);

}  // namespace photomat
