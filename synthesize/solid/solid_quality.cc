#include "synthesize/solid/solid_quality.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "core/error.h"
#include "core/fft.h"
#include "core/wrap.h"
#include "synthesize/solid/similarity_set.h"
#include "synthesize/volume/voxel_hash.h"

namespace photomat {
namespace {}  // namespace

double NeighbourhoodMatchError(const Image& solid, const Image& exemplar,
                               const AppearanceSpace& appearance, int samples, std::uint64_t seed) {
  if (solid.channels() != exemplar.channels()) {
    throw Error(fmt::format("a solid of {} channels cannot match an exemplar of {}",
                            solid.channels(), exemplar.channels()));
  }
  const AppearanceIndex index(appearance);
  const std::size_t voxels = solid.pixel_count();
  const bool all = static_cast<std::size_t>(samples) >= voxels;
  const std::size_t count = all ? voxels : static_cast<std::size_t>(samples);
  std::vector<double> errors(count);
  const int half = appearance.neighbourhood / 2;
  const ImageExtent& size = solid.extent();
  const ImageExtent& exemplar_size = exemplar.extent();
  tbb::parallel_for(std::size_t{0}, count, [&](std::size_t i) {
    const std::size_t p = all ? i : MixBits(seed * 0x9e3779b97f4a7c15ULL + i) % voxels;
    const int x = static_cast<int>(p % size.width),
              y = static_cast<int>((p / size.width) % size.height),
              z = static_cast<int>(p / (static_cast<std::size_t>(size.width) * size.height));
    std::vector<float> query(static_cast<std::size_t>(appearance.dimensions));
    appearance.Project(solid, x, y, z, query);
    const auto u = appearance.domain.Coordinates(index.Nearest(query));
    double sum = 0;
    for (int dz = -half; dz <= half; ++dz) {
      for (int dy = -half; dy <= half; ++dy) {
        for (int dx = -half; dx <= half; ++dx) {
          const auto a = solid.pixel(Wrap(x + dx, size.width), Wrap(y + dy, size.height),
                                     Wrap(z + dz, size.depth));
          const auto b = exemplar.pixel(Wrap(u[0] + dx, exemplar_size.width),
                                        Wrap(u[1] + dy, exemplar_size.height),
                                        Wrap(u[2] + dz, exemplar_size.depth));
          for (std::size_t c = 0; c < a.size(); ++c) sum += std::pow(a[c] - b[c], 2);
        }
      }
    }
    const int side = 2 * half + 1;
    errors[i] = sum / (static_cast<double>(side) * side * side * solid.channels());
  });
  double total = 0;
  for (double e : errors) total += e;
  return total / static_cast<double>(count);
}

double HistogramDistance(const Image& solid, const Image& reference, int bins) {
  if (solid.channels() != reference.channels() || bins < 1) {
    throw Error("histogram distance needs the same channels and at least one bin");
  }
  double total = 0;
  for (int c = 0; c < reference.channels(); ++c) {
    float low = std::numeric_limits<float>::max(), high = std::numeric_limits<float>::lowest();
    for (std::size_t i = 0; i < reference.pixel_count(); ++i) {
      low = std::min(low, reference.pixel(i)[static_cast<std::size_t>(c)]);
      high = std::max(high, reference.pixel(i)[static_cast<std::size_t>(c)]);
    }
    if (!(high > low)) high = low + 1e-6f;
    const auto histogram = [&](const Image& volume) {
      std::vector<double> h(static_cast<std::size_t>(bins), 0.0);
      for (std::size_t i = 0; i < volume.pixel_count(); ++i) {
        const float t = (volume.pixel(i)[static_cast<std::size_t>(c)] - low) / (high - low);
        h[static_cast<std::size_t>(std::clamp(static_cast<int>(t * bins), 0, bins - 1))] += 1.0;
      }
      for (double& v : h) v /= static_cast<double>(volume.pixel_count());
      return h;
    };
    const std::vector<double> a = histogram(solid), b = histogram(reference);
    for (int k = 0; k < bins; ++k)
      total += std::abs(a[static_cast<std::size_t>(k)] - b[static_cast<std::size_t>(k)]);
  }
  return total / reference.channels();
}

double EarthMoverDistance(const Image& solid, const Image& reference) {
  if (solid.channels() != reference.channels() || solid.pixel_count() == 0 ||
      reference.pixel_count() == 0) {
    throw Error("earth mover's distance needs the same channels and non-empty volumes");
  }
  const auto sorted_channel = [](const Image& volume, std::size_t c) {
    std::vector<float> values(volume.pixel_count());
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = volume.pixel(i)[c];
    std::sort(values.begin(), values.end());
    return values;
  };
  double total = 0;
  for (std::size_t c = 0; c < static_cast<std::size_t>(reference.channels()); ++c) {
    const std::vector<float> a = sorted_channel(solid, c), b = sorted_channel(reference, c);
    // Walk the merged values; between two consecutive ones both distribution functions are flat.
    const double na = static_cast<double>(a.size()), nb = static_cast<double>(b.size());
    std::size_t i = 0, j = 0;
    double area = 0, previous = std::min(a.front(), b.front());
    while (i < a.size() || j < b.size()) {
      const double next = j == b.size() || (i < a.size() && a[i] <= b[j]) ? a[i] : b[j];
      area +=
          std::abs(static_cast<double>(i) / na - static_cast<double>(j) / nb) * (next - previous);
      previous = next;
      while (i < a.size() && a[i] == next) ++i;
      while (j < b.size() && b[j] == next) ++j;
    }
    const double range = static_cast<double>(b.back()) - b.front();
    total += range > 0 ? area / range : area;
  }
  return total / reference.channels();
}

std::vector<double> RadialPowerSpectrum(const Image& volume, int bins) {
  const ImageExtent& size = volume.extent();
  const RealFft3d<float> fft(size.width, size.height, size.depth);
  std::vector<double> power(static_cast<std::size_t>(bins), 0.0), weight(power.size(), 0.0);
  std::vector<float> channel(volume.pixel_count());
  std::vector<std::complex<float>> spectrum(fft.spectrum_size());
  const double voxels = static_cast<double>(volume.pixel_count());
  for (int c = 0; c < volume.channels(); ++c) {
    double mean = 0;
    for (std::size_t i = 0; i < channel.size(); ++i)
      mean += volume.pixel(i)[static_cast<std::size_t>(c)];
    mean /= voxels;
    for (std::size_t i = 0; i < channel.size(); ++i) {
      channel[i] = static_cast<float>(volume.pixel(i)[static_cast<std::size_t>(c)] - mean);
    }
    fft.Forward(channel, spectrum);
    const int half_x = fft.spectrum_x();
    for (int fz = 0; fz < size.depth; ++fz) {
      const double wz =
          static_cast<double>(fz <= size.depth / 2 ? fz : fz - size.depth) / size.depth;
      for (int fy = 0; fy < size.height; ++fy) {
        const double wy =
            static_cast<double>(fy <= size.height / 2 ? fy : fy - size.height) / size.height;
        for (int fx = 0; fx < half_x; ++fx) {
          const double wx = static_cast<double>(fx) / size.width;
          const double radius = std::sqrt(wx * wx + wy * wy + wz * wz);
          if (radius == 0.0 || radius > 0.5) continue;
          const int bin = std::min(bins - 1, static_cast<int>(radius / 0.5 * bins));
          const double pair = (fx == 0 || 2 * fx == size.width) ? 1.0 : 2.0;
          const std::size_t k = (static_cast<std::size_t>(fz) * size.height + fy) * half_x + fx;
          power[static_cast<std::size_t>(bin)] += pair * std::norm(spectrum[k]) / voxels;
          weight[static_cast<std::size_t>(bin)] += pair;
        }
      }
    }
  }
  for (std::size_t b = 0; b < power.size(); ++b) {
    power[b] = weight[b] > 0 ? power[b] / weight[b] : std::numeric_limits<double>::quiet_NaN();
  }
  return power;
}

double LogSpectralDistance(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size() || a.empty()) throw Error("spectra of different lengths");
  double sum = 0;
  int used = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i]) || std::isnan(b[i])) continue;
    const double ratio = 10.0 * std::log10(std::max(a[i], 1e-20) / std::max(b[i], 1e-20));
    sum += ratio * ratio;
    ++used;
  }
  if (used == 0) throw Error("the spectra share no frequency ring");
  return std::sqrt(sum / used);
}

