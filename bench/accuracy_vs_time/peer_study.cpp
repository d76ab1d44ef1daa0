// The peer part of accuracy_vs_time (study.cpp): the Duffing tracking task integrated by odeint and
// by SUNDIALS ARKODE's explicit RK at equal tolerances (peer.csv). A unit of its own, so that
// neither it nor study.cpp compiles above 1.5 GB.
#ifdef GAUSSTRACK_HAVE_ARKODE
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#endif

#include <Eigen/Core>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <string>

#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/tracking_controller.hpp"
#include "study.hpp"

namespace gausstrack::study {
namespace {

namespace odeint = boost::numeric::odeint;

// The Duffing tracking task as one ODE: plant x'' = A^-1 (Q' - f) with Q' from the library.
struct DuffingTask {
  TrackingController<systems::CoupledDuffing<double>> controller;
  TrackingController<systems::CoupledDuffing<double>>::Output out;
  long evaluations = 0;
  explicit DuffingTask(double alpha) : controller(make_model(alpha)) {}
  static systems::CoupledDuffing<double> make_model(double alpha) {
    systems::CoupledDuffing<double> m;
    m.trajectory.alpha = alpha;
    return m;
  }
  void rhs(const double* x, double* dx, double t) {
    ++evaluations;
    const auto& model = controller.model();
    const Eigen::Vector2d q(x[0], x[1]), qd(x[2], x[3]);
    controller.compute(q, qd, t, out);
    const Eigen::Vector2d f = model.spring_damper_force(q, qd);
    dx[0] = x[2];
    dx[1] = x[3];
    dx[2] = (out.force(0) - f(0)) / model.m1;
    dx[3] = (out.force(1) - f(1)) / model.m2;
  }
  Eigen::Vector4d initial() const { return {1.0, 1.0, controller.model().consistent_x1_velocity(2.0), 2.0}; }
};

#ifdef GAUSSTRACK_HAVE_ARKODE
int arkode_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void* user) {
  static_cast<DuffingTask*>(user)->rhs(N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), t);
  return 0;
}
#endif

struct PeerResult {
  Eigen::Vector4d final;
  long evaluations;
  double wall_s;
};

PeerResult run_odeint(const char* method, double tol, double alpha, double duration) {
  DuffingTask task(alpha);
  using V = Eigen::Vector4d;
  V x = task.initial();
  auto rhs = [&](const V& s, V& ds, double t) { task.rhs(s.data(), ds.data(), t); };
  const auto t0 = std::chrono::steady_clock::now();
  using Dopri = odeint::runge_kutta_dopri5<V, double, V, double, odeint::vector_space_algebra>;
  using Rkf = odeint::runge_kutta_fehlberg78<V, double, V, double, odeint::vector_space_algebra>;
  if (std::string(method) == "dopri5")
    odeint::integrate_adaptive(odeint::make_controlled(tol, tol, Dopri()), rhs, x, 0.0, duration, 1e-3);
  else
    odeint::integrate_adaptive(odeint::make_controlled(tol, tol, Rkf()), rhs, x, 0.0, duration, 1e-3);
  return {x, task.evaluations, seconds_since(t0)};
}

#ifdef GAUSSTRACK_HAVE_ARKODE
PeerResult run_arkode(ARKODE_ERKTableID table, double tol, double alpha, double duration) {
  DuffingTask task(alpha);
  SUNContext ctx = nullptr;
  SUNContext_Create(nullptr, &ctx);
  N_Vector y = N_VNew_Serial(4, ctx);
  const Eigen::Vector4d x0 = task.initial();
  for (int i = 0; i < 4; ++i) N_VGetArrayPointer(y)[i] = x0(i);
  const auto t0 = std::chrono::steady_clock::now();
  void* mem = ERKStepCreate(arkode_rhs, 0.0, y, ctx);
  ERKStepSetUserData(mem, &task);
  ERKStepSStolerances(mem, tol, tol);
  ERKStepSetTableNum(mem, table);
  ERKStepSetMaxNumSteps(mem, 100000000);
  sunrealtype t = 0;
  ERKStepSetStopTime(mem, duration);
  const int flag = ERKStepEvolve(mem, duration, y, &t, ARK_NORMAL);
  const double wall = seconds_since(t0);
  PeerResult r{Eigen::Map<Eigen::Vector4d>(N_VGetArrayPointer(y)), task.evaluations, wall};
  if (flag < 0) r.final.setConstant(std::nan(""));
  ERKStepFree(&mem);
  N_VDestroy(y);
  SUNContext_Free(&ctx);
  return r;
}
#endif

}  // namespace

void peer(std::ofstream& csv, bool quick) {
  csv << "integrator,tolerance,rhs_evaluations,wall_s,final_error\n";
  const double alpha = 0.4, duration = quick ? 1.0 : 10.0;
  const PeerResult ref = run_odeint("rkf78", 1e-14, alpha, duration);
  for (int e = 4; e <= 13; ++e) {
    if (quick && e % 4 != 0) continue;
    const double tol = std::pow(10.0, -e);
#ifdef GAUSSTRACK_HAVE_ARKODE
    const PeerResult runs[] = {
        run_odeint("dopri5", tol, alpha, duration), run_arkode(ARKODE_DORMAND_PRINCE_7_4_5, tol, alpha, duration),
        run_odeint("rkf78", tol, alpha, duration), run_arkode(ARKODE_FEHLBERG_13_7_8, tol, alpha, duration)};
    const char* names[] = {"odeint dopri5", "arkode dormand_prince_7_4_5", "odeint rkf78", "arkode fehlberg_13_7_8"};
#else
    const PeerResult runs[] = {run_odeint("dopri5", tol, alpha, duration), run_odeint("rkf78", tol, alpha, duration)};
    const char* names[] = {"odeint dopri5", "odeint rkf78"};
#endif
    for (std::size_t k = 0; k < std::size(runs); ++k) {
      char line[256];
      std::snprintf(line, sizeof line, "%s,%g,%ld,%.6g,%.6g\n", names[k], tol, runs[k].evaluations, runs[k].wall_s,
                    (runs[k].final - ref.final).cwiseAbs().maxCoeff());
      csv << line;
    }
  }
#ifdef GAUSSTRACK_HAVE_ARKODE
  std::printf("  peer: odeint and ARKODE on the Duffing task\n");
#else
  std::printf("  peer: odeint only; SUNDIALS ARKODE is not installed (GAUSSTRACK_PEER_STUDY=1 scripts/setup "
              "installs it; scripts/bench does)\n");
#endif
}

}  // namespace gausstrack::study
