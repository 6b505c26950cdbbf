#pragma once

#include <cmath>
#include <numbers>

namespace photomat {

// The one microfacet BRDF of photomat: the synthetic generator renders with it, the `pbr` method
// fits and relights with it. Templated on the scalar so that Ceres' Jets differentiate it.
//
// Conventions (those of glTF 2.0's metallic-roughness dielectric and Blender's Principled BSDF
// inputs; README, "Representations"):
//  - orthographic camera: the view direction is v = +z for every pixel, as in the rest of photomat;
//  - distant lights, l a unit vector towards the light;
//  - perceptual roughness r in [0, 1], GGX alpha = r^2 (glTF, Blender, Unreal, Substance);
//  - D: GGX / Trowbridge-Reitz, D(h) = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2);
//  - G: Smith height-correlated, as the visibility V = G / (4 n.l n.v)
//      V = 0.5 / (n.l sqrt((n.v)^2 (1 - alpha^2) + alpha^2) + n.v sqrt((n.l)^2 (1 - alpha^2) +
//      alpha^2))
//    (IMPLEMENTER CHOICE: the form glTF's reference renderer and Filament use; it accounts for the
//    correlation of masking and shadowing that the separable form double-counts at grazing angles);
//  - F: Schlick, F = F0 + (1 - F0) (1 - v.h)^5, with a grey (white-light) F0;
//  - diffuse and specular mixed as glTF's fresnel_mix: f = (1 - F) base / pi + F D V.
//  - Radiance = pi f (n.l) I. photomat's light intensity I is in units of irradiance / pi (a white
//    Lambertian surface facing a light of intensity 1 has radiance 1), so that the base colour is
//    the albedo photometric stereo measures (radiance = albedo n.l). A renderer's light of
//    irradiance E (Blender's sun "strength") matches intensity I = E / pi.
//
// The response at one pixel: radiance of colour channel c = diffuse * base_c + specular (light of
// intensity 1). Both 0 when the light or the view is below the surface (n.l <= 0 or n.v <= 0).
template <typename T>
struct MicrofacetResponse {
  T diffuse;
  T specular;
};

// `normal` unit (3 values), `light` unit (3 values, towards the light).
template <typename T, typename L>
MicrofacetResponse<T> MicrofacetRadiance(const T* normal, const L* light, const T& roughness,
                                         const T& f0) {
  using std::sqrt;
  const T n_dot_l = normal[0] * T(light[0]) + normal[1] * T(light[1]) + normal[2] * T(light[2]);
  const T n_dot_v = normal[2];
  if (!(n_dot_l > T(0.0)) || !(n_dot_v > T(0.0))) return {T(0.0), T(0.0)};
  // h = (l + v) / |l + v|, v = (0, 0, 1).
  const T hx = T(light[0]), hy = T(light[1]), hz = T(light[2]) + T(1.0);
  const T h_norm = sqrt(hx * hx + hy * hy + hz * hz);
  const T n_dot_h = (normal[0] * hx + normal[1] * hy + normal[2] * hz) / h_norm;
  const T v_dot_h = hz / h_norm;

  const T alpha = roughness * roughness;
  const T alpha2 = alpha * alpha;
  const T d_denominator = n_dot_h * n_dot_h * (alpha2 - T(1.0)) + T(1.0);
  const T distribution = alpha2 / (T(std::numbers::pi) * d_denominator * d_denominator);
  const T visibility = T(0.5) / (n_dot_l * sqrt(n_dot_v * n_dot_v * (T(1.0) - alpha2) + alpha2) +
                                 n_dot_v * sqrt(n_dot_l * n_dot_l * (T(1.0) - alpha2) + alpha2));
  const T m = T(1.0) - v_dot_h;
  const T m2 = m * m;
  const T fresnel = f0 + (T(1.0) - f0) * (m2 * m2 * m);
  return {(T(1.0) - fresnel) * n_dot_l,
          T(std::numbers::pi) * fresnel * distribution * visibility * n_dot_l};
}

}  // namespace photomat
