#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/progress.h"
#include "synthesize/surface/fem.h"
#include "synthesize/surface/semi_implicit.h"

namespace photomat {

// Two-species reaction-diffusion models as instances of the general equation (semi_implicit.h):
// for each species the diffusion constant (C0 with C1 = 1, or times an anisotropic tensor) and the
// linearised reaction C2 u + C3 evaluated at step n (the coefficient table of Bajaj, Zhang and Xu,
// Fig. 2, with the sign errors of their divided forms corrected as in the spec, 3.1).
class ReactionDiffusionModel {
 public:
  virtual ~ReactionDiffusionModel() = default;
  virtual std::string name() const = 0;
  virtual std::vector<std::string> species_names() const = 0;
  // Diffusion constant of each species (C0; may be 0).
  virtual double diffusion(int species) const = 0;
  // The initial fields on `domain`, drawing every random choice from `seed`. Models with random
  // per-node parameters (Turk's beta) draw them here and keep them for Reaction().
  virtual std::vector<Eigen::VectorXd> Initialize(const FemDomain& domain, std::uint64_t seed) = 0;
  // C2 and C3 of `species` at every node from the fields at step n and time t.
  virtual void Reaction(int species, const std::vector<Eigen::VectorXd>& fields, double time,
                        Eigen::VectorXd& c2, Eigen::VectorXd& c3) const = 0;
  // Applied to the fields after every step: keeps concentrations in the model's domain (Turk's
  // clamp of b at 0). Default: nothing.
  virtual void Project(std::vector<Eigen::VectorXd>& /*fields*/) const {}
  // The field that shows the pattern (for colours, height fields and stopping).
  virtual int pattern_species() const { return 0; }
  // Longest stable time step for these parameters (a suggestion; the CLI's default).
  virtual double suggested_time_step() const = 0;
};

// Turk (1991), spec 3.1:
//   da/dt = s (16 - a b) + D_a lap a      C0 = D_a, C2 = -s b,        C3 = 16 s
//   db/dt = s (a b - b - beta) + D_b lap b C0 = D_b, C2 = s (a - 1),  C3 = -s beta
// beta is drawn per node uniformly from [beta - beta_noise, beta + beta_noise] (the paper's
// "12 +- 0.1", the only randomness); a = b = 4, the homogeneous equilibrium at beta = 12. The
// Turing wavelength is 2 pi / sqrt(32 s). Concentrations are clamped at 0 after each step, as in
// Turk's own simulation: the spec's equations alone let b cross zero inside a growing spot, after
// which a b < 0 feeds a without bound (seen here within 300 time units at s = 0.05).
// The Jacobi-ordered semi-implicit step keeps the homogeneous state stable only for
// tau s < 1/28 (its amplification at a = b = 4 is sqrt((1 + 16 x^2) / ((1 + 4x)(1 - 3x))) with
// x = tau s); the suggested step is tau s = 0.025 (the spec's tau = 0.5 at s = 0.05).
struct TurkParameters {
  double s = 0.05;
  double d_a = 0.125;
  double d_b = 0.03125;
  double beta = 12.0;
  double beta_noise = 0.1;
};
std::unique_ptr<ReactionDiffusionModel> MakeTurkModel(const TurkParameters& parameters);
// 2 pi / sqrt(32 s) (spec 3.1, linear stability at a = b = 4).
double TurkCriticalWavelength(double s);

// Gray-Scott as Pearson (1993) and Ready write it (a = U, b = V):
//   da/dt = D_a lap a - a b^2 + F (1 - a)   C2 = -(b^2 + F), C3 = F
//   db/dt = D_b lap b + a b^2 - (F + K) b   C2 = a b - (F + K), C3 = 0
// Pearson's set-up: a = 1, b = 0, except a square of side `seed_size` (fraction of the domain;
// 0.08 is Pearson's 20 x 20 of 256) at the centre with a in [0.49, 0.51] and b in [0.24, 0.26].
// On a mesh (no centre) `seed_count` squares' worth of such patches are placed at random vertices,
// each a ball of radius seed_size * bounding-box diagonal / 2.
struct GrayScottParameters {
  double d_a = 2e-5;
  double d_b = 1e-5;
  double f = 0.040;
  double k = 0.060;
  double seed_size = 0.08;
  int seed_count = 8;
};
std::unique_ptr<ReactionDiffusionModel> MakeGrayScottModel(const GrayScottParameters& parameters);

// The periodically forced Brusselator (Lin et al., Phys. Rev. E 2000; spec 3.3):
//   du/dt = c + beta - (d + 1) u + (1 + gamma cos(omega t)) u^2 v + lap u
//   dv/dt = d u - u^2 v + delta lap v
// (standard form, default) or, with `printed_form`, the paper's -d u in the first equation (whose
// u + v grows without bound, spec 3.3). beta is per-node noise in [-beta_noise, beta_noise].
// u starts at c, v at d / c (the unforced equilibrium), plus the noise.
struct BrusselatorParameters {
  double c = 0.5;
  double d = 1.5;
  double omega = 1.69;
  double gamma = 0.1;
  double delta = 1.0;
  double beta_noise = 0.1;
  bool printed_form = false;
};
std::unique_ptr<ReactionDiffusionModel> MakeBrusselatorModel(
    const BrusselatorParameters& parameters);

// FitzHugh-Nagumo variant (spec 3.2): F(a, b) = a - a^3 - b, G(a, b) = s (a - s1 b - s0):
//   da/dt = D_a lap a + a - a^3 - b   C2 = 1 - a^2, C3 = -b
//   db/dt = D_b lap b + s (a - s1 b - s0) C2 = -s s1, C3 = s (a - s0)
// The paper's caption repeats Turk's constants, with which this model cannot form a Turing pattern
// (the inhibitor b would have to diffuse faster, spec 3.2). IMPLEMENTER CHOICE: s = 3, s1 = 0.5,
// s0 = 0 make a = b = 0 the only rest state, stable without diffusion (trace -0.5, determinant
// 1.5); with the inhibitor 20x faster (D_b / D_a above the Turing threshold 8.7) it forms
// patterns of wavelength 2 pi / (1.5 / (D_a D_b))^(1/4) = 5.4 at the defaults. Starts from
// uniform noise of +-`noise` around rest. C2 = 1 - a^2 limits the step to tau < 1.
struct FitzHughNagumoParameters {
  double s = 3.0;
  double s0 = 0.0;
  double s1 = 0.5;
  double d_a = 0.2;
  double d_b = 4.0;
  double noise = 0.05;
};
std::unique_ptr<ReactionDiffusionModel> MakeFitzHughNagumoModel(
    const FitzHughNagumoParameters& parameters);

// Anisotropic diffusion along a direction field, for stripes that follow the surface: every
// species diffuses with C1 = `along` t t^T + `across` (n x t)(n x t)^T on each element, t the unit
// tangent of the field. Where the field has no tangential part (the poles of an axis), C1 is the
// isotropic mean.
enum class DirectionField {
  kAlongAxis,   // t = the axis projected onto the element's plane (meridians)
  kAroundAxis,  // t = axis x n (parallels: rings around the axis)
};
struct Anisotropy {
  DirectionField field = DirectionField::kAroundAxis;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitY();
  double along = 1.0;
  double across = 0.1;
};
// One C1 tensor per element of `domain`.
std::vector<Eigen::Matrix3d> AnisotropicTensors(const FemDomain& domain,
                                                const Anisotropy& anisotropy);

// Which fields a species' coefficients C2, C3 see within a step (spec 3.1).
enum class SpeciesOrdering {
  kJacobi,       // all at step n (the paper's scheme; species solved in parallel)
  kGaussSeidel,  // species s sees species < s at step n+1 (one after the other)
};

struct SimulationOptions {
  double time_step = 1.0;
  int max_steps = 1000;
  // Stop when the root-mean-square rate of change |u^{n+1} - u^n| / tau (area-weighted over the
  // nodes, the larger of the species) falls below this: the paper's "until a and b achieve their
  // stable states" (spec 3.1). IMPLEMENTER CHOICE: the mean rather than the maximum, because on a
  // large surface some spot is always still shifting a little (the bunny's max rate stays near
  // 0.01-0.03 for thousands of steps after the pattern has formed). The rate must first have
  // risen above 5 x settle_rate (the pattern's growth): before a pattern forms the fields also
  // change slowly, which is not a stable state. 0: run max_steps.
  double settle_rate = 0.0;
  // Steps before the stopping test starts (the pattern grows slowly from a near-uniform state).
  int min_steps = 0;
  // IMPLEMENTER CHOICE: CG to a relative residual of 1e-6. A step changes the fields by about
  // 1e-3 of their size, so this solves each step's change to about 1e-3; Turk on the bunny
  // settles at the same step as with 1e-8 (2,291 against 2,290) with half the iterations.
  SolverOptions solver = {1e-6, 1000, Preconditioner::kJacobi, false};
  std::uint64_t seed = 1;
  std::optional<Anisotropy> anisotropy;
  // The Jacobi step keeps Turk's homogeneous state stable for tau s < 1/28, Gauss-Seidel (a
  // first, then b with the new a) for tau s < 1/12: the latter allows a 2-3x longer step.
  SpeciesOrdering ordering = SpeciesOrdering::kJacobi;
  // Solve the species of one step in parallel (Jacobi ordering makes them independent; results
  // are identical either way).
  bool parallel_species = true;
};

struct StepRecord {
  int step = 0;
  double time = 0.0;
  double max_rate = 0.0;        // max |u^{n+1} - u^n| / tau
  double rms_rate = 0.0;        // its area-weighted root mean square (the larger species)
  std::vector<int> iterations;  // conjugate-gradient iterations per species
};

struct SimulationResult {
  std::vector<Eigen::VectorXd> fields;
  int steps = 0;
  double time = 0.0;
  bool settled = false;
  long long total_iterations = 0;
  std::vector<StepRecord> history;
};

// The stopping rule of SimulationOptions::settle_rate, fed one step at a time.
class SettlingMonitor {
 public:
  explicit SettlingMonitor(const SimulationOptions& options) : options_(options) {}
  // True when the run has settled after this step.
  bool Update(const StepRecord& record);

