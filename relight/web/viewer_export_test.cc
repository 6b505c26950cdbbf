#include "relight/web/viewer_export.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/json_file.h"
#include "core/random.h"
#include "relight/web/viewer_assets.h"
#include "relight/web/viewer_pyramid.h"
#include "represent/fitting/fit.h"
#include "tests/support/synthetic_sets.h"
#include "tests/support/test_support.h"

namespace photomat {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::vector<Representation> FitAll(const PhotometricSet& set) {
  std::vector<Representation> fits;
  for (const Method& method : AllMethods()) fits.push_back(Fit(set, method));
  return fits;
}

LightDirection FromJson(const nlohmann::json& v) {
  return LightDirection::FromVector(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
}

std::vector<LightDirection> IrregularLights(int count, std::uint64_t seed) {
  Random random(seed);
  std::vector<LightDirection> lights;
  for (int i = 0; i < count; ++i) {
    lights.push_back(LightDirection::FromSlantTilt(random.Uniform(5, 65), random.Uniform(0, 360)));
  }
  return lights;
}

TEST(ViewerExportTest, WritesTheViewerAndEveryMethodsMapsAsFloat32Layers) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 24);
  const std::vector<Representation> fits = FitAll(synthetic.set);
  ExportViewer(dir / "viewer", fits);

  for (const ViewerAsset& asset : ViewerAssets()) {
    EXPECT_EQ(ReadTextFile(dir / "viewer" / asset.path), asset.contents) << asset.path;
  }
  EXPECT_TRUE(fs::exists(dir / "viewer" / "index.html"));
  EXPECT_TRUE(fs::exists(dir / "viewer" / "basis.js"));

  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  EXPECT_EQ(manifest["format"], "photomat-viewer");
  EXPECT_EQ(manifest["width"], 24);
  EXPECT_EQ(manifest["height"], 24);
  ASSERT_EQ(manifest["methods"].size(), fits.size());
  for (std::size_t m = 0; m < fits.size(); ++m) {
    const Representation& r = fits[m];
    const nlohmann::json& method = manifest["methods"][m];
    SCOPED_TRACE(r.method());
    EXPECT_EQ(method["name"], r.method());
    EXPECT_EQ(method["layout"], r.layout().ToJson());
    const int n = r.maps().channels();
    const int layers = (n + 3) / 4;
    EXPECT_EQ(method["data"]["layers"], layers);
    const std::vector<float> data =
        ReadFloat32File(dir / "viewer" / method["data"]["file"].get<std::string>());
    ASSERT_EQ(data.size(), static_cast<std::size_t>(layers) * 24 * 24 * 4);
    // Map i of pixel p is component i % 4 of texel p in layer i / 4; padding is 0.
    for (std::size_t p = 0; p < r.maps().pixel_count(); ++p) {
      for (int i = 0; i < 4 * layers; ++i) {
        const float expected = i < n ? r.maps().pixel(p)[i] : 0.0f;
        ASSERT_EQ(data[((i / 4) * r.maps().pixel_count() + p) * 4 + i % 4], expected);
      }
    }
  }
}

TEST(ViewerExportTest, CheckLightsCarryTheCxxCoefficientsOverTheHemisphereAndTheNodes) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const std::vector<Representation> fits = FitAll(synthetic.set);
  ExportViewer(dir / "viewer", fits);
  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  for (std::size_t m = 0; m < fits.size(); ++m) {
    const nlohmann::json& check = manifest["methods"][m]["check"];
    SCOPED_TRACE(fits[m].method());
    double largest_slant = 0.0;
    ASSERT_EQ(check["lights"].size(), check["coefficients"].size());
    ASSERT_GE(check["lights"].size(), 64u);
    for (std::size_t i = 0; i < check["lights"].size(); ++i) {
      const LightDirection light = FromJson(check["lights"][i]);
      largest_slant = std::max(largest_slant, light.SlantDegrees());
      const Eigen::VectorXd expected = fits[m].basis().Coefficients(light);
      const auto written = check["coefficients"][i].get<std::vector<double>>();
      ASSERT_EQ(written.size(), static_cast<std::size_t>(expected.size()));
      // The light was normalised again on reading: equal up to that rounding.
      for (int j = 0; j < expected.size(); ++j) {
        EXPECT_NEAR(written[j], expected[j], 1e-12 * std::max(1.0, std::abs(expected[j])));
      }
    }
    EXPECT_GT(largest_slant, 85.0);  // the check reaches the horizon
    EXPECT_LE(check["tolerance"].get<double>(), 1e-9);
  }
  // Eigen-k checks every fitted light, where interpolation must reproduce the node exactly.
  const auto eigen_lights = ViewerCheckLights(fits.back().basis());
  EXPECT_EQ(eigen_lights.size(), 64u + 1u + 36u);
}

