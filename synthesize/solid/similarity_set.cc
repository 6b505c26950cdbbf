#include "synthesize/solid/similarity_set.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <nanoflann.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "synthesize/volume/volume_filter.h"

namespace photomat {
namespace {

// --- k-d tree over the appearance vectors of the valid voxels ---

struct AppearancePoints {
  const AppearanceSpace* space;
  const std::vector<std::size_t>* valid;

  std::size_t kdtree_get_point_count() const { return valid->size(); }
  float kdtree_get_pt(std::size_t point, std::size_t dimension) const {
    return space->values[(*valid)[point] * static_cast<std::size_t>(space->dimensions) + dimension];
  }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using AppearanceTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, AppearancePoints, float, std::size_t>, AppearancePoints, -1,
    std::size_t>;

// Squared distance, summed in the same order as nanoflann's L2_Simple_Adaptor so that the tree
// and brute force agree to the bit.
float SquaredDistance(std::span<const float> a, std::span<const float> b) {
  float result = 0.0f;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const float diff = a[i] - b[i];
    result += diff * diff;
  }
  return result;
}

// nanoflann result set keeping the nearest point outside the exclusion boxes of `centres`; ties go
// to the lower voxel index (points as close as the best so far are still offered to it).
class NearestOutsideBoxes {
 public:
  NearestOutsideBoxes(const ExemplarDomain& domain, const std::vector<std::size_t>& valid,
                      std::span<const std::size_t> centres, int radius)
      : domain_(domain), valid_(valid), centres_(centres), radius_(radius) {}

  std::size_t size() const { return found_ ? 1 : 0; }
  bool full() const { return true; }
  // Offers a voxel before the search (its distance computed as the tree computes it): a close one
  // lets the tree prune from the start. The answer stays the exact one, ties included.
  void Seed(float distance, std::size_t voxel) {
    for (std::size_t centre : centres_) {
      if (ChebyshevDistance(domain_, voxel, centre) <= radius_) return;
    }
    best_ = distance;
    best_voxel_ = voxel;
    found_ = true;
  }
  bool addPoint(float distance, std::size_t point) {
    const std::size_t voxel = valid_[point];
    if (distance > best_ || (distance == best_ && found_ && voxel > best_voxel_)) return true;
    for (std::size_t centre : centres_) {
      if (ChebyshevDistance(domain_, voxel, centre) <= radius_) return true;
    }
    best_ = distance;
    best_voxel_ = voxel;
    found_ = true;
    return true;
  }
  float worstDist() const {
    return found_ ? std::nextafter(best_, std::numeric_limits<float>::infinity())
                  : std::numeric_limits<float>::infinity();
  }
  bool found() const { return found_; }
  std::size_t voxel() const { return best_voxel_; }