Eigen::Matrix3d StructureTensor(const Image& volume) {
  const std::vector<float> luminance = ChannelMean(volume);
  const ImageExtent& size = volume.extent();
  const auto at = [&](int x, int y, int z) {
    return static_cast<double>(
        luminance[volume.Index(Wrap(x, size.width), Wrap(y, size.height), Wrap(z, size.depth))]);
  };
  Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero();
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        const Eigen::Vector3d g(0.5 * (at(x + 1, y, z) - at(x - 1, y, z)),
                                0.5 * (at(x, y + 1, z) - at(x, y - 1, z)),
                                0.5 * (at(x, y, z + 1) - at(x, y, z - 1)));
        tensor += g * g.transpose();
      }
    }
  }
  return tensor;
}

Eigen::Vector3d PrincipalDirection(const Eigen::Matrix3d& tensor) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(tensor);
  return solver.eigenvectors().col(2).normalized();
}

double CoherentFraction(const Image& coordinates, const ExemplarDomain& domain) {
  const ImageExtent& size = coordinates.extent();
  const auto extent = domain.extent();
  std::size_t coherent = 0, pairs = 0;
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        const int p[3] = {x, y, z};
        for (int axis = 0; axis < 3; ++axis) {
          int q[3] = {x, y, z};
          if (++q[axis] >= (axis == 0 ? size.width : axis == 1 ? size.height : size.depth))
            continue;
          bool same = true;
          for (int a = 0; a < 3; ++a) {
            const int expected = a == axis ? 1 : 0;
            const int diff = static_cast<int>(coordinates.at(q[0], q[1], q[2], a) -
                                              coordinates.at(p[0], p[1], p[2], a));
            same &= Wrap(diff - expected, extent[static_cast<std::size_t>(a)]) == 0;
          }
          coherent += same;
          ++pairs;
        }
      }
    }
  }
  return pairs ? static_cast<double>(coherent) / static_cast<double>(pairs) : 0.0;
}

