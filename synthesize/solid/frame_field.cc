#include "synthesize/solid/frame_field.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <numbers>

#include "core/enum_names.h"
#include "core/error.h"

namespace photomat {
namespace {

Eigen::Matrix3f RotationAboutZ(double degrees) {
  return Eigen::AngleAxisf(static_cast<float>(degrees * std::numbers::pi / 180.0),
                           Eigen::Vector3f::UnitZ())
      .toRotationMatrix();
}

// The right-handed frame [f1, z x f1, z] whose f1 is the unit tangent `tangent` in the xy plane
// (for counter-clockwise circle tangents, f2 = z x f1 points to the centre).
Eigen::Matrix3f PlanarFrame(const Eigen::Vector2f& tangent) {
  Eigen::Matrix3f frame;
  const Eigen::Vector3f f1(tangent.x(), tangent.y(), 0.0f);
  const Eigen::Vector3f f3 = Eigen::Vector3f::UnitZ();
  frame.col(0) = f1;
  frame.col(1) = f3.cross(f1);
  frame.col(2) = f3;
  return frame;
}

}  // namespace

FrameField::FrameField(ImageExtent size) : size_(size) {
  if (size.width <= 0 || size.height <= 0 || size.depth <= 0) {
    throw Error(fmt::format("invalid frame field size {}", ToString(size)));
  }
  frames_.assign(size.pixel_count(), Eigen::Matrix3f::Identity());
}

Eigen::Matrix3f Orthonormalise(const Eigen::Matrix3f& matrix) {
  if (matrix.norm() < 1e-6f) return Eigen::Matrix3f::Identity();
  const Eigen::JacobiSVD<Eigen::Matrix3f> svd(matrix, Eigen::ComputeFullU | Eigen::ComputeFullV);
  return svd.matrixU() * svd.matrixV().transpose();
}

FrameField FrameField::Downsampled() const {
  const ImageExtent half{(size_.width + 1) / 2, (size_.height + 1) / 2, (size_.depth + 1) / 2};
  FrameField result(half);
  for (int z = 0; z < half.depth; ++z) {
    for (int y = 0; y < half.height; ++y) {
      for (int x = 0; x < half.width; ++x) {
        Eigen::Matrix3f sum = Eigen::Matrix3f::Zero();
        for (int dz = 0; dz < 2; ++dz) {
          for (int dy = 0; dy < 2; ++dy) {
            for (int dx = 0; dx < 2; ++dx) {
              const int cx = std::min(2 * x + dx, size_.width - 1);
              const int cy = std::min(2 * y + dy, size_.height - 1);
              const int cz = std::min(2 * z + dz, size_.depth - 1);
              sum += at(cx, cy, cz);
            }
          }
        }
        result.at(x, y, z) = Orthonormalise(sum);
      }
    }
  }
  return result;
}

FrameField FrameField::Resampled(ImageExtent size) const {
  FrameField result(size);
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        const int sx =
            std::min(size_.width - 1, static_cast<int>((x + 0.5) * size_.width / size.width));
        const int sy =
            std::min(size_.height - 1, static_cast<int>((y + 0.5) * size_.height / size.height));
        const int sz =
            std::min(size_.depth - 1, static_cast<int>((z + 0.5) * size_.depth / size.depth));
        result.at(x, y, z) = at(sx, sy, sz);
      }
    }
  }
  return result;
}

namespace {

constexpr std::array<NamedValue<FieldKind>, 5> kFieldKindNames = {
    {{FieldKind::kCircular, "circular"},
     {FieldKind::kOval, "oval"},
     {FieldKind::kSlant, "slant"},
     {FieldKind::kZigzag, "zigzag"},
     {FieldKind::kSlant3d, "slant3d"}}};

}  // namespace

std::optional<FieldKind> ParseFieldKind(std::string_view text) {
  return FindValueNamed(text, kFieldKindNames);
}

std::string_view ToString(FieldKind kind) { return NameOf(kind, kFieldKindNames); }

