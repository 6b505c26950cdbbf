#include "synthesize/surface/reaction_diffusion.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <numbers>

#include "core/error.h"
#include "core/random.h"

namespace photomat {
namespace {

void RequireSpecies(int species, int count) {
  if (species < 0 || species >= count) throw Error(fmt::format("no species {}", species));
}

class TurkModel final : public ReactionDiffusionModel {
 public:
  explicit TurkModel(const TurkParameters& p) : p_(p) {
    if (!(p.s > 0.0) || !(p.d_a >= 0.0) || !(p.d_b >= 0.0) || !(p.beta_noise >= 0.0)) {
      throw Error("turk: s must be positive and D_a, D_b, beta noise not negative");
    }
  }
  std::string name() const override { return "turk"; }
  std::vector<std::string> species_names() const override { return {"a", "b"}; }
  double diffusion(int species) const override {
    RequireSpecies(species, 2);
    return species == 0 ? p_.d_a : p_.d_b;
  }
  std::vector<Eigen::VectorXd> Initialize(const FemDomain& domain, std::uint64_t seed) override {
    const int n = domain.node_count();
    Random random(seed);
    beta_.resize(n);
    for (int i = 0; i < n; ++i)
      beta_[i] = random.Uniform(p_.beta - p_.beta_noise, p_.beta + p_.beta_noise);
    return {Eigen::VectorXd::Constant(n, 4.0), Eigen::VectorXd::Constant(n, 4.0)};
  }
  void Reaction(int species, const std::vector<Eigen::VectorXd>& f, double, Eigen::VectorXd& c2,
                Eigen::VectorXd& c3) const override {
    RequireSpecies(species, 2);
    if (species == 0) {
      c2 = -p_.s * f[1];
      c3 = Eigen::VectorXd::Constant(f[0].size(), 16.0 * p_.s);
    } else {
      c2 = p_.s * (f[0].array() - 1.0).matrix();
      c3 = -p_.s * beta_;
    }
  }
  void Project(std::vector<Eigen::VectorXd>& fields) const override {
    for (auto& f : fields) f = f.cwiseMax(0.0);
  }
  // b is the slow self-activator whose spots and stripes the paper shows; a mirrors it.
  int pattern_species() const override { return 1; }
  double suggested_time_step() const override { return 0.025 / p_.s; }

 private:
  TurkParameters p_;
  Eigen::VectorXd beta_;
};

class GrayScottModel final : public ReactionDiffusionModel {
 public:
  explicit GrayScottModel(const GrayScottParameters& p) : p_(p) {
    if (!(p.d_a >= 0.0) || !(p.d_b >= 0.0) || !(p.f >= 0.0) || !(p.k >= 0.0) ||
        !(p.seed_size > 0.0 && p.seed_size < 1.0) || p.seed_count < 1) {
      throw Error("gray-scott: D, F, K must not be negative and the seed size in (0, 1)");
    }
  }
  std::string name() const override { return "grayscott"; }
  std::vector<std::string> species_names() const override { return {"a", "b"}; }
  double diffusion(int species) const override {
    RequireSpecies(species, 2);
    return species == 0 ? p_.d_a : p_.d_b;
  }
  std::vector<Eigen::VectorXd> Initialize(const FemDomain& domain, std::uint64_t seed) override {
    const int n = domain.node_count();
    Random random(seed);
    Eigen::VectorXd a = Eigen::VectorXd::Ones(n), b = Eigen::VectorXd::Zero(n);
    auto perturb = [&](int i) {
      a[i] = random.Uniform(0.49, 0.51);
      b[i] = random.Uniform(0.24, 0.26);
    };
    const auto& positions = domain.node_positions();
    if (const auto& grid = domain.grid()) {
      // Pearson's central square, in grid cells as Ready places it.
      for (int y = 0; y < grid->height; ++y) {
        for (int x = 0; x < grid->width; ++x) {
          const double u = static_cast<double>(x) / grid->width;
          const double v = static_cast<double>(y) / grid->height;
          const double lo = 0.5 - p_.seed_size / 2, hi = 0.5 + p_.seed_size / 2;
          if (u >= lo && u <= hi && v >= lo && v <= hi) perturb(y * grid->width + x);
        }
      }
      return {a, b};
    }
    Eigen::Vector3d low = positions.front(), high = positions.front();
    for (const auto& p : positions) {
      low = low.cwiseMin(p);
      high = high.cwiseMax(p);
    }
    const double radius = p_.seed_size * (high - low).norm() / 2.0;
    for (int s = 0; s < p_.seed_count; ++s) {
      const Eigen::Vector3d centre = positions[random.Index(n)];
      for (int i = 0; i < n; ++i) {
        if ((positions[i] - centre).norm() <= radius) perturb(i);
      }
    }
    return {a, b};
  }
  void Reaction(int species, const std::vector<Eigen::VectorXd>& f, double, Eigen::VectorXd& c2,
                Eigen::VectorXd& c3) const override {
    RequireSpecies(species, 2);
    const auto& a = f[0].array();
    const auto& b = f[1].array();
    if (species == 0) {
      c2 = (-(b * b) - p_.f).matrix();
      c3 = Eigen::VectorXd::Constant(a.size(), p_.f);
    } else {
      c2 = (a * b - (p_.f + p_.k)).matrix();
      c3 = Eigen::VectorXd::Zero(a.size());
    }
  }
  int pattern_species() const override { return 1; }
  double suggested_time_step() const override { return 1.0; }

