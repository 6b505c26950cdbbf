#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/progress.h"
#include "synthesize/solid/appearance_space.h"
#include "synthesize/volume/volume.h"

namespace photomat {

// The similarity set (Su 2008 section 3.2, a k-coherence search after Tong et al. 2002): for every
// valid exemplar voxel u, k voxels that look like it, C_1(u) = u and C_j+1(u) the voxel nearest
// to u in appearance space outside the exclusion boxes (Chebyshev radius exclusion / 2, toroidal
// in periodic mode) of all of C_1 .. C_j, so the candidates come from different places.
struct SimilarityOptions {
  int candidates = 3;  // k
  int exclusion = 7;   // odd side of the exclusion box
};

struct SimilaritySet {
  int k = 0;
  // voxel_count x k linear exemplar indices; -1 outside the valid region. When fewer than k
  // voxels lie outside the boxes (tiny exemplars), the last one found repeats.
  std::vector<std::int32_t> indices;

  std::span<const std::int32_t> at(std::size_t voxel) const {
    return {indices.data() + voxel * static_cast<std::size_t>(k), static_cast<std::size_t>(k)};
  }
};

// Exact search in a k-d tree (nanoflann) whose result set skips excluded voxels: the answer is
// the brute-force one, ties going to the lower index.
SimilaritySet BuildSimilaritySet(const AppearanceSpace& appearance,
                                 const SimilarityOptions& options, Progress* progress = nullptr);
// O(n^2) reference, for tests.
SimilaritySet BuildSimilaritySetBruteForce(const AppearanceSpace& appearance,
                                           const SimilarityOptions& options);

// Exact nearest valid exemplar voxel to any appearance vector (a k-d tree over the valid voxels).
class AppearanceIndex {
 public:
  explicit AppearanceIndex(const AppearanceSpace& appearance);
  ~AppearanceIndex();
  AppearanceIndex(const AppearanceIndex&) = delete;
  AppearanceIndex& operator=(const AppearanceIndex&) = delete;
  // Linear exemplar index of the nearest voxel (ties: the lower index).
  std::size_t Nearest(std::span<const float> query) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

// Chebyshev distance between two exemplar voxels (toroidal over the domain when periodic).
int ChebyshevDistance(const ExemplarDomain& domain, std::size_t a, std::size_t b);

// One coarser level of a Gaussian stack: the appearance space of the exemplar blurred by
// GaussianStackSigma(spacing), with neighbourhood samples `spacing` apart, and its similarity set.
struct PreparedLevel {
  AppearanceSpace appearance;  // its `spacing` is the level's
  SimilaritySet similarity;
};

// Appearance space and similarity set of one exemplar: what synthesis needs, reusable for any
// output size, seed or field.
struct PreparedExemplar {
  AppearanceSpace appearance;  // of the exemplar itself (spacing 1)
  SimilaritySet similarity;
  std::vector<PreparedLevel> stack;  // spacing 2, 4, ...; empty for a single-resolution exemplar
  bool from_cache = false;
  std::filesystem::path cache_file;  // empty without a cache folder

  // The level synthesis at `spacing` matches against: the stack level of that spacing, or the
  // exemplar itself when there is none.
  const AppearanceSpace& AppearanceAt(int spacing) const;
  const SimilaritySet& SimilarityAt(int spacing) const;

 private:
  const PreparedLevel* StackLevel(int spacing) const;  // nullptr when there is none
};

// The cache key: a hash (XXH3, 64 bits) of the exemplar's size, channel names and values and of
// every option, with a format version; two exemplars or settings differing in any byte differ.
std::string SimilarityCacheKey(const Image& exemplar, const AppearanceOptions& appearance,
                               const SimilarityOptions& similarity);

// Computes both (and, with appearance.gaussian_stack, those of the coarser stack levels), or loads
// them from `cache_folder`/solid-<key>.bin when present (a damaged cache file is reported on the
// log and recomputed), and stores new results there atomically.
PreparedExemplar PrepareExemplar(const Image& exemplar, const AppearanceOptions& appearance,
                                 const SimilarityOptions& similarity,
                                 const std::optional<std::filesystem::path>& cache_folder,
                                 Progress* progress = nullptr);

// The cache file format, exposed for tests. Load throws Error naming the file on any fault.
void SavePreparedExemplar(const std::filesystem::path& path, const std::string& key,
                          const PreparedExemplar& prepared);
PreparedExemplar LoadPreparedExemplar(const std::filesystem::path& path, const std::string& key);

}  // namespace photomat