 private:
  const ExemplarDomain& domain_;
  const std::vector<std::size_t>& valid_;
  std::span<const std::size_t> centres_;
  int radius_;
  float best_ = std::numeric_limits<float>::infinity();
  std::size_t best_voxel_ = 0;
  bool found_ = false;
};

void CheckOptions(const SimilarityOptions& options) {
  if (options.candidates < 1 || options.exclusion < 1 || options.exclusion % 2 == 0) {
    throw Error(fmt::format("similarity set needs k >= 1 and an odd exclusion box (got k = {}, {})",
                            options.candidates, options.exclusion));
  }
}

// Fills the k candidates of `voxel` with `nearest(centres)` for j = 2..k.
template <typename Nearest>
void FillCandidates(std::size_t voxel, int k, std::int32_t* out, Nearest nearest) {
  std::vector<std::size_t> centres{voxel};
  out[0] = static_cast<std::int32_t>(voxel);
  for (int j = 1; j < k; ++j) {
    const std::optional<std::size_t> next = nearest(centres);
    if (!next) {
      out[j] = out[j - 1];
      continue;
    }
    out[j] = static_cast<std::int32_t>(*next);
    centres.push_back(*next);
  }
}

// --- cache file ---

constexpr char kMagic[8] = {'P', 'M', 'S', 'O', 'L', 'I', 'D', '1'};
// 2: neighbourhood spacing and the Gaussian-stack levels.
constexpr std::uint32_t kCacheVersion = 2;
// More stack levels than this would need an exemplar of 2^17 voxels a side.
constexpr std::uint32_t kMaxStackLevels = 16;

class Writer {
 public:
  template <typename T>
  void Put(const T& value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <typename T>
  void PutArray(const T* data, std::size_t count) {
    Put<std::uint64_t>(count);
    bytes_.append(reinterpret_cast<const char*>(data), sizeof(T) * count);
  }
  void PutString(const std::string& text) { PutArray(text.data(), text.size()); }
  void PutMatrix(const Eigen::MatrixXf& m) {
    Put<std::int64_t>(m.rows());
    Put<std::int64_t>(m.cols());
    bytes_.append(reinterpret_cast<const char*>(m.data()),
                  sizeof(float) * static_cast<std::size_t>(m.size()));
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

class Reader {
 public:
  Reader(const std::string& bytes, std::filesystem::path path)
      : bytes_(bytes), path_(std::move(path)) {}
  template <typename T>
  T Get() {
    T value;
    Take(&value, sizeof(T));
    return value;
  }
  template <typename T>
  std::vector<T> GetArray(std::size_t limit) {
    const auto count = Get<std::uint64_t>();
    if (count > limit) Fail("array length out of range");
    std::vector<T> values(count);
    Take(values.data(), sizeof(T) * count);
    return values;
  }
  std::string GetString() {
    const std::vector<char> chars = GetArray<char>(4096);
    return std::string(chars.begin(), chars.end());
  }
  Eigen::MatrixXf GetMatrix() {
    const auto rows = Get<std::int64_t>(), cols = Get<std::int64_t>();
    if (rows < 0 || cols < 0 || rows > 100000 || cols > 100000) Fail("matrix size out of range");
    Eigen::MatrixXf m(rows, cols);
    Take(m.data(), sizeof(float) * static_cast<std::size_t>(m.size()));
    return m;
  }
  bool AtEnd() const { return offset_ == bytes_.size(); }
  [[noreturn]] void Fail(const std::string& fault) const {
    throw Error(path_, fmt::format("similarity-set cache: {} (at byte {})", fault, offset_));
  }

 private:
  void Take(void* out, std::size_t size) {
    if (size > bytes_.size() - offset_) Fail("truncated");
    std::memcpy(out, bytes_.data() + offset_, size);
    offset_ += size;
  }
  const std::string& bytes_;
  std::filesystem::path path_;
  std::size_t offset_ = 0;
};

void PutLevel(Writer& out, const AppearanceSpace& a, const SimilaritySet& similarity) {
  out.Put(a.domain.size.width);
  out.Put(a.domain.size.height);
  out.Put(a.domain.size.depth);
  out.Put(static_cast<std::uint8_t>(a.domain.periodic));
  out.Put(a.domain.border);
  out.Put(a.neighbourhood);
  out.Put(a.spacing);
  out.Put(a.dimensions);
  out.Put(a.retained_variance);
  out.PutMatrix(a.channel_mean);
  out.PutMatrix(a.channel_basis);
  out.PutMatrix(a.feature_mean);
  out.PutMatrix(a.feature_basis);
  out.PutArray(a.values.data(), a.values.size());
  out.Put(similarity.k);
  out.PutArray(similarity.indices.data(), similarity.indices.size());
}

void GetLevel(Reader& in, AppearanceSpace& a, SimilaritySet& similarity) {
  a.domain.size.width = in.Get<int>();
  a.domain.size.height = in.Get<int>();
  a.domain.size.depth = in.Get<int>();
  a.domain.periodic = in.Get<std::uint8_t>() != 0;
  a.domain.border = in.Get<int>();
  a.neighbourhood = in.Get<int>();
  a.spacing = in.Get<int>();
  a.dimensions = in.Get<int>();
  a.retained_variance = in.Get<double>();
  a.channel_mean = in.GetMatrix();
  a.channel_basis = in.GetMatrix();
  a.feature_mean = in.GetMatrix();
  a.feature_basis = in.GetMatrix();
  const std::size_t voxels = a.domain.size.pixel_count();
  const auto extent = a.domain.extent();
  if (a.domain.size.width < 1 || a.domain.size.height < 1 || a.domain.size.depth < 1 ||
      a.dimensions < 1 || a.spacing < 1 || a.domain.border < 0 ||
      std::min({extent[0], extent[1], extent[2]}) < 1 || a.feature_basis.cols() != a.dimensions ||
      a.feature_basis.rows() != a.feature_mean.rows() ||
      a.channel_basis.rows() != a.channel_mean.rows()) {
    in.Fail("inconsistent sizes");
  }
  a.values = in.GetArray<float>(voxels * static_cast<std::size_t>(a.dimensions));
  if (a.values.size() != voxels * static_cast<std::size_t>(a.dimensions)) {
    in.Fail("wrong number of appearance values");
  }
  similarity.k = in.Get<int>();
  if (similarity.k < 1 || similarity.k > 64) in.Fail("k out of range");
  similarity.indices = in.GetArray<std::int32_t>(voxels * static_cast<std::size_t>(similarity.k));
  if (similarity.indices.size() != voxels * static_cast<std::size_t>(similarity.k)) {
    in.Fail("wrong number of candidates");
  }
  for (std::size_t voxel : a.domain.ValidIndices()) {
    for (std::int32_t candidate : similarity.at(voxel)) {
      if (candidate < 0 || static_cast<std::size_t>(candidate) >= voxels) {
        in.Fail("candidate index out of range");
      }
    }
  }
}

// Names each phase after the stack level it belongs to.
class LevelProgress final : public Progress {
 public:
  LevelProgress(Progress& inner, int spacing) : inner_(inner), spacing_(spacing) {}
  void Start(const std::string& label, std::size_t total) override {
    inner_.Start(fmt::format("{} (stack level, spacing {})", label, spacing_), total);
  }
  void Advance(std::size_t steps) override { inner_.Advance(steps); }
  void Finish() override { inner_.Finish(); }

 private:
  Progress& inner_;
  int spacing_;
};

}  // namespace

struct AppearanceIndex::Tree {
  std::vector<std::size_t> valid;
  AppearancePoints points;
  AppearanceTree tree;
  const AppearanceSpace& appearance;

  explicit Tree(const AppearanceSpace& space)
      : valid(space.domain.ValidIndices()),
        points{&space, &valid},
        tree(space.dimensions, points, nanoflann::KDTreeSingleIndexAdaptorParams(16)),
        appearance(space) {}
};

AppearanceIndex::AppearanceIndex(const AppearanceSpace& appearance)
    : tree_(std::make_unique<Tree>(appearance)) {}

AppearanceIndex::~AppearanceIndex() = default;

std::size_t AppearanceIndex::Nearest(std::span<const float> query) const {
  if (query.size() != static_cast<std::size_t>(tree_->appearance.dimensions)) {
    throw Error(fmt::format("appearance query of {} values, expected {}", query.size(),
                            tree_->appearance.dimensions));
  }
  NearestOutsideBoxes result(tree_->appearance.domain, tree_->valid, {}, -1);
  tree_->tree.findNeighbors(result, query.data(), nanoflann::SearchParams());
  return result.voxel();
}

const PreparedLevel* PreparedExemplar::StackLevel(int spacing) const {
  for (const PreparedLevel& level : stack) {
    if (level.appearance.spacing == spacing) return &level;
  }
  return nullptr;
}

const AppearanceSpace& PreparedExemplar::AppearanceAt(int spacing) const {
  const PreparedLevel* level = StackLevel(spacing);
  return level ? level->appearance : appearance;
}

const SimilaritySet& PreparedExemplar::SimilarityAt(int spacing) const {
  const PreparedLevel* level = StackLevel(spacing);
  return level ? level->similarity : similarity;
}

int ChebyshevDistance(const ExemplarDomain& domain, std::size_t a, std::size_t b) {
  const auto pa = domain.Coordinates(a), pb = domain.Coordinates(b);
  const auto extent = domain.extent();
  int distance = 0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    int d = std::abs(pa[axis] - pb[axis]);
    if (domain.periodic) d = std::min(d, extent[axis] - d);
    distance = std::max(distance, d);
  }
  return distance;
}

SimilaritySet BuildSimilaritySet(const AppearanceSpace& appearance,
                                 const SimilarityOptions& options, Progress* progress) {
  CheckOptions(options);
  NullProgress null_progress;
  Progress& report = OrNull(progress, null_progress);
  const std::vector<std::size_t> valid = appearance.domain.ValidIndices();
  const AppearancePoints points{&appearance, &valid};
  const AppearanceTree tree(static_cast<int>(appearance.dimensions), points,
                            nanoflann::KDTreeSingleIndexAdaptorParams(16));
  SimilaritySet set;
  set.k = options.candidates;
  set.indices.assign(appearance.domain.size.pixel_count() * static_cast<std::size_t>(set.k), -1);
  const int radius = options.exclusion / 2;
  constexpr std::size_t kChunk = 1024;
  const std::size_t chunks = (valid.size() + kChunk - 1) / kChunk;
  report.Start("similarity set", chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    const std::size_t begin = chunk * kChunk;
    for (std::size_t i = begin; i < std::min(valid.size(), (chunk + 1) * kChunk); ++i) {
      const std::size_t voxel = valid[i];
      const float* query =
          appearance.values.data() + voxel * static_cast<std::size_t>(appearance.dimensions);
      // When the previous voxel of the chunk is the one before along x, its candidates moved one
      // step along x are usually about as close (textures are coherent): a first bound.
      const auto position = appearance.domain.Coordinates(voxel);
      const bool follows =
          i > begin && valid[i - 1] + 1 == voxel && position[0] > appearance.domain.origin();
      FillCandidates(
          voxel, set.k, set.indices.data() + voxel * static_cast<std::size_t>(set.k),
          [&](const std::vector<std::size_t>& centres) -> std::optional<std::size_t> {
            NearestOutsideBoxes result(appearance.domain, valid, centres, radius);
            if (follows) {
              const std::int32_t previous =
                  set.indices[(voxel - 1) * static_cast<std::size_t>(set.k) + centres.size()];
              const auto c = appearance.domain.Coordinates(static_cast<std::size_t>(previous));
              const std::size_t seed =
                  appearance.domain.Index(appearance.domain.Wrap(c[0] + 1, 0), c[1], c[2]);
              result.Seed(SquaredDistance(appearance.at(voxel), appearance.at(seed)), seed);
            }
            tree.findNeighbors(result, query, nanoflann::SearchParams());
            if (!result.found()) return std::nullopt;
            return result.voxel();
          });
    }
    report.Advance();
  });
  report.Finish();
  return set;
}

SimilaritySet BuildSimilaritySetBruteForce(const AppearanceSpace& appearance,
                                           const SimilarityOptions& options) {
  CheckOptions(options);
  const std::vector<std::size_t> valid = appearance.domain.ValidIndices();
  SimilaritySet set;
  set.k = options.candidates;
  set.indices.assign(appearance.domain.size.pixel_count() * static_cast<std::size_t>(set.k), -1);
  const int radius = options.exclusion / 2;
  for (std::size_t voxel : valid) {
    FillCandidates(voxel, set.k, set.indices.data() + voxel * static_cast<std::size_t>(set.k),
                   [&](const std::vector<std::size_t>& centres) -> std::optional<std::size_t> {
                     std::optional<std::size_t> best;
                     float best_distance = std::numeric_limits<float>::infinity();
                     for (std::size_t other : valid) {
                       bool excluded = false;
                       for (std::size_t centre : centres) {
                         excluded |= ChebyshevDistance(appearance.domain, other, centre) <= radius;
                       }
                       if (excluded) continue;
                       const float d = SquaredDistance(appearance.at(voxel), appearance.at(other));
                       if (d < best_distance) best_distance = d, best = other;
                     }
                     return best;
                   });
  }
  return set;
}

std::string SimilarityCacheKey(const Image& exemplar, const AppearanceOptions& appearance,
                               const SimilarityOptions& similarity) {
  Writer description;
  description.PutString("photomat solid similarity set");
  description.Put(kCacheVersion);
  description.Put(exemplar.width());
  description.Put(exemplar.height());
  description.Put(exemplar.depth());
  description.Put(exemplar.channels());
  for (const std::string& name : exemplar.channel_names()) description.PutString(name);
  description.Put(appearance.neighbourhood);
  description.Put(appearance.spacing);
  description.Put(static_cast<std::uint8_t>(appearance.gaussian_stack));
  description.Put(appearance.dimensions);
  description.Put(static_cast<int>(appearance.boundary));
  description.Put(appearance.max_channels);
  description.Put(appearance.covariance_samples);
  description.Put(similarity.candidates);
  description.Put(similarity.exclusion);
  XXH3_state_t* state = XXH3_createState();
  XXH3_64bits_reset(state);
  XXH3_64bits_update(state, description.bytes().data(), description.bytes().size());
  // The values voxel by voxel, channels innermost (the interleaved order the keys were made in,
  // so caches written before the storage became planar stay valid), a block at a time.
  constexpr std::size_t kVoxelsPerUpdate = 4096;
  std::vector<float> interleaved;
  for (std::size_t first = 0; first < exemplar.pixel_count(); first += kVoxelsPerUpdate) {
    const std::size_t last = std::min(exemplar.pixel_count(), first + kVoxelsPerUpdate);
    interleaved.clear();
    for (std::size_t i = first; i < last; ++i) {
      for (const float v : exemplar.pixel(i)) interleaved.push_back(v);
    }
    XXH3_64bits_update(state, interleaved.data(), interleaved.size() * sizeof(float));
  }
  const XXH64_hash_t hash = XXH3_64bits_digest(state);
  XXH3_freeState(state);
  return fmt::format("{:016x}", hash);
}

void SavePreparedExemplar(const std::filesystem::path& path, const std::string& key,
                          const PreparedExemplar& prepared) {
  Writer out;
  out.Put(kMagic);
  out.Put(kCacheVersion);
  out.PutString(key);
  PutLevel(out, prepared.appearance, prepared.similarity);
  out.Put(static_cast<std::uint32_t>(prepared.stack.size()));
  for (const PreparedLevel& level : prepared.stack) {
    PutLevel(out, level.appearance, level.similarity);
  }
  WriteTextFileAtomically(path, out.bytes());
}

PreparedExemplar LoadPreparedExemplar(const std::filesystem::path& path, const std::string& key) {
  const std::string bytes = ReadTextFile(path);
  Reader in(bytes, path);
  char magic[8];
  for (char& c : magic) c = in.Get<char>();
  if (std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) in.Fail("not a photomat cache file");
  if (in.Get<std::uint32_t>() != kCacheVersion) in.Fail("another format version");
  if (in.GetString() != key) in.Fail("written for another exemplar or other settings");
  PreparedExemplar prepared;
  GetLevel(in, prepared.appearance, prepared.similarity);
  const auto levels = in.Get<std::uint32_t>();
  if (levels > kMaxStackLevels) in.Fail("too many stack levels");
  int spacing = 1;
  for (std::uint32_t l = 0; l < levels; ++l) {
    PreparedLevel level;
    GetLevel(in, level.appearance, level.similarity);
    spacing *= 2;
    if (level.appearance.spacing != spacing ||
        level.appearance.domain.size != prepared.appearance.domain.size ||
        level.appearance.domain.border != prepared.appearance.domain.border) {
      in.Fail("a stack level that does not fit the exemplar");
    }
    prepared.stack.push_back(std::move(level));
  }
  if (!in.AtEnd()) in.Fail("trailing bytes");
  prepared.from_cache = true;
  prepared.cache_file = path;
  return prepared;
}

PreparedExemplar PrepareExemplar(const Image& exemplar, const AppearanceOptions& appearance,
                                 const SimilarityOptions& similarity,
                                 const std::optional<std::filesystem::path>& cache_folder,
                                 Progress* progress) {
  std::string key;
  std::filesystem::path cache_file;
  if (cache_folder) {
    key = SimilarityCacheKey(exemplar, appearance, similarity);
    cache_file = *cache_folder / fmt::format("solid-{}.bin", key);
    if (std::filesystem::exists(cache_file)) {
      try {
        return LoadPreparedExemplar(cache_file, key);
      } catch (const Error& error) {
        spdlog::warn("ignoring the similarity-set cache: {}", error.what());
      }
    }
  }
  PreparedExemplar prepared;
  prepared.appearance = ComputeAppearanceSpace(exemplar, appearance, progress);
  prepared.similarity = BuildSimilaritySet(prepared.appearance, similarity, progress);
  if (appearance.gaussian_stack) {
    // The levels synthesis corrects: twice the spacing below the exemplar (ExemplarSolid).
    const auto extent = prepared.appearance.domain.extent();
    const int smallest = std::min({extent[0], extent[1], extent[2]});
    const VolumeEdge edge =
        prepared.appearance.domain.periodic ? VolumeEdge::kWrap : VolumeEdge::kClamp;
    NullProgress null_progress;
    for (int spacing = 2; 2 * spacing < smallest; spacing *= 2) {
      LevelProgress level_progress(OrNull(progress, null_progress), spacing);
      AppearanceOptions options = appearance;
      options.spacing = spacing;
      PreparedLevel level;
      level.appearance = ComputeAppearanceSpace(
          GaussianBlur(exemplar, GaussianStackSigma(spacing), edge), options, &level_progress);
      level.similarity = BuildSimilaritySet(level.appearance, similarity, &level_progress);
      prepared.stack.push_back(std::move(level));
    }
  }
  if (cache_folder) {
    std::error_code error;
    std::filesystem::create_directories(*cache_folder, error);
    if (error) {
      throw Error(*cache_folder, fmt::format("cannot create cache folder: {}", error.message()));
    }
    SavePreparedExemplar(cache_file, key, prepared);
    prepared.cache_file = cache_file;
  }
  return prepared;
}

}  // namespace photomat