TEST(ViewerExportTest, BasesAreDescribedExactly) {
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 12);
  const Representation three = Fit(synthetic.set, Method::Parse("3i"));
  const nlohmann::json linear = ViewerBasisJson(three.basis());
  EXPECT_EQ(linear["kind"], "linear");
  const Eigen::MatrixXd matrix = *three.basis().LinearInLight();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) EXPECT_EQ(linear["matrix"][r][c].get<double>(), matrix(r, c));
  }
  EXPECT_EQ(ViewerBasisJson(PtmLightBasis())["kind"], "ptm");

  // The thesis grid: three rings of twelve, by increasing slant, with their tilts and nodes.
  const Representation eigen = Fit(synthetic.set, Method::Parse("eigen3"));
  const nlohmann::json rings = ViewerBasisJson(eigen.basis());
  EXPECT_EQ(rings["kind"], "interpolated");
  EXPECT_EQ(rings["scheme"], "slant-rings");
  ASSERT_EQ(rings["rings"].size(), 3u);
  for (int ring = 0; ring < 3; ++ring) {
    EXPECT_NEAR(rings["rings"][ring]["slant"].get<double>(), 30.0 + 15.0 * ring, 1e-9);
    ASSERT_EQ(rings["rings"][ring]["by_tilt"].size(), 12u);
    for (const auto& entry : rings["rings"][ring]["by_tilt"]) {
      const LightDirection node = synthetic.set.light(entry[1].get<int>());
      EXPECT_NEAR(node.TiltDegrees(), entry[0].get<double>(), 1e-9);
    }
  }
  ASSERT_EQ(rings["values"].size(), 36u);
  const auto& values = dynamic_cast<const InterpolatedLightBasis&>(eigen.basis()).values();
  for (int node = 0; node < 36; ++node) {
    for (int j = 0; j < 3; ++j) EXPECT_EQ(rings["values"][node][j].get<double>(), values(j, node));
  }
}

TEST(ViewerExportTest, IrregularLightsExportTheirTriangulation) {
  SyntheticMaterialOptions options;
  options.pattern = SurfacePattern::kBumps;
  options.width = options.height = 12;
  const auto material = MakeSyntheticMaterial(options);
  const auto lights = IrregularLights(30, 11);
  const PhotometricSet set = RenderSyntheticCapture(material, lights);
  const Representation eigen = Fit(set, Method::Parse("eigen3"));
  const nlohmann::json json = ViewerBasisJson(eigen.basis());
  EXPECT_EQ(json["scheme"], "triangulation");
  const auto& interpolator =
      dynamic_cast<const InterpolatedLightBasis&>(eigen.basis()).interpolator();
  ASSERT_EQ(json["projected"].size(), lights.size());
  EXPECT_EQ(json["projection_scale"], LightInterpolator::kProjectionScale);
  for (std::size_t i = 0; i < lights.size(); ++i) {
    // slant * (cos tilt, sin tilt) in radians, scaled.
    const double slant = lights[i].SlantDegrees() * std::numbers::pi / 180.0;
    const double tilt = lights[i].TiltDegrees() * std::numbers::pi / 180.0;
    EXPECT_NEAR(json["projected"][i][0].get<double>(), 1000.0 * slant * std::cos(tilt), 1e-9);
    EXPECT_NEAR(json["projected"][i][1].get<double>(), 1000.0 * slant * std::sin(tilt), 1e-9);
  }
  EXPECT_EQ(json["triangles"].size(), interpolator.triangles().size());
  EXPECT_GE(json["triangles"].size(), lights.size() - 2 - json["boundary"].size());
  EXPECT_GE(json["boundary"].size(), 3u);
}

