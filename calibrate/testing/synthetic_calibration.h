#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "calibrate/lights/mirror_sphere.h"
#include "calibrate/radiometry/near_light.h"
#include "capture/synthetic/synthetic_capture.h"
#include "core/image.h"
#include "core/light_direction.h"
#include "core/photometric_set.h"

namespace photomat {

// Synthetic captures with known truth for the calibration stages: a mirror sphere under distant
// lights, and a sample or a flat matte target under near point lights.

struct MirrorSphereRenderOptions {
  int width = 320;
  int height = 240;
  SphereCircle sphere{Eigen::Vector2d(160.0, 120.0), 90.0};
  // The lamp seen in the mirror: a Gaussian lobe of this angular standard deviation around the
  // light direction (a lamp of finite size), with this peak value.
  double lamp_sigma_degrees = 3.0;
  double lamp_peak = 0.9;
  // A dim reflection of the room (brighter toward +y) so that the outline shows without a mask.
  double environment = 0.06;
  double background = 0.01;
  int supersampling = 4;  // per axis, for anti-aliased outlines and highlights
  double noise_sigma = 0.0;
  std::uint64_t noise_seed = 1;
  // Perspective camera: set, the sphere (radius 1) is centred at `sphere_centre_camera` in the
  // camera frame (OpenCV: x right, y down, z forward) and `sphere` is ignored.
  std::optional<CameraIntrinsics> camera;
  Eigen::Vector3d sphere_centre_camera = Eigen::Vector3d(0.0, 0.0, 10.0);
  // More spheres in the same images beside `sphere` (orthographic camera only).
  std::vector<SphereCircle> more_spheres;
  // The lens's blur: a Gaussian of this standard deviation (pixels) over the images and the
  // mask, before the noise.
  double blur_sigma = 0.0;
};

struct MirrorSphereRender {
  std::vector<Image> images;  // RGB, linear
  Image coverage;             // 1 channel: the sphere's anti-aliased mask (coverage in [0, 1])
};

MirrorSphereRender RenderMirrorSphere(const std::vector<LightDirection>& lights,
                                      const MirrorSphereRenderOptions& options = {});

// The same spheres (orthographic camera) under near point lamps at `lamps` (the sample frame of
// near_light.h, pixel units): each sphere rests on the sample plane (mirror_sphere.h,
// LightModel), and each of its points mirrors the lamp in the direction from that point.
MirrorSphereRender RenderMirrorSpheresUnderLamps(const std::vector<Eigen::Vector3d>& lamps,
                                                 const MirrorSphereRenderOptions& options);

// A small render (200 x 150, a sphere of radius 60 px, 3 x 3 supersampling): plenty for
// 0.1-degree accuracy, and fast.
MirrorSphereRenderOptions SmallSphereRenderOptions();
// Two spheres on the sample plane, left and right of a 320 x 240 image (radii 40 and 41.5 px),
// with the flaws of a real capture: a blurred lens (the outline and the highlights, Gaussian
// 1 px), sensor noise (0.01 of full scale, which moves each highlight's centroid) and lamps of
// finite size (2 degrees).
MirrorSphereRenderOptions TwoSphereRenderOptions();
// `count` lamps `distance` px from the sample's centre (sample frame), slants 15 to 55 degrees
// all around: for two spheres in TwoSphereRenderOptions about two image widths away.
std::vector<Eigen::Vector3d> NearLampRing(int count = 16, double distance = 600.0);
// "sphere_0.png", "sphere_1.png", ...: the names a calibration gives its images in messages.
std::vector<std::string> SphereImageNames(std::size_t count);
// The angles between the lights of two lists of the same length, in degrees.
struct AngleStats {
  double mean = 0.0, max = 0.0;
};
AngleStats CompareLights(const std::vector<LightDirection>& a,
                         const std::vector<LightDirection>& b);

// `material` under near point lights with inverse-square fall-off (Lambertian, attached shadows
// clamped to 0; or, `microfacet`, the GGX material of core/microfacet_brdf.h with the material's
// roughness and F0 maps, each light of irradiance intensity / d^2 from its direction at the
// point), in the sample frame of near_light.h (surface height included). The set's lights are
// the nominal directions from the sample's centre.
PhotometricSet RenderNearLightCapture(const SyntheticMaterial& material,
                                      const std::vector<NearLight>& lights,
                                      bool microfacet = false);

// A flat matte target of uniform `albedo` under the same lights (what EstimateFlatField reads),
// with optional Gaussian noise.
PhotometricSet RenderNearLightTarget(int width, int height, const std::vector<NearLight>& lights,
                                     double albedo = 0.5, double noise_sigma = 0.0,
                                     std::uint64_t noise_seed = 1);

}  // namespace photomat
