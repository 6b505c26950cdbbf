// relight's rbf and bilinear planes made band by band (RelightWebBands, relight_web_format.h):
// any band height gives the planes of one band, byte for byte, from a stack in memory, a stack
// read in bands and photographs read in bands; and the basis is the PCA of the whole profile
// matrix.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "capture/io/capture_manifest.h"
#include "capture/io/load_photometric_set.h"
#include "capture/io/streamed_set.h"
#include "core/colour.h"
#include "core/error.h"
#include "relight/formats/relight_web_format.h"
#include "represent/fitting/fit.h"
#include "represent/stack/map_stack.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

void ExpectSamePlanes(const RelightWebStack& a, const RelightWebStack& b, const std::string& what) {
  EXPECT_EQ(a.basis, b.basis) << what;
  EXPECT_EQ(a.basis_values, b.basis_values) << what;
  EXPECT_EQ(a.range, b.range) << what;
  EXPECT_EQ(a.scale, b.scale) << what;
  EXPECT_EQ(a.bias, b.bias) << what;
  EXPECT_EQ(a.lights, b.lights) << what;
  ASSERT_EQ(a.planes.size(), b.planes.size()) << what;
  for (std::size_t p = 0; p < a.planes.size(); ++p) EXPECT_EQ(a.planes[p], b.planes[p]) << what;
}

RelightWebBands Rows(int rows) {
  RelightWebBands bands;
  bands.band_rows = rows;
  return bands;
}

RelightWebOptions Basis(RelightWebBasis basis) {
  RelightWebOptions options;
  options.basis = basis;
  return options;
}

// A shadowed, glossy RGB sample (40 x 40, the five-ring dome) fitted with rbf, linear values.
LoadedStack LinearRbfFit() {
  const PhotometricSet set = testing::ShadowedSpecularSet(40).set;
  return {Fit(set, Method::Parse("rbf")), StackProvenance(set.lights(), "linear", "shadowed")};
}

TEST(RelightWebBandsTest, AStackInBandsOfAnyHeightGivesTheOneBandPlanes) {
  const testing::TempDir dir;
  const LoadedStack fit = LinearRbfFit();
  SaveRepresentation(dir / "rbf.exr", fit.representation, fit.provenance);
  // As read back: the lights went through the stack's description (their last bits may differ).
  const LoadedStack stack = LoadRepresentation(dir / "rbf.exr");
  const int height = stack.representation.height();
  for (RelightWebBasis basis : {RelightWebBasis::kRbf, RelightWebBasis::kBilinear}) {
    const std::string name(ToString(basis));
    const RelightWebStack one = RelightWebFromStack(stack, Basis(basis), Rows(height));
    for (int rows : {1, 3, 7}) {
      ExpectSamePlanes(RelightWebFromStack(stack, Basis(basis), Rows(rows)), one,
                       name + " in memory, bands of " + std::to_string(rows));
      StackBandReader reader(dir / "rbf.exr");
      ExpectSamePlanes(RelightWebFromStack(reader, Basis(basis), Rows(rows)), one,
                       name + " read in bands of " + std::to_string(rows));
    }
  }
}

TEST(RelightWebBandsTest, PhotographsReadInBandsGiveTheInMemoryRbfPlanes) {
  const testing::TempDir dir;
  SavePhotometricSet(dir / "capture", testing::ShadowedSpecularSet(40).set);
  const LoadedSet loaded = LoadPhotometricSet(dir / "capture");
  const RelightWebOptions rbf = Basis(RelightWebBasis::kRbf);
  const RelightWebStack whole = RelightWebFromSet(loaded.set, rbf, Rows(loaded.set.height()));
  ASSERT_EQ(whole.lights.size(), loaded.set.lights().size());
  for (int rows : {2, 5}) {
    StreamedSet set = OpenStreamedSet(dir / "capture");
    ExpectSamePlanes(RelightWebFromSet(set, rbf, Rows(rows)), whole,
                     "bands of " + std::to_string(rows));
  }
  // ptm, hsh and bilinear come from a fit of the encoded photographs, which the caller makes.
  StreamedSet set = OpenStreamedSet(dir / "capture");
  EXPECT_THAT([&] { RelightWebFromSet(set, Basis(RelightWebBasis::kBilinear)); },
              ThrowsMessage<Error>(HasSubstr("made from a bilinear fit of their encoded values")));
}