TEST(ViewerExportTest, CoefficientTableIsExactOnItsGridAndBoundedBetween) {
  const PtmLightBasis ptm;
  const CoefficientTable table(ptm);
  EXPECT_EQ(table.slant_steps(), 91);
  EXPECT_EQ(table.tilt_steps(), 361);
  // Bilinear on 1-degree cells: the error of a quadratic in (u, v) is about h^2/8 * curvature.
  EXPECT_GT(table.max_error(), 1e-6);
  EXPECT_LT(table.max_error(), 2e-4);
  Random random(3);
  double worst = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const auto light = LightDirection::FromSlantTilt(random.Uniform(0, 90), random.Uniform(0, 360));
    worst = std::max(worst,
                     (table.Coefficients(light) - ptm.Coefficients(light)).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, table.max_error() * 1.01 + 1e-7);
  for (const auto& [slant, tilt] : {std::pair{0.0, 0.0}, std::pair{0.0, 200.0},
                                    std::pair{37.0, 121.0}, std::pair{90.0, 359.0}}) {
    const auto light = LightDirection::FromSlantTilt(slant, tilt);
    EXPECT_LT((table.Coefficients(light) - ptm.Coefficients(light)).cwiseAbs().maxCoeff(), 1e-6)
        << slant << "," << tilt;
  }
  EXPECT_THROW(CoefficientTable(ptm, 0.7), Error);
}

TEST(ViewerExportTest, TableMethodsWriteTheirCoefficientTable) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBumps, 12);
  const std::vector<Representation> fits = {Fit(synthetic.set, Method::Parse("ptm")),
                                            Fit(synthetic.set, Method::Parse("gradient"))};
  ViewerExportOptions options;
  options.table_methods = {"ptm"};
  ExportViewer(dir / "viewer", fits, options);
  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  const nlohmann::json& basis = manifest["methods"][0]["basis"];
  EXPECT_EQ(basis["kind"], "table");
  EXPECT_EQ(basis["source_kind"], "ptm");
  EXPECT_LT(basis["max_error"].get<double>(), 2e-4);
  const std::vector<float> values =
      ReadFloat32File(dir / "viewer" / basis["file"].get<std::string>());
  const CoefficientTable table(fits[0].basis());
  EXPECT_EQ(values, table.values());
  EXPECT_EQ(manifest["methods"][1]["basis"]["kind"], "linear");
}

TEST(ViewerExportTest, DisplayMapsShowTheTruthOfALambertianSample) {
  TempDir dir;
  const auto synthetic = testing::LambertianSet(SurfacePattern::kBricks, 48);
  ExportViewer(dir / "viewer", {Fit(synthetic.set, Method::Parse("eigen3")),
                                Fit(synthetic.set, Method::Parse("gradient"))});
  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  ASSERT_EQ(manifest["views"].size(), 3u);
  for (const auto& view : manifest["views"]) EXPECT_EQ(view["source"], "gradient");

  ImageReadOptions raw;
  raw.colour_space = ColourSpace::kLinear;
  const Image normals = ReadImage(dir / "viewer" / "maps" / "normal.png", raw).image;
  const Image albedo = ReadImage(dir / "viewer" / "maps" / "albedo.png").image;  // sRGB
  const Image height = ReadImage(dir / "viewer" / "maps" / "height.png", raw).image;
  const SyntheticMaterial& truth = synthetic.material;
  for (std::size_t p = 0; p < normals.pixel_count(); ++p) {
    for (int c = 0; c < 3; ++c) {
      ASSERT_NEAR(normals.pixel(p)[c], 0.5 * (truth.normals.pixel(p)[c] + 1.0), 1.0 / 255 + 1e-4);
      // sRGB 8-bit steps are at most 0.0056 linear.
      ASSERT_NEAR(albedo.pixel(p)[c], truth.albedo.pixel(p)[c], 0.006);
    }
  }
  // The height is the truth up to offset and scale: strongly correlated.
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  const auto n = static_cast<double>(height.pixel_count());
  for (std::size_t p = 0; p < height.pixel_count(); ++p) {
    const double x = height.pixel(p)[0], y = truth.height.pixel(p)[0];
    sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
  }
  const double correlation =
      (sxy - sx * sy / n) / std::sqrt((sxx - sx * sx / n) * (syy - sy * sy / n));
  EXPECT_GT(correlation, 0.98);
}

