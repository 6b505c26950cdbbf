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

// MicrofacetRadiance (double) with its derivatives by roughness, F0 and the normal's three
// components (the normal as a free 3-vector: a fit on the unit sphere projects them), for the
// pbr fit: derived by hand, because automatic derivatives of this function (8 dual numbers per
// evaluation) were half the fit's time. microfacet_brdf_test.cc checks them against central
// differences of MicrofacetRadiance.
struct MicrofacetDerivatives {
  MicrofacetResponse<double> value;
  double diffuse_f0 = 0.0;          // d diffuse / d F0 (diffuse does not depend on roughness)
  double diffuse_normal[3] = {};    // d diffuse / d normal
  double specular_roughness = 0.0;  // d specular / d roughness
  double specular_f0 = 0.0;         // d specular / d F0
  double specular_normal[3] = {};   // d specular / d normal
};

// The terms of MicrofacetRadiance that depend on the light alone (the view is fixed at +z): a fit
// evaluates the same lights at many parameters, so it computes them once per light.
struct MicrofacetLight {
  double direction[3] = {0.0, 0.0, 1.0};  // unit, towards the light
  double halfway[3] = {0.0, 0.0, 1.0};    // h = (l + v) / |l + v|
  double schlick = 0.0;                   // Schlick's (1 - v.h)^5

  MicrofacetLight() = default;
  explicit MicrofacetLight(const double* light) {
    const double hz = light[2] + 1.0;
    const double h_norm = std::sqrt(light[0] * light[0] + light[1] * light[1] + hz * hz);
    for (int k = 0; k < 3; ++k) direction[k] = light[k];
    halfway[0] = light[0] / h_norm;
    halfway[1] = light[1] / h_norm;
    halfway[2] = hz / h_norm;
    const double m = 1.0 - halfway[2];
    schlick = m * m * m * m * m;
  }
};

// The terms that depend on the surface alone (normal, roughness, F0), once per evaluation of all
// of a pixel's lights.
struct MicrofacetSurface {
  const double* normal;  // unit
  double roughness, f0;
  double alpha2;     // alpha^2 = roughness^4
  double view_term;  // sqrt((n.v)^2 (1 - alpha^2) + alpha^2), V's term of the view

  MicrofacetSurface(const double* unit_normal, double perceptual_roughness, double grey_f0)
      : normal(unit_normal), roughness(perceptual_roughness), f0(grey_f0) {
    alpha2 = roughness * roughness * roughness * roughness;
    view_term = std::sqrt(normal[2] * normal[2] * (1.0 - alpha2) + alpha2);
  }
};

// The response of `surface` to `light`, with its derivatives only when `with_derivatives` (a
// trial step's cost needs the value alone).
inline MicrofacetDerivatives MicrofacetRadianceDerivatives(const MicrofacetSurface& surface,
                                                           const MicrofacetLight& light,
                                                           bool with_derivatives = true) {
  MicrofacetDerivatives out;
  const double* normal = surface.normal;
  const double* l = light.direction;
  const double* h = light.halfway;
  const double n_dot_l = normal[0] * l[0] + normal[1] * l[1] + normal[2] * l[2];
  const double n_dot_v = normal[2];
  if (!(n_dot_l > 0.0) || !(n_dot_v > 0.0)) {
    out.value = {0.0, 0.0};
    return out;
  }
  const double n_dot_h = normal[0] * h[0] + normal[1] * h[1] + normal[2] * h[2];
  const double alpha2 = surface.alpha2;
  const double d_denominator = n_dot_h * n_dot_h * (alpha2 - 1.0) + 1.0;
  const double pi = std::numbers::pi;
  const double distribution = alpha2 / (pi * d_denominator * d_denominator);
  const double a = surface.view_term;
  const double b = std::sqrt(n_dot_l * n_dot_l * (1.0 - alpha2) + alpha2);
  const double q = n_dot_l * a + n_dot_v * b;
  const double visibility = 0.5 / q;
  const double m5 = light.schlick;
  const double fresnel = surface.f0 + (1.0 - surface.f0) * m5;
  out.value = {(1.0 - fresnel) * n_dot_l, pi * fresnel * distribution * visibility * n_dot_l};
  if (!with_derivatives) return out;

  // F depends on F0 only (v and h are fixed by the light); D and V on alpha^2 and the normal.
  const double fresnel_f0 = 1.0 - m5;
  out.diffuse_f0 = -fresnel_f0 * n_dot_l;
  out.specular_f0 = pi * fresnel_f0 * distribution * visibility * n_dot_l;
  // dD / d alpha^2 and dD / d n.h.
  const double distribution_alpha2 = (1.0 - 2.0 * alpha2 * n_dot_h * n_dot_h / d_denominator) /
                                     (pi * d_denominator * d_denominator);
  const double distribution_n_dot_h =
      -4.0 * distribution * n_dot_h * (alpha2 - 1.0) / d_denominator;
  // V = 0.5 / q: dV = -V / q dq.
  const double q_alpha2 = n_dot_l * (1.0 - n_dot_v * n_dot_v) / (2.0 * a) +
                          n_dot_v * (1.0 - n_dot_l * n_dot_l) / (2.0 * b);
  const double q_n_dot_l = a + n_dot_v * n_dot_l * (1.0 - alpha2) / b;
  const double q_n_dot_v = n_dot_l * n_dot_v * (1.0 - alpha2) / a + b;
  const double visibility_alpha2 = -visibility / q * q_alpha2;
  const double roughness = surface.roughness;
  const double alpha2_roughness = 4.0 * roughness * roughness * roughness;
  out.specular_roughness = pi * fresnel * n_dot_l *
                           (distribution_alpha2 * visibility + distribution * visibility_alpha2) *
                           alpha2_roughness;
  for (int k = 0; k < 3; ++k) {
    const double v_k = k == 2 ? 1.0 : 0.0;  // d n.v / d n_k
    const double visibility_k = -visibility / q * (q_n_dot_l * l[k] + q_n_dot_v * v_k);
    out.diffuse_normal[k] = (1.0 - fresnel) * l[k];
    out.specular_normal[k] =
        pi * fresnel *
        (distribution_n_dot_h * h[k] * visibility * n_dot_l +
         distribution * visibility_k * n_dot_l + distribution * visibility * l[k]);
  }
  return out;
}

// The same for one `normal` (unit), `light` (unit), roughness and F0.
inline MicrofacetDerivatives MicrofacetRadianceDerivatives(const double* normal,
                                                           const double* light, double roughness,
                                                           double f0) {
  return MicrofacetRadianceDerivatives(MicrofacetSurface(normal, roughness, f0),
                                       MicrofacetLight(light));
}

}  // namespace photomat
