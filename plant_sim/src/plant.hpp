// The plant's physics (internal to plant_sim): the scene's point masses or model, the effects it
// lists, and its physical constraints, solved as a Lagrange-multiplier (KKT) system.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/QR>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "gausstrack/plant_sim/models.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::plant_sim::detail {

using V = Eigen::VectorXd;
using M = Eigen::MatrixXd;

/// The model of that name: one the run was given (RunOptions::models), else a compiled-in one.
/// Throws SceneError at `where` for an unknown name.
const ModelFactory& find_model(const RunOptions& o, const std::string& name, const std::string& where);

/// The plant assembled from exactly the scene's description: point masses or a model's own
/// dynamics, the effects listed and the physical constraints listed. Its constraint rows are
/// written here and solved as a Lagrange-multiplier (KKT) system, independently of the
/// controller's ConstraintSolver, so that plant and controller check each other.
class Plant {
 public:
  Plant(const Scene& s, const RunOptions& o);

  int dof() const { return n_; }
  /// Rows the plant holds: the scene's listed constraints, then its model's physical rows.
  int constraint_rows() const { return static_cast<int>(constraints_.size()) + model_rows_; }
  bool has_constraints() const { return constraint_rows() > 0; }

  /// Generalized impressed force Q(q, q', t) from the force effects listed, and nothing else.
  /// Every output is written into a vector the caller keeps: no allocation per evaluation,
  /// except in a constrained plant's KKT solve (Eigen's CompleteOrthogonalDecomposition::solve).
  void applied_force(const V& q, const V& qd, double t, RunSummary& stats, V& Q) const;
  /// Clamps u to the listed actuator saturation, if any.
  void saturate(V& u, RunSummary& stats) const;
  /// The state the controller measures: exact, or with the listed sensor noise.
  void measure(V& q, V& qd, RunSummary& stats);
  /// Eq. (31) by Lagrange multipliers: [A D^T; D 0] (q'', -lambda) = (Q + u - f, g).
  void acceleration(const V& q, const V& qd, double t, const V& u, RunSummary& stats, V& qdd);
  /// Projects a state x = (q, q') onto the constraint manifolds, by the least change in the
  /// metric of A (the mass-weighted projection): positions onto phi = 0 for the holonomic
  /// rows (Gauss-Newton, at most 3 steps), then velocities onto phi' = 0 and psi = 0 for all of
  /// them (both affine in q'). Returns false if the state is not finite.
  bool project(V& x, double t, RunSummary& stats);
  /// The physical constraint residual of largest magnitude (0 without constraints): phi for a
  /// position-level row, psi for a velocity-level one.
  double constraint_residual(const V& q, const V& qd, double t);

 private:
  // Every row the plant holds at (q, q', t), into rows_: D q'' = g, position error e (phi; 0 for
  // a velocity-level row), velocity error e' (phi' or psi), and which rows are holonomic.
  void gather_rows(const V& q, const V& qd, double t);
  // Constraint k's row: D_k q'' = g_k, with D_k = grad phi_k (or the Pfaffian row) and g_k the
  // rest of phi_k'' (or psi_k') moved to the right.
  void constraint_row(const ConstraintSpec& c, const Eigen::Ref<const V>& q, const Eigen::Ref<const V>& qd,
                      Eigen::RowVectorXd& D, double& g) const;
  static double position_residual(const ConstraintSpec& c, const Eigen::Ref<const V>& q);

  int n_;
  V mass_;
  std::unique_ptr<PlantModel> model_;
  M A_;
  V f_, Q_;
  std::vector<EffectSpec> forces_;
  std::optional<EffectSpec> saturation_, noise_;
  std::vector<ConstraintSpec> constraints_;
  int model_rows_ = 0;  // the model's physical rows
  struct Rows {
    M D;
    V g, e, e_rate;
    std::vector<char> holonomic;
  } rows_;
  std::mt19937_64 rng_;
  Eigen::LLT<M> llt_;
  M kkt_;
  Eigen::RowVectorXd row_;
  Eigen::CompleteOrthogonalDecomposition<M> kkt_solver_;
  V force_, kkt_rhs_, kkt_solution_;  // acceleration()'s work vectors, sized on first use
};

/// The scene's tracking controller (none without a tracking section), or, when the forces come
/// from elsewhere (a controller process), only the tracking error of the scene's model.
class Control {
 public:
  Control(const Scene& s, const RunOptions& o);
  /// u = the law's command at (q, q', t): its force, then (for a plant driven through its
  /// actuators, plant.actuators) its control; zero without a law or on failure.
  void force(const V& q, const V& qd, double t, RunSummary& stats, V& u);
  double tracking_error(const V& q, const V& qd, double t) const;

 private:
  std::unique_ptr<ControlLaw> law_;
  std::function<double(const double*, const double*, double)> error_;
  int actuators_ = 0;
};

}  // namespace gausstrack::plant_sim::detail
