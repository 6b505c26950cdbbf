#ifndef PHOTOMAT_BENCH_HELD_OUT_DIAGNOSES_H_
#define PHOTOMAT_BENCH_HELD_OUT_DIAGNOSES_H_

// Diagnoses beside the held-out-lights benchmark (bench/held_out_lights.cc, issue 19): what the
// held-out lights themselves would choose, and choices photomat's fit does not offer. They print
// figures for the README ("Relighting held-out lights against relight-cli") and never choose
// anything for the fit.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/light_direction.h"
#include "represent/fitting/light_profile_fit.h"
#include "represent/fitting/observations.h"

namespace photomat {

// Lights held out of a fit (`held_out`) and the ones fitted (`selected`), as indices into the set.
struct HoldOut {
  std::string name;
  std::vector<int> held_out, selected;
};

std::vector<LightDirection> LightsOf(const std::vector<LightDirection>& lights,
                                     const std::vector<int>& indices);

// Interpolation weights (targets x nodes) of the rbf and bilinear bases: a target light's
// predicted profile is its row times the nodes' values.
Eigen::MatrixXd RbfWeights(const std::vector<LightDirection>& nodes,
                           const std::vector<LightDirection>& targets, double width_degrees,
                           double regularisation, RbfTail tail = RbfTail::kAffine);

Eigen::MatrixXd BilinearWeights(const std::vector<LightDirection>& nodes,
                                const std::vector<LightDirection>& targets, int grid_size,
                                double smoothness);

// Weights (targets x nodes) of polyharmonic spline interpolation over light directions:
// f(l) = sum_i a_i phi(|l - l_i|) + (1, lx, ly, lz) . b, phi(r) = r (order 1), r^2 log r (2,
// the thin-plate spline) or r^3 (3), |.| the chord as the rbf method's Gaussian; the coefficients
// solve [Phi + lambda I, T; T^T, 0] [a; b] = [profile; 0]. No width: the kernels have no scale.
Eigen::MatrixXd PolyharmonicWeights(const std::vector<LightDirection>& nodes,
                                    const std::vector<LightDirection>& targets, int order,
                                    double regularisation);

// --clamped-score: rbf's width, regularisation and plane count (4, 6, 9, 16) chosen by a
// leave-block-out score over the training lights that clamps the prediction to [0, peak] as the
// benchmark's PSNR does (a pass over the pixels per fold and candidate, which the fit's
// Gram-matrix score avoids); prints each candidate's score and held-out PSNR, and the choice's.
void PrintClampedScores(const Observations& observations, const std::vector<LightDirection>& lights,
                        const HoldOut& hold_out, double peak);

// --blend: w(l) = a w_rbf(l) + (1 - a) w_bilinear(l), a in {0, 0.25, .., 1}, each part's
// settings among the fit's candidates, all chosen together by each training-light score
// (leave-one-out, leave-edge-out, leave-block-out; 9 planes); the held-out PSNR of each a's choice
// and of the joint choice (clamped, as the table), and separately labelled, the held-out lights'
// own best a for the chosen parts (oracle, never a choice).
void PrintBlend(const Observations& observations, const std::vector<LightDirection>& lights,
                const HoldOut& hold_out, double peak, const LightProfileOptions& profile);

// Polyharmonic splines in place of the rbf method's Gaussian (diagnosis, never a choice of the
// fit): their held-out PSNR (clamped as the table) per order, regularisation and plane count;
// the candidate each training-light score picks among them and the fit's Gaussian candidates;
// and for leave-side-out the cubic's score of each side (4 planes).
void PrintPolyharmonic(const Observations& observations, const std::vector<LightDirection>& lights,
                       const HoldOut& hold_out, double peak);

// --oracle: what the held-out lights themselves would choose (never used to choose; it shows how
// far the training lights' choice is from the best available). The mean held-out PSNR of every
// rbf and bilinear candidate and plane count, from the Gram matrix of every light (the PCA over
// the training lights, the interpolation's weights from them), without the fit's clamp to
// [0, peak].
void PrintOracle(const Observations& observations, const std::vector<LightDirection>& lights,
                 const HoldOut& hold_out, double peak, int grid_size);

}  // namespace photomat

#endif  // PHOTOMAT_BENCH_HELD_OUT_DIAGNOSES_H_