 private:
  GrayScottParameters p_;
};

class BrusselatorModel final : public ReactionDiffusionModel {
 public:
  explicit BrusselatorModel(const BrusselatorParameters& p) : p_(p) {
    if (!(p.c > 0.0) || !(p.d >= 0.0) || !(p.delta >= 0.0) || !(p.beta_noise >= 0.0)) {
      throw Error("brusselator: c must be positive and d, delta, beta noise not negative");
    }
  }
  std::string name() const override { return "brusselator"; }
  std::vector<std::string> species_names() const override { return {"u", "v"}; }
  double diffusion(int species) const override {
    RequireSpecies(species, 2);
    return species == 0 ? 1.0 : p_.delta;
  }
  std::vector<Eigen::VectorXd> Initialize(const FemDomain& domain, std::uint64_t seed) override {
    const int n = domain.node_count();
    Random random(seed);
    beta_.resize(n);
    for (int i = 0; i < n; ++i) beta_[i] = random.Uniform(-p_.beta_noise, p_.beta_noise);
    Eigen::VectorXd u = Eigen::VectorXd::Constant(n, p_.c) + beta_;
    return {u, Eigen::VectorXd::Constant(n, p_.d / p_.c)};
  }
  void Reaction(int species, const std::vector<Eigen::VectorXd>& f, double time,
                Eigen::VectorXd& c2, Eigen::VectorXd& c3) const override {
    RequireSpecies(species, 2);
    const auto& u = f[0].array();
    const auto& v = f[1].array();
    if (species == 0) {
      const double forcing = 1.0 + p_.gamma * std::cos(p_.omega * time);
      const double decay = p_.printed_form ? p_.d : p_.d + 1.0;
      c2 = (forcing * u * v - decay).matrix();
      c3 = (p_.c + beta_.array()).matrix();
    } else {
      c2 = (-(u * u)).matrix();
      c3 = (p_.d * u).matrix();
    }
  }
  double suggested_time_step() const override { return 0.05; }

