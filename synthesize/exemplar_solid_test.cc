#include "synthesize/exemplar_solid.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <chrono>
#include <numbers>

#include "synthesize/procedural_exemplars.h"
#include "synthesize/solid_quality.h"
#include "synthesize/volume_io.h"

namespace photomat {
namespace {

TEST(ExemplarSolidDevTest, Rotation) {
  const Volume exemplar = MakeProceduralExemplar(
      ProceduralPattern::kStripes, std::getenv("I8_N") ? std::atoi(std::getenv("I8_N")) : 16, 3);
  const PreparedExemplar prepared = PrepareExemplar(exemplar, {}, {}, std::nullopt);
  for (double angle : {0.0, 30.0, 60.0}) {
    ExemplarSolidOptions options;
    options.size = VolumeSize::Cube(2 * exemplar.size().x);
    const Eigen::Matrix3f r = Eigen::AngleAxisf(static_cast<float>(angle * std::numbers::pi / 180),
                                                Eigen::Vector3f::UnitZ())
                                  .toRotationMatrix();
    const FrameField field = ConstantFrameField(options.size, r);
    options.field = &field;
    for (int passes : {0, 1})
      for (double j : {0.0, 0.7}) {
        options.correction_passes = passes;
        options.jitter = j;
        const Eigen::Vector3d d2 = PrincipalDirection(
            StructureTensor(SynthesizeExemplarSolid(exemplar, prepared, options).volume));
        std::printf("  passes %d jitter %.1f dir %.3f %.3f %.3f\n", passes, j, d2.x(), d2.y(),
                    d2.z());
      }
    options.correction_passes = 2;
    options.jitter = 0.7;
    const ExemplarSolidResult a = SynthesizeExemplarSolid(exemplar, prepared, options);
    const Eigen::Vector3d dir = PrincipalDirection(StructureTensor(a.volume));
    std::printf("angle %.0f dir %.3f %.3f %.3f E %.4f\n", angle, dir.x(), dir.y(), dir.z(),
                NeighbourhoodMatchError(a.volume, exemplar, prepared.appearance));
    WriteCentralSlices("/tmp/i8/rot" + std::to_string(int(angle)), "a_", a.volume);
  }
  ExemplarSolidOptions options;
  options.size = VolumeSize::Cube(2 * exemplar.size().x);
  const Eigen::Vector3d dir = PrincipalDirection(
      StructureTensor(SynthesizeExemplarSolid(exemplar, prepared, options).volume));
  std::printf("isometric dir %.3f %.3f %.3f\n", dir.x(), dir.y(), dir.z());
}

}  // namespace
}  // namespace photomat