// The basis against the PCA of the whole profile matrix made directly (every pixel's sRGB codes
// at the 40 nodes as one matrix, centred in double): the same mean codes, and axis codes within
// one of the direct axes' (the band's covariance sums floats per image row; a code can round
// the other way when an axis entry lies within that rounding of a half code).
TEST(RelightWebBandsTest, TheBasisIsThePcaOfTheWholeProfileMatrix) {
  const PhotometricSet set = testing::ShadowedSpecularSet(40).set;
  RelightWebOptions options = Basis(RelightWebBasis::kRbf);
  options.planes = 6;
  const RelightWebStack web = RelightWebFromSet(set, options, Rows(3));
  const int n = set.size(), dimension = 3 * n;
  const Eigen::Index pixels = static_cast<Eigen::Index>(set.width()) * set.height();
  Eigen::MatrixXd profiles(pixels, dimension);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const auto plane = set.images()[i].plane(k);
      for (Eigen::Index p = 0; p < pixels; ++p) {
        profiles(p, 3 * i + k) = 255.0 * LinearToSrgb(plane[static_cast<std::size_t>(p)]);
      }
    }
  }
  const Eigen::RowVectorXd mean = profiles.colwise().mean();
  for (int d = 0; d < dimension; ++d) EXPECT_EQ(web.basis_values[d], std::lround(mean[d])) << d;
  const Eigen::MatrixXd centred = profiles.rowwise() - mean;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(centred.transpose() * centred);
  int differing = 0;
  for (int p = 0; p < options.planes; ++p) {
    Eigen::VectorXd axis = eigen.eigenvectors().col(dimension - 1 - p);
    Eigen::Index largest;
    axis.cwiseAbs().maxCoeff(&largest);
    if (axis[largest] < 0) axis = -axis;
    const double range = 127.0 / axis.cwiseAbs().maxCoeff();
    EXPECT_NEAR(web.range[p], range, 1e-4 * range) << p;
    for (int d = 0; d < dimension; ++d) {
      const long code = std::lround(127.0 + range * axis[d]);
      const int stored = web.basis_values[static_cast<std::size_t>(p + 1) * dimension + d];
      EXPECT_LE(std::abs(stored - code), 1) << "plane " << p << ", entry " << d;
      differing += stored != code ? 1 : 0;
    }
  }
  std::printf("%d of %d axis codes differ from the direct PCA's\n", differing,
              options.planes * dimension);
}

// Records the phases a construction reports.
class PhaseRecorder final : public Progress {
 public:
  void Start(const std::string& label, std::size_t total) override {
    const std::lock_guard lock(mutex_);
    phases.emplace_back(label, total);
    advanced.push_back(0);
  }
  void Advance(std::size_t steps) override {
    const std::lock_guard lock(mutex_);
    advanced.back() += steps;
  }
  void Finish() override {}
  std::vector<std::pair<std::string, std::size_t>> phases;
  std::vector<std::size_t> advanced;

 private:
  std::mutex mutex_;
};

// Three passes, each over every band (40 rows in bands of 16: 3 bands), reported as phases.
TEST(RelightWebBandsTest, ReportsItsThreePassesAsPhases) {
  PhaseRecorder recorder;
  RelightWebBands bands = Rows(16);
  bands.progress = &recorder;
  RelightWebFromStack(LinearRbfFit(), Basis(RelightWebBasis::kRbf), bands);
  using Phase = std::pair<std::string, std::size_t>;
  EXPECT_THAT(recorder.phases, ::testing::ElementsAre(Phase{"relight planes: mean", 3},
                                                      Phase{"relight planes: covariance", 3},
                                                      Phase{"relight planes: coefficients", 3}));
  EXPECT_THAT(recorder.advanced, ::testing::ElementsAre(3, 3, 3));
}

}  // namespace
}  // namespace photomat