 private:
  BrusselatorParameters p_;
  Eigen::VectorXd beta_;
};

class FitzHughNagumoModel final : public ReactionDiffusionModel {
 public:
  explicit FitzHughNagumoModel(const FitzHughNagumoParameters& p) : p_(p) {
    if (!(p.s > 0.0) || !(p.d_a >= 0.0) || !(p.d_b >= 0.0) || !(p.noise >= 0.0)) {
      throw Error("fhn: s must be positive and D_a, D_b, noise not negative");
    }
  }
  std::string name() const override { return "fhn"; }
  std::vector<std::string> species_names() const override { return {"a", "b"}; }
  double diffusion(int species) const override {
    RequireSpecies(species, 2);
    return species == 0 ? p_.d_a : p_.d_b;
  }
  std::vector<Eigen::VectorXd> Initialize(const FemDomain& domain, std::uint64_t seed) override {
    const int n = domain.node_count();
    Random random(seed);
    Eigen::VectorXd a(n);
    for (int i = 0; i < n; ++i) a[i] = random.Uniform(-p_.noise, p_.noise);
    return {a, Eigen::VectorXd::Zero(n)};
  }
  void Reaction(int species, const std::vector<Eigen::VectorXd>& f, double, Eigen::VectorXd& c2,
                Eigen::VectorXd& c3) const override {
    RequireSpecies(species, 2);
    if (species == 0) {
      c2 = (1.0 - f[0].array().square()).matrix();
      c3 = -f[1];
    } else {
      c2 = Eigen::VectorXd::Constant(f[1].size(), -p_.s * p_.s1);
      c3 = (p_.s * (f[0].array() - p_.s0)).matrix();
    }
  }
  double suggested_time_step() const override { return 0.2; }