PatchStatistics CoherentPatches(const Image& coordinates, const ExemplarDomain& domain) {
  const ImageExtent& size = coordinates.extent();
  const auto extent = domain.extent();
  // Union-find over voxels, joined along coherent pairs.
  std::vector<std::size_t> parent(coordinates.pixel_count());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto find = [&parent](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int z = 0; z < size.depth; ++z) {
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        for (int axis = 0; axis < 3; ++axis) {
          int q[3] = {x, y, z};
          if (++q[axis] >= (axis == 0 ? size.width : axis == 1 ? size.height : size.depth))
            continue;
          bool same = true;
          for (int a = 0; a < 3; ++a) {
            const int diff =
                static_cast<int>(coordinates.at(q[0], q[1], q[2], a) - coordinates.at(x, y, z, a));
            same &= Wrap(diff - (a == axis ? 1 : 0), extent[static_cast<std::size_t>(a)]) == 0;
          }
          if (same)
            parent[find(coordinates.Index(q[0], q[1], q[2]))] = find(coordinates.Index(x, y, z));
        }
      }
    }
  }
  std::vector<std::size_t> count(parent.size(), 0);
  for (std::size_t i = 0; i < parent.size(); ++i) ++count[find(i)];
  PatchStatistics statistics;
  for (std::size_t c : count) {
    if (c == 0) continue;
    ++statistics.patches;
    statistics.largest = std::max(statistics.largest, c);
    statistics.voxel_weighted += static_cast<double>(c) * static_cast<double>(c);
  }
  statistics.voxel_weighted /= static_cast<double>(parent.size());
  statistics.mean_size =
      statistics.patches ? static_cast<double>(parent.size()) / statistics.patches : 0.0;
  return statistics;
}

}  // namespace photomat
