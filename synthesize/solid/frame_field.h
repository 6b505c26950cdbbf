#pragma once

#include <Eigen/Core>
#include <optional>
#include <string_view>
#include <vector>

#include "synthesize/volume/volume.h"

namespace photomat {

// A field of local frames over the output of exemplar-based solid synthesis (Su 2008, chapter 4).
// The frame F(p) = [f1 f2 f3] at output voxel p holds, as columns, the output-space directions the
// exemplar's x, y and z axes should follow there. Synthesis uses A = F^-1 = F^T (frames are
// orthonormal): A maps an output offset to an exemplar offset, the role of the Jacobian in
// Lefebvre and Hoppe 2006. (The thesis leaves the direction ambiguous; this is the convention its
// constant-rotation test fixes: a field equal to R everywhere turns the texture by R.)
class FrameField {
 public:
  FrameField() = default;
  // Identity frames.
  explicit FrameField(ImageExtent size);

  const ImageExtent& size() const { return size_; }
  const Eigen::Matrix3f& at(int x, int y, int z) const { return frames_[Index(x, y, z)]; }
  Eigen::Matrix3f& at(int x, int y, int z) { return frames_[Index(x, y, z)]; }

  // Half the resolution (rounded up): each frame the orthonormalised mean of its up to 8 children.
  FrameField Downsampled() const;
  // Nearest-voxel resampling to `size` (coordinates scaled by the size ratio).
  FrameField Resampled(ImageExtent size) const;

 private:
  std::size_t Index(int x, int y, int z) const {
    return (static_cast<std::size_t>(z) * size_.height + y) * size_.width + x;
  }
  ImageExtent size_;
  std::vector<Eigen::Matrix3f> frames_;
};

// The nearest orthonormal matrix (polar decomposition through the SVD); the identity for a
// matrix too close to zero to have a direction.
Eigen::Matrix3f Orthonormalise(const Eigen::Matrix3f& matrix);

// The controls of the thesis's experiments (spec section 5.5; the thesis gives no formulas, so
// these are parametric reconstructions).
enum class FieldKind {
  kCircular,  // f1 tangent to circles about the z axis through the centre, f2 inward, f3 = z
  kOval,      // the same about ellipses with semi-axes ratio a:b (x:y)
  kSlant,     // a constant rotation by `angle` about z
  kZigzag,    // the slant alternating between +angle and -angle in bands along y
  kSlant3d,   // a constant rotation by `angle` about the axis (1, 1, 1)
};
std::optional<FieldKind> ParseFieldKind(std::string_view text);
std::string_view ToString(FieldKind kind);

struct FieldParameters {
  double angle_degrees = 30.0;
  double ratio = 2.0;  // oval: a / b
  int band = 16;       // zigzag band width in voxels
};

FrameField MakeFrameField(FieldKind kind, ImageExtent size, const FieldParameters& parameters);
// R everywhere.
FrameField ConstantFrameField(ImageExtent size, const Eigen::Matrix3f& rotation);

// A field as a volume of 9 channels f1.X f1.Y f1.Z f2.X ... f3.Z (so it can be saved and edited
// as any volume), and back; a 6-channel volume (f1, f2) takes f3 = f1 x f2. Frames are
// orthonormalised on reading. Throws Error for other channel counts.
Image FrameFieldToVolume(const FrameField& field);
FrameField FrameFieldFromVolume(const Image& volume);

}  // namespace photomat