 private:
  FitzHughNagumoParameters p_;
};

}  // namespace

std::unique_ptr<ReactionDiffusionModel> MakeTurkModel(const TurkParameters& parameters) {
  return std::make_unique<TurkModel>(parameters);
}
std::unique_ptr<ReactionDiffusionModel> MakeGrayScottModel(const GrayScottParameters& parameters) {
  return std::make_unique<GrayScottModel>(parameters);
}
std::unique_ptr<ReactionDiffusionModel> MakeBrusselatorModel(
    const BrusselatorParameters& parameters) {
  return std::make_unique<BrusselatorModel>(parameters);
}
std::unique_ptr<ReactionDiffusionModel> MakeFitzHughNagumoModel(
    const FitzHughNagumoParameters& parameters) {
  return std::make_unique<FitzHughNagumoModel>(parameters);
}

double TurkCriticalWavelength(double s) { return 2.0 * std::numbers::pi / std::sqrt(32.0 * s); }

std::vector<Eigen::Matrix3d> AnisotropicTensors(const FemDomain& domain,
                                                const Anisotropy& anisotropy) {
  if (!(anisotropy.along >= 0.0) || !(anisotropy.across >= 0.0) ||
      !(anisotropy.axis.norm() > 0.0)) {
    throw Error("anisotropy: diffusion factors must not be negative and the axis not zero");
  }
  const Eigen::Vector3d axis = anisotropy.axis.normalized();
  std::vector<Eigen::Matrix3d> tensors(domain.element_count());
  for (int e = 0; e < domain.element_count(); ++e) {
    const Eigen::Vector3d& n = domain.normal(e);
    Eigen::Vector3d t = anisotropy.field == DirectionField::kAlongAxis
                            ? (axis - axis.dot(n) * n).eval()
                            : axis.cross(n).eval();
    const Eigen::Matrix3d tangent_projection = Eigen::Matrix3d::Identity() - n * n.transpose();
    // Near the axis' poles the field has no direction; blend to isotropic there.
    const double strength = std::min(1.0, t.norm() / 0.2);
    if (t.norm() < 1e-9) {
      tensors[e] = 0.5 * (anisotropy.along + anisotropy.across) * tangent_projection;
      continue;
    }
    t.normalize();
    const Eigen::Vector3d w = n.cross(t);
    const Eigen::Matrix3d oriented =
        anisotropy.along * t * t.transpose() + anisotropy.across * w * w.transpose();
    tensors[e] = strength * oriented + (1.0 - strength) * 0.5 *
                                           (anisotropy.along + anisotropy.across) *
                                           tangent_projection;
  }
  return tensors;
}

ReactionDiffusionSystem::ReactionDiffusionSystem(ReactionDiffusionModel& model,
                                                 const FemOperators& operators,
                                                 const SimulationOptions& options)
    : model_(&model), operators_(&operators), options_(options) {
  if (!(options.time_step > 0.0)) {
    throw Error(fmt::format("time step must be positive, not {}", options.time_step));
  }
  fields_ = model.Initialize(operators.domain(), options.seed);
  BuildStiffness();
}

void ReactionDiffusionSystem::SetOperators(const FemOperators& operators) {
  if (operators.domain().node_count() != operators_->domain().node_count()) {
    throw Error("reaction-diffusion: the new domain has other nodes");
  }
  operators_ = &operators;
  BuildStiffness();
}

void ReactionDiffusionSystem::BuildStiffness() {
  anisotropic_stiffness_.reset();
  if (options_.anisotropy) {
    anisotropic_stiffness_ =
        operators_->TensorStiffness(AnisotropicTensors(operators_->domain(), *options_.anisotropy));
  }
}

StepRecord ReactionDiffusionSystem::Step() {
  const int species = static_cast<int>(fields_.size());
  const double tau = options_.time_step;
  std::vector<Eigen::VectorXd> next = fields_;
  std::vector<StepReport> reports(species);
  // Jacobi: every species' coefficients from step n. Gauss-Seidel: from the newest fields, so a
  // later species sees the earlier ones at step n+1.
  const bool gauss_seidel = options_.ordering == SpeciesOrdering::kGaussSeidel;
  auto solve = [&](int s) {
    GeneralEquation equation;
    equation.c0 = Eigen::VectorXd::Constant(1, model_->diffusion(s));
    if (anisotropic_stiffness_) equation.c1_stiffness = &*anisotropic_stiffness_;
    model_->Reaction(s, gauss_seidel ? next : fields_, time_, equation.c2, equation.c3);
    reports[s] = SemiImplicitStep(*operators_, equation, tau, options_.solver, next[s]);
  };
  if (options_.parallel_species && !gauss_seidel) {
    tbb::parallel_for(0, species, solve);
  } else {
    for (int s = 0; s < species; ++s) solve(s);
  }
  StepRecord record;
  model_->Project(next);
  const Eigen::VectorXd& mass = operators_->lumped_mass_vector();
  for (int s = 0; s < species; ++s) {
    const Eigen::VectorXd rate = (next[s] - fields_[s]) / tau;
    record.max_rate = std::max(record.max_rate, rate.cwiseAbs().maxCoeff());
    record.rms_rate = std::max(record.rms_rate, std::sqrt(mass.dot(rate.cwiseAbs2()) / mass.sum()));
    record.iterations.push_back(reports[s].iterations);
  }
  fields_ = std::move(next);
  time_ += tau;
  record.step = ++steps_;
  record.time = time_;
  return record;
}

bool SettlingMonitor::Update(const StepRecord& record) {
  if (!(options_.settle_rate > 0.0)) return false;
  if (record.rms_rate > 5.0 * options_.settle_rate) grown_ = true;
  return grown_ && record.step >= options_.min_steps && record.rms_rate < options_.settle_rate;
}

SimulationResult SimulateReactionDiffusion(ReactionDiffusionModel& model, const FemDomain& domain,
                                           const SimulationOptions& options, Progress* progress) {
  NullProgress null;
  Progress& report = OrNull(progress, null);
  const FemOperators operators(domain);
  ReactionDiffusionSystem system(model, operators, options);
  SimulationResult result;
  SettlingMonitor monitor(options);
  report.Start(fmt::format("{} reaction-diffusion", model.name()), options.max_steps);
  for (int step = 0; step < options.max_steps; ++step) {
    StepRecord record = system.Step();
    for (int i : record.iterations) result.total_iterations += i;
    const bool settled = monitor.Update(record);
    result.history.push_back(std::move(record));
    report.Advance();
    if (settled) {
      result.settled = true;
      break;
    }
  }
  report.Finish();
  result.fields = system.fields();
  result.steps = system.steps();
  result.time = system.time();
  return result;
}

}  // namespace photomat