TEST(ViewerExportTest, RejectsBadInputAndNeverOverwritesOtherFolders) {
  TempDir dir;
  EXPECT_THROW(ExportViewer(dir / "v", {}), Error);
  const auto small = testing::LambertianSet(SurfacePattern::kBumps, 12);
  const auto large = testing::LambertianSet(SurfacePattern::kBumps, 16);
  const Representation a = Fit(small.set, Method::Parse("gradient"));
  try {
    ExportViewer(dir / "v", {a, Fit(large.set, Method::Parse("ptm"))});
    FAIL() << "different sizes were accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("16x16"), std::string::npos) << error.what();
  }
  EXPECT_THROW(ExportViewer(dir / "v", {a, a}), Error);
  EXPECT_FALSE(fs::exists(dir / "v"));

  testing::WriteFile(dir / "mine" / "notes.txt", "keep me");
  try {
    ExportViewer(dir / "mine", {a});
    FAIL() << "an unrelated folder was replaced";
  } catch (const Error& error) {
    EXPECT_EQ(error.file(), dir / "mine");
  }
  EXPECT_EQ(ReadTextFile(dir / "mine" / "notes.txt"), "keep me");

  // A previous export is replaced whole.
  ExportViewer(dir / "v", {a, Fit(small.set, Method::Parse("ptm"))});
  ExportViewer(dir / "v", {a});
  EXPECT_FALSE(fs::exists(dir / "v" / "maps" / "ptm.f32"));
  EXPECT_EQ(ReadJsonFile(dir / "v" / "viewer.json")["methods"].size(), 1u);
}

// A basis of a kind basis.js has no formula for: smooth in the light, two terms.
class LobeBasis final : public LightBasis {
 public:
  std::string_view kind() const override { return "lobe"; }
  int size() const override { return 2; }
  Eigen::VectorXd Coefficients(const LightDirection& l) const override {
    Eigen::VectorXd c(2);
    c << l.z() * l.z() * l.z(), 0.5 * l.x() + 0.25 * l.y() * l.z();
    return c;
  }
  nlohmann::json ToJson() const override { return {{"kind", "lobe"}}; }
};

// Stands in for hemispherical harmonics, which the viewer recognises by kind and terms.
class HshKindBasis final : public LightBasis {
 public:
  std::string_view kind() const override { return "hsh"; }
  int size() const override { return 4; }
  Eigen::VectorXd Coefficients(const LightDirection& l) const override {
    return Eigen::Vector4d(1.0, l.x(), l.y(), l.z());
  }
  nlohmann::json ToJson() const override { return {{"kind", "hsh"}, {"terms", 4}}; }
};

TEST(ViewerExportTest, UnknownBasesGoThroughTheTableAndHshThroughItsFormula) {
  TempDir dir;
  Image maps(8, 6, 4);
  for (std::size_t i = 0; i < maps.values().size(); ++i) maps.values()[i] = 0.01f * (i % 97);
  const MapLayout shared{
      .basis_size = 2, .basis_per_channel = false, .has_gain = true, .output_channels = 2};
  const MapLayout hsh_layout{
      .basis_size = 4, .basis_per_channel = false, .has_gain = false, .output_channels = 1};
  const Representation lobe("lobe", maps, shared, std::make_shared<LobeBasis>());
  const Representation hsh("hsh4", maps, hsh_layout, std::make_shared<HshKindBasis>());
  EXPECT_FALSE(ViewerEvaluatesExactly(lobe.basis()));
  EXPECT_THROW(ViewerBasisJson(lobe.basis()), Error);
  EXPECT_TRUE(ViewerEvaluatesExactly(hsh.basis()));
  ExportViewer(dir / "viewer", {lobe, hsh});
  const nlohmann::json manifest = ReadJsonFile(dir / "viewer" / "viewer.json");
  const nlohmann::json& table = manifest["methods"][0]["basis"];
  EXPECT_EQ(table["kind"], "table");
  EXPECT_EQ(table["source_kind"], "lobe");
  EXPECT_LT(table["max_error"].get<double>(), 5e-4);
  EXPECT_TRUE(fs::exists(dir / "viewer" / table["file"].get<std::string>()));
  EXPECT_EQ(manifest["methods"][1]["basis"], nlohmann::json({{"kind", "hsh"}, {"terms", 4}}));
  EXPECT_TRUE(manifest["views"].empty());  // neither gives normals
}

TEST(ViewerExportTest, MethodLabels) {
  EXPECT_EQ(MethodLabel("3i"), "3I");
  EXPECT_EQ(MethodLabel("ptm-lrgb"), "PTM LRGB");
  EXPECT_EQ(MethodLabel("eigen6"), "Eigen-6");
  EXPECT_EQ(MethodLabel("gradient"), "Gradient");
}

}  // namespace
}  // namespace photomat
