#include "plant.hpp"

#include <cmath>
#include <limits>

namespace gausstrack::plant_sim::detail {

const ModelFactory& find_model(const RunOptions& o, const std::string& name, const std::string& where) {
  for (const ModelFactory& f : o.models)
    if (f.name == name) return f;
  if (const ModelFactory* f = find_builtin_model(name)) return *f;
  std::string given;
  for (const ModelFactory& f : o.models) given += (given.empty() ? "" : ", ") + f.name;
  throw SceneError(where + ": unknown model '" + name + "' (compiled in: " + builtin_model_names() +
                   (given.empty() ? std::string() : "; given to this run: " + given) + ")");
}

Plant::Plant(const Scene& s, const RunOptions& o) : n_(s.dof()) {
  if (!s.plant_model.empty()) {
    model_ = find_model(o, s.plant_model, s.plant_model_where).plant(s.plant_parameters);
    if (model_->dof() != n_)
      throw SceneError(s.plant_model_where + ": model '" + s.plant_model + "' has " +
                       std::to_string(model_->dof()) + " coordinates, the plant lists " + std::to_string(n_));
  } else if (!s.masses.empty()) {
    mass_ = Eigen::Map<const V>(s.masses.data(), n_);
  }  // else an engine's plant: its physics are the engine's
  for (const EffectSpec& e : s.effects) {
    switch (e.kind) {
      case EffectKind::kActuatorSaturation: saturation_ = e; break;
      case EffectKind::kSensorNoise:
        noise_ = e;
        rng_.seed(e.seed);
        break;
      default: forces_.push_back(e);
    }
  }
  constraints_ = s.constraints;
  if (model_) model_rows_ = model_->physical_rows();
  const int p = constraint_rows();
  rows_.D.setZero(p, n_);
  rows_.g.setZero(p);
  rows_.e.setZero(p);
  rows_.e_rate.setZero(p);
  rows_.holonomic.assign(static_cast<std::size_t>(p), 0);
  for (int k = 0; k < p; ++k)
    rows_.holonomic[static_cast<std::size_t>(k)] =
        k < static_cast<int>(constraints_.size())
            ? constraints_[static_cast<std::size_t>(k)].kind == ConstraintKind::kPendulumLength
            : model_->physical_holonomic(k - static_cast<int>(constraints_.size()));
  A_.setZero(n_, n_);
  f_.setZero(n_);
  Q_.setZero(n_);
}

void Plant::applied_force(const V& q, const V& qd, double t, RunSummary& stats, V& Q) const {
  Q.setZero(n_);
  for (const EffectSpec& e : forces_) {
    ++stats.effect_evaluations[static_cast<std::size_t>(e.kind)];
    const double xb = e.b == kGround ? 0.0 : q(e.b), vb = e.b == kGround ? 0.0 : qd(e.b);
    const double d = q(e.a) - xb, dd = qd(e.a) - vb;
    double force_on_a = 0;  // force on coordinate a; b receives the opposite
    switch (e.kind) {
      case EffectKind::kGravity: Q(e.a) += mass_(e.a) * e.value; continue;
      case EffectKind::kDisturbance: Q(e.a) += e.value * std::sin(e.frequency * t + e.phase); continue;
      case EffectKind::kSpring: force_on_a = -e.value * d; break;
      case EffectKind::kCubicSpring: force_on_a = -e.value * d * d * d; break;
      case EffectKind::kDamper: force_on_a = -e.value * dd; break;
      default: continue;
    }
    Q(e.a) += force_on_a;
    if (e.b != kGround) Q(e.b) -= force_on_a;
  }
}

void Plant::saturate(V& u, RunSummary& stats) const {
  if (!saturation_) return;
  ++stats.effect_evaluations[static_cast<std::size_t>(EffectKind::kActuatorSaturation)];
  u = u.cwiseMax(-saturation_->value).cwiseMin(saturation_->value);
}

void Plant::measure(V& q, V& qd, RunSummary& stats) {
  if (!noise_) return;
  ++stats.effect_evaluations[static_cast<std::size_t>(EffectKind::kSensorNoise)];
  std::normal_distribution<double> nd(0.0, noise_->value);
  for (int i = 0; i < n_; ++i) {
    q(i) += nd(rng_);
    qd(i) += nd(rng_);
  }
}

void Plant::constraint_row(const ConstraintSpec& c, const Eigen::Ref<const V>& q, const Eigen::Ref<const V>& qd,
                    Eigen::RowVectorXd& D, double& g) const {
  D.setZero(n_);
  const auto& k = c.coordinates;
  if (c.kind == ConstraintKind::kPendulumLength) {
    // phi = x^2 + y^2 - L^2 + mu L^2 sin(x^2); D = grad phi; g = -q'^T Hess(phi) q'.
    const double x = q(k[0]), y = q(k[1]), xd = qd(k[0]), yd = qd(k[1]);
    const double l2mu = c.length * c.length * c.mu;
    D(k[0]) = 2 * x + 2 * l2mu * x * std::cos(x * x);
    D(k[1]) = 2 * y;
    const double hxx = 2 + 2 * l2mu * (std::cos(x * x) - 2 * x * x * std::sin(x * x));
    g = -(hxx * xd * xd + 2 * yd * yd);
  } else {
    // y' - z x' = 0 differentiated: y'' - z x'' = z' x'.
    D(k[0]) = -q(k[2]);
    D(k[1]) = 1;
    g = qd(k[2]) * qd(k[0]);
  }
}

void Plant::gather_rows(const V& q, const V& qd, double t) {
  const int listed = static_cast<int>(constraints_.size());
  for (int k = 0; k < listed; ++k) {
    const ConstraintSpec& c = constraints_[static_cast<std::size_t>(k)];
    constraint_row(c, q, qd, row_, rows_.g(k));
    rows_.D.row(k) = row_;
    // Each listed constraint has phi_t = 0 and psi = D q'.
    rows_.e(k) = c.kind == ConstraintKind::kPendulumLength ? position_residual(c, q) : 0.0;
    rows_.e_rate(k) = row_.dot(qd);
  }
  if (model_rows_ > 0) model_->physical(q, qd, t, listed, rows_.D, rows_.g, rows_.e, rows_.e_rate);
}

void Plant::acceleration(const V& q, const V& qd, double t, const V& u, RunSummary& stats, V& qdd) {
  V& rhs = force_;
  applied_force(q, qd, t, stats, rhs);
  rhs += u;
  if (model_) {
    model_->evaluate(q, qd, t, A_, f_, Q_);
    rhs += Q_ - f_;
  }
  const int p = constraint_rows();
  if (p == 0) {
    if (!model_) {
      qdd = rhs.cwiseQuotient(mass_);
      return;
    }
    llt_.compute(A_);
    if (llt_.info() != Eigen::Success) qdd.setConstant(n_, std::numeric_limits<double>::quiet_NaN());
    else qdd = llt_.solve(rhs);
    return;
  }
  kkt_.setZero(n_ + p, n_ + p);
  if (model_) kkt_.topLeftCorner(n_, n_) = A_;
  else kkt_.topLeftCorner(n_, n_).diagonal() = mass_;
  V& b = kkt_rhs_;
  b.resize(n_ + p);
  b.head(n_) = rhs;
  gather_rows(q, qd, t);
  kkt_.block(n_, 0, p, n_) = rows_.D;
  kkt_.block(0, n_, n_, p) = rows_.D.transpose();
  b.tail(p) = rows_.g;
  // Rank-revealing, so that a configuration where the rows lose rank still gives the
  // least-squares multipliers rather than a division by zero.
  kkt_solver_.compute(kkt_);
  kkt_solution_ = kkt_solver_.solve(b);
  qdd = kkt_solution_.head(n_);
}

bool Plant::project(Eigen::VectorXd& x, double t, RunSummary& stats) {
  if (!has_constraints() || !x.allFinite()) return x.allFinite();
  ++stats.projections;
  const int p = constraint_rows();
  M D(p, n_);
  V r(p);
  auto rows = [&](bool holonomic_only) {
    gather_rows(x.head(n_), x.tail(n_), t);
    for (int k = 0; k < p; ++k) {
      const bool holonomic = rows_.holonomic[static_cast<std::size_t>(k)] != 0;
      if (holonomic_only && !holonomic)
        D.row(k).setZero();
      else
        D.row(k) = rows_.D.row(k);
      r(k) = holonomic_only ? (holonomic ? rows_.e(k) : 0.0) : rows_.e_rate(k);
    }
  };
  Eigen::Ref<V> q = x.head(n_), qd = x.tail(n_);
  // W = A^-1 at the current q.
  M W;
  if (model_) {
    model_->evaluate(q, qd, t, A_, f_, Q_);
    llt_.compute(A_);
    if (llt_.info() != Eigen::Success) {
      x.setConstant(std::numeric_limits<double>::quiet_NaN());  // the run stops with its reason
      return false;
    }
    W = llt_.solve(M::Identity(n_, n_));
  } else {
    W = mass_.cwiseInverse().asDiagonal();
  }
  auto correction = [&]() -> V {
    const M DWDt = D * W * D.transpose();
    return W * D.transpose() * DWDt.completeOrthogonalDecomposition().solve(r);
  };
  for (int it = 0; it < 3; ++it) {
    rows(true);
    if (r.cwiseAbs().maxCoeff() == 0) break;
    q -= correction();
  }
  rows(false);
  qd -= correction();
  return x.allFinite();
}

double Plant::position_residual(const ConstraintSpec& c, const Eigen::Ref<const V>& q) {
  const auto& k = c.coordinates;
  const double x = q(k[0]), y = q(k[1]), L = c.length;
  return x * x + y * y - L * L * (1 - c.mu * std::sin(x * x));
}

double Plant::constraint_residual(const V& q, const V& qd, double t) {
  if (!has_constraints()) return 0.0;
  gather_rows(q, qd, t);
  double worst = 0;
  for (int k = 0; k < constraint_rows(); ++k) {
    const double r =
        rows_.holonomic[static_cast<std::size_t>(k)] != 0 ? rows_.e(k) : rows_.e_rate(k);
    if (std::abs(r) > std::abs(worst) || !std::isfinite(r)) worst = r;
  }
  return worst;
}

Control::Control(const Scene& s, const RunOptions& o) : actuators_(s.actuators()) {
  if (!s.tracking.enabled) return;
  const ModelFactory& model = find_model(o, s.tracking.model, s.tracking.where);
  if (model.dof != s.dof())
    throw SceneError(s.tracking.where + ": model '" + s.tracking.model + "' has " +
                     std::to_string(model.dof) + " coordinates, the plant has " +
                     std::to_string(s.dof()));
  // The law leaves the model's physical rows to the plant: a plant that does not hold them would
  // let the machine move where the law assumes it cannot (a wheel slipping sideways).
  if (model.physical_rows > 0) {
    const ModelFactory* plant =
        s.plant_model.empty() ? nullptr : &find_model(o, s.plant_model, s.plant_model_where);
    if (plant == nullptr || plant->physical_rows != model.physical_rows)
      throw SceneError(s.tracking.where + ": model '" + s.tracking.model + "' declares " +
                       std::to_string(model.physical_rows) +
                       " physical row(s), which the plant must hold: the plant's model "
                       "(plant.model) must declare "
                       "the same rows" +
                       (s.plant_model.empty() ? std::string(" (this plant has no model)")
                                              : " ('" + s.plant_model + "' declares " +
                                                    std::to_string(plant->physical_rows) + ")"));
  }
  // A plant driven through its own actuators holds u: the model's B must have one column each.
  if (s.actuators() > 0 && s.actuators() != model.actuators)
    throw SceneError(s.engine.where + ": the plant's actuators (plant.actuators) are " +
                     std::to_string(s.actuators()) + ", model '" + s.tracking.model + "' has " +
                     std::to_string(model.actuators) + ": the controller's u drives them one to one");
  if (o.sampled_control)
    error_ = model.tracking_error(s.tracking);
  else {
    // A sampled controller holds its force over the scene's control period.
    TrackingSpec spec = s.tracking;
    spec.period = s.control_mode == ControlMode::kSampled ? 1.0 / s.control_rate : 0.0;
    law_ = model.control_law(spec);
    if (law_->actuators() != model.actuators)
      throw SceneError(s.tracking.where + ": model '" + s.tracking.model + "' declares " +
                       std::to_string(model.actuators) + " actuators but its law has " +
                       std::to_string(law_->actuators()) + " (its ModelFactory's actuators is wrong)");
  }
}

void Control::force(const V& q, const V& qd, double t, RunSummary& stats, V& u) {
  u.setZero(q.size() + actuators_);
  if (!law_) return;
  ++stats.control_evaluations;
  if (failed(law_->compute(q.data(), qd.data(), t, u.data()))) {
    ++stats.control_failures;
    stats.warnings.add_failure();
    u.setZero();
    return;
  }
  stats.warnings.add(law_->warnings());
  if (actuators_ > 0) u.tail(actuators_) = Eigen::Map<const V>(law_->control(), actuators_);
}

double Control::tracking_error(const V& q, const V& qd, double t) const {
  if (error_) return error_(q.data(), qd.data(), t);
  return law_ ? law_->tracking_error(q.data(), qd.data(), t) : 0.0;
}

}  // namespace gausstrack::plant_sim::detail