FrameField ConstantFrameField(ImageExtent size, const Eigen::Matrix3f& rotation) {
  FrameField field(size);
  const Eigen::Matrix3f frame = Orthonormalise(rotation);
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) field.at(x, y, z) = frame;
    }
  }
  return field;
}

FrameField MakeFrameField(FieldKind kind, ImageExtent size, const FieldParameters& parameters) {
  if (kind == FieldKind::kSlant) {
    return ConstantFrameField(size, RotationAboutZ(parameters.angle_degrees));
  }
  if (kind == FieldKind::kSlant3d) {
    const Eigen::Vector3f axis = Eigen::Vector3f::Ones().normalized();
    return ConstantFrameField(
        size, Eigen::AngleAxisf(
                  static_cast<float>(parameters.angle_degrees * std::numbers::pi / 180.0), axis)
                  .toRotationMatrix());
  }
  if (parameters.band < 1 || !(parameters.ratio > 0)) {
    throw Error("field band must be positive and the oval ratio above 0");
  }
  FrameField field(size);
  const float cx = 0.5f * size.width, cy = 0.5f * size.height;
  const float a2 = static_cast<float>(parameters.ratio * parameters.ratio);
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        const float px = x + 0.5f - cx, py = y + 0.5f - cy;
        Eigen::Matrix3f frame = Eigen::Matrix3f::Identity();
        switch (kind) {
          case FieldKind::kCircular:
          case FieldKind::kOval: {
            // Ellipses x^2 / a^2 + y^2 / b^2 = c (b = 1): the gradient is (x / a^2, y), the
            // tangent its quarter turn counter-clockwise.
            const float scale = kind == FieldKind::kOval ? a2 : 1.0f;
            const Eigen::Vector2f gradient(px / scale, py);
            if (gradient.norm() > 0.5f / std::max(1.0f, scale)) {
              frame = PlanarFrame(Eigen::Vector2f(-gradient.y(), gradient.x()).normalized());
            }
            break;
          }
          case FieldKind::kZigzag: {
            const bool positive = (y / parameters.band) % 2 == 0;
            frame = RotationAboutZ(positive ? parameters.angle_degrees : -parameters.angle_degrees);
            break;
          }
          case FieldKind::kSlant:
          case FieldKind::kSlant3d:
            break;
        }
        field.at(x, y, z) = frame;
      }
    }
  }
  return field;
}

Image FrameFieldToVolume(const FrameField& field) {
  std::vector<std::string> names;
  for (const char* column : {"f1", "f2", "f3"}) {
    for (const char* axis : {"X", "Y", "Z"}) names.push_back(fmt::format("{}.{}", column, axis));
  }
  Image volume(field.size(), names);
  for (int z = 0; z < field.size().depth; ++z) {
    for (int y = 0; y < field.size().height; ++y) {
      for (int x = 0; x < field.size().width; ++x) {
        const Eigen::Matrix3f& frame = field.at(x, y, z);
        for (int column = 0; column < 3; ++column) {
          for (int row = 0; row < 3; ++row)
            volume.at(x, y, z, 3 * column + row) = frame(row, column);
        }
      }
    }
  }
  return volume;
}

FrameField FrameFieldFromVolume(const Image& volume) {
  if (volume.channels() != 9 && volume.channels() != 6) {
    throw Error(
        fmt::format("a frame field volume has 9 channels (f1, f2, f3) or 6 (f1, f2), not {}",
                    volume.channels()));
  }
  FrameField field(volume.extent());
  for (int z = 0; z < volume.depth(); ++z) {
    for (int y = 0; y < volume.height(); ++y) {
      for (int x = 0; x < volume.width(); ++x) {
        Eigen::Matrix3f frame;
        for (int column = 0; column < 2; ++column) {
          for (int row = 0; row < 3; ++row)
            frame(row, column) = volume.at(x, y, z, 3 * column + row);
        }
        if (volume.channels() == 9) {
          for (int row = 0; row < 3; ++row) frame(row, 2) = volume.at(x, y, z, 6 + row);
        } else {
          frame.col(2) = frame.col(0).cross(frame.col(1));
        }
        field.at(x, y, z) = Orthonormalise(frame);
      }
    }
  }
  return field;
}

}  // namespace photomat
