#include "synthesize/carving/solid_carving.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/wrap.h"
#include "synthesize/volume/volume_io.h"

namespace photomat {
namespace {

// Lower and upper voxel of a 1D linear interpolation at continuous coordinate `at` (voxel
// centres at i + 1/2), and the weight of the upper one.
struct Taps {
  int low = 0;
  int high = 0;
  float weight = 0.0f;
};

Taps AxisTaps(double at, int length, bool tileable) {
  const double t = at - 0.5;
  const double base = std::floor(t);
  Taps taps;
  taps.weight = static_cast<float>(t - base);
  const int low = static_cast<int>(base);
  if (tileable) {
    taps.low = Wrap(low, length);
    taps.high = (taps.low + 1) % length;
  } else {
    taps.low = std::clamp(low, 0, length - 1);
    taps.high = std::clamp(low + 1, 0, length - 1);
  }
  return taps;
}

}  // namespace

CarveMapping PlaceMesh(const TriangleMesh& mesh, const ImageExtent& volume,
                       const CarvePlacement& placement) {
  if (!(placement.periods > 0.0) || !std::isfinite(placement.periods)) {
    throw Error(fmt::format("the texture periods across the mesh must be positive (got {})",
                            placement.periods));
  }
  if (!placement.tileable && placement.periods > 1.0) {
    throw Error(
        fmt::format("{} periods across the mesh repeat the volume, which needs a tileable one",
                    placement.periods));
  }
  const BoundingBox box = ComputeBoundingBox(mesh);
  const double longest = (box.max - box.min).maxCoeff();
  const int smallest = std::min({volume.width, volume.height, volume.depth});
  CarveMapping mapping;
  mapping.scale = longest > 0.0 ? placement.periods * smallest / longest : 1.0;
  mapping.mesh_centre = box.Centre();
  mapping.volume_centre = 0.5 * Eigen::Vector3d(volume.width, volume.height, volume.depth);
  return mapping;
}

void SampleTrilinear(const Image& volume, const Eigen::Vector3d& at, bool tileable,
                     std::span<float> out) {
  const ImageExtent& size = volume.extent();
  const Taps x = AxisTaps(at.x(), size.width, tileable);
  const Taps y = AxisTaps(at.y(), size.height, tileable);
  const Taps z = AxisTaps(at.z(), size.depth, tileable);
  std::fill(out.begin(), out.end(), 0.0f);
  for (int corner = 0; corner < 8; ++corner) {
    const bool ux = corner & 1, uy = corner & 2, uz = corner & 4;
    const float weight = (ux ? x.weight : 1.0f - x.weight) * (uy ? y.weight : 1.0f - y.weight) *
                         (uz ? z.weight : 1.0f - z.weight);
    if (weight == 0.0f) continue;
    const auto voxel = volume.pixel(ux ? x.high : x.low, uy ? y.high : y.low, uz ? z.high : z.low);
    for (std::size_t c = 0; c < out.size(); ++c) out[c] += weight * voxel[c];
  }
}

CarvedMesh CarveMesh(const TriangleMesh& mesh, const Image& volume, const CarveOptions& options,
                     Progress* progress) {
  if (volume.empty()) throw Error("cannot carve out of an empty volume");
  ValidateMesh(mesh, "the mesh to carve");
  NullProgress null_progress;
  Progress& report = OrNull(progress, null_progress);
  CarvedMesh carved;
  carved.mapping = PlaceMesh(mesh, volume.extent(), options.placement);
  // Subdivision halves the mean edge at each level.
  const double mean_edge = MeanEdgeLength(mesh) * carved.mapping.scale;
  std::size_t triangles = static_cast<std::size_t>(mesh.triangle_count());
  if (options.max_mean_edge_voxels > 0.0) {
    double edge = mean_edge;
    while (edge > options.max_mean_edge_voxels &&
           4 * triangles <= static_cast<std::size_t>(options.max_triangles)) {
      edge *= 0.5;
      triangles *= 4;
      ++carved.subdivision_levels;
    }
  }
  carved.mesh = SubdivideMidpoints(mesh, carved.subdivision_levels);
  carved.channels = volume.channels();
  const std::size_t channels = static_cast<std::size_t>(volume.channels());
  const std::size_t vertices = static_cast<std::size_t>(carved.mesh.vertex_count());
  carved.values.assign(vertices * channels, 0.0f);
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (vertices + kChunk - 1) / kChunk;
  report.Start("carving", chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    for (std::size_t v = chunk * kChunk; v < std::min(vertices, (chunk + 1) * kChunk); ++v) {
      SampleTrilinear(volume, carved.mapping.ToVolume(carved.mesh.positions[v]),
                      options.placement.tileable,
                      std::span<float>(carved.values.data() + v * channels, channels));
    }
    report.Advance();
  });
  report.Finish();
  return carved;
}

std::vector<Eigen::Vector3f> CarvedColours(const CarvedMesh& carved, const Image& volume,
                                           bool normalise) {
  if (carved.channels != volume.channels()) {
    throw Error(fmt::format("the carved mesh has {} channels, the volume {}", carved.channels,
                            volume.channels()));
  }
  const std::vector<int> shown = DisplayChannels(volume);
  const int vertices = carved.mesh.vertex_count();
  float low = 0.0f, high = 1.0f;
  if (normalise) {
    low = std::numeric_limits<float>::max();
    high = std::numeric_limits<float>::lowest();
    for (int v = 0; v < vertices; ++v) {
      for (int c : shown) {
        low = std::min(low, carved.at(v)[static_cast<std::size_t>(c)]);
        high = std::max(high, carved.at(v)[static_cast<std::size_t>(c)]);
      }
    }
    if (!(high > low)) high = low + 1.0f;
  }
  std::vector<Eigen::Vector3f> colours(static_cast<std::size_t>(vertices));
  for (int v = 0; v < vertices; ++v) {
    Eigen::Vector3f colour;
    for (int k = 0; k < 3; ++k) {
      const int c = shown[std::min<std::size_t>(static_cast<std::size_t>(k), shown.size() - 1)];
      colour[k] =
          std::clamp((carved.at(v)[static_cast<std::size_t>(c)] - low) / (high - low), 0.0f, 1.0f);
    }
    colours[static_cast<std::size_t>(v)] = colour;
  }
  return colours;
}

}  // namespace photomat