 private:
  SimulationOptions options_;
  bool grown_ = false;
};

// A reaction-diffusion state on one domain, advanced step by step (the coupled loop of
// geometric_diffusion.h swaps the domain between steps).
class ReactionDiffusionSystem {
 public:
  // Initialises `model` on `operators`' domain (the operators must outlive the system).
  ReactionDiffusionSystem(ReactionDiffusionModel& model, const FemOperators& operators,
                          const SimulationOptions& options);
  // Moves the state to other operators with the same nodes (a smoothed mesh).
  void SetOperators(const FemOperators& operators);
  // One semi-implicit step of every species (Jacobi ordering: all species see step n).
  StepRecord Step();
  const std::vector<Eigen::VectorXd>& fields() const { return fields_; }
  double time() const { return time_; }
  int steps() const { return steps_; }

 private:
  void BuildStiffness();

  ReactionDiffusionModel* model_;
  const FemOperators* operators_;
  SimulationOptions options_;
  std::vector<Eigen::VectorXd> fields_;
  std::optional<SparseMatrixD> anisotropic_stiffness_;
  double time_ = 0.0;
  int steps_ = 0;
};

// Runs `model` on `domain` until it settles or max_steps, reporting each step to `progress`.
SimulationResult SimulateReactionDiffusion(ReactionDiffusionModel& model, const FemDomain& domain,
                                           const SimulationOptions& options,
                                           Progress* progress = nullptr);

}  // namespace photomat
