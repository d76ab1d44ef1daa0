// accuracy_vs_time SCENE_DIR OUT_DIR [--quick]
// What accuracy costs in time. Each section measures error against cost and writes one CSV into
// OUT_DIR; report_study.py turns them into Markdown work-precision tables, plots and the Pareto
// front.
//   integrators.csv  every scene of plant_sim's own (SCENE_DIR/*.yaml) with RK4 at steps
//                    1e-2..1e-5, and Dormand-Prince 5(4), Fehlberg 7(8) and Bulirsch-Stoer at
//                    tolerances 1e-4..1e-13 (odeint), sampled at 11 sparse times so that no step
//                    is cut by the output grid, against a reference from two methods at 1e-14
//                    (Fehlberg 7(8) and Bulirsch-Stoer; their difference is reported) and, where
//                    one exists, an independent formulation: the angle-coordinate pendulum, the
//                    minimal-coordinate Duffing oscillator (x2 alone; x1 = x2 + s(t)).
//   peer.csv         the Duffing tracking task (law and plant in one right-hand side) integrated
//                    by odeint and by SUNDIALS ARKODE's explicit RK (same tableaux) at equal
//                    tolerances, against a reference at 1e-14.
//   strategies.csv   generalized-inverse strategies and damping on normal, near-singular and
//                    redundant constraint sets: force error against a manufactured exact
//                    solution, constraint residual, cost per call.
//   control_rate.csv the Duffing task with sampled-and-held control at 100 Hz..10 kHz, with and
//                    without stabilization.
//   stabilization.csv stabilization gains at 1 kHz, exact model and a plant whose k1 is 10% high.
// --quick runs a token subset (for CI).
#include <CLI/CLI.hpp>

#include <Eigen/Dense>
#include <boost/numeric/odeint.hpp>
#include <boost/numeric/odeint/external/eigen/eigen.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "gausstrack/constraint_solver.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"
#include "pendulum_angle_model.hpp"
#include "study.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"

namespace {

namespace odeint = boost::numeric::odeint;
namespace fs = std::filesystem;
using namespace gausstrack;
using plant_sim::Method;
using plant_sim::RunResult;
using plant_sim::Scene;
using study::seconds_since;

// Largest |q - q_ref| over the samples, and at the final sample.
std::pair<double, double> trajectory_error(const RunResult& run, const RunResult& ref) {
  double worst = 0, final = 0;
  const std::size_t n = std::min(run.samples.size(), ref.samples.size());
  for (std::size_t k = 0; k < n; ++k) {
    double e = 0;
    for (std::size_t i = 0; i < run.samples[k].q.size(); ++i)
      e = std::max(e, std::abs(run.samples[k].q[i] - ref.samples[k].q[i]));
    worst = std::max(worst, e);
    if (k + 1 == n) final = e;
  }
  return {worst, final};
}

// The Duffing oscillator held on x1 - x2 = s(t) has one degree of freedom. Adding eqs. (35a) and
// (35b), the constraint forces cancel (Q'_1 = -Q'_2):
//   (m1 + m2) x2'' = -(k2 x2 + c2 x2' + kb2 x2^3) - m1 s''(t),   x1 = x2 + s(t).
// Returns the largest |q - q_minimal| over the run's samples.
double minimal_coordinate_difference(const Scene& s, const RunResult& run) {
  systems::CoupledDuffing<double> tr;
  plant_sim::apply_parameters(tr, s.tracking.parameters, s.tracking.model);
  const systems::DecayingSine<double>& sine = tr.trajectory;
  using S2 = Eigen::Vector2d;
  auto rhs = [&](const S2& z, S2& dz, double t) {
    dz << z(1), (-(tr.k2 * z(0) + tr.c2 * z(1) + tr.kb2 * z(0) * z(0) * z(0)) - tr.m1 * sine.acceleration(t)) /
                    (tr.m1 + tr.m2);
  };
  using D = odeint::runge_kutta_dopri5<S2, double, S2, double, odeint::vector_space_algebra>;
  auto stepper = odeint::make_dense_output(1e-14, 1e-14, D());
  stepper.initialize(S2(s.q0[1], s.qd0[1]), 0.0, 1e-4);
  double worst = 0;
  for (const auto& smp : run.samples) {
    while (stepper.current_time() < smp.t) stepper.do_step(rhs);
    S2 z(s.q0[1], s.qd0[1]);
    if (smp.t > 0) stepper.calc_state(smp.t, z);
    worst = std::max({worst, std::abs(smp.q[1] - z(0)), std::abs(smp.q[0] - z(0) - sine.position(smp.t))});
  }
  return worst;
}

// Every method's cost must follow its tolerance: the runs sample the state at 11 sparse times
// (every tenth of the duration), so no step is cut by the output grid (dopri5 and Bulirsch-Stoer
// interpolate with dense output; rkf78 ends a step on each of those 10 times only). The
// reference is two computations that agree: Fehlberg 7(8) and Bulirsch-Stoer, both at 1e-14
// (tighter than any measured run; their largest difference is the reference's own uncertainty,
// written as the method "reference_uncertainty"), the error measured against their mean; and,
// where one exists, an independent formulation (the angle-coordinate pendulum, the
// minimal-coordinate Duffing oscillator), whose difference each row reports beside it.
void integrators(const std::vector<fs::path>& scenes, std::ofstream& csv, bool quick) {
  csv << "scene,method,setting,rhs_evaluations,wall_s,max_error,final_error,independent_difference,"
         "max_tracking_error,max_constraint_residual\n";
  for (const fs::path& path : scenes) {
    Scene base = plant_sim::load_scene(path.string());
    if (!base.engine.name.empty()) continue;  // an engine's plant is studied by mujoco_study
    if (quick) base.duration = 1.0;
    base.output_period = base.duration / 10;
    Scene ref_scene = base;
    ref_scene.tolerance = 1e-14;
    ref_scene.method = Method::kRkf78;
    const RunResult ref78 = plant_sim::run_scene(ref_scene);
    ref_scene.method = Method::kBulirschStoer;
    RunResult ref = plant_sim::run_scene(ref_scene);
    const double uncertainty = trajectory_error(ref78, ref).first;
    for (std::size_t k = 0; k < std::min(ref.samples.size(), ref78.samples.size()); ++k)
      for (std::size_t i = 0; i < ref.samples[k].q.size(); ++i)
        ref.samples[k].q[i] = 0.5 * (ref.samples[k].q[i] + ref78.samples[k].q[i]);
    char line[512];
    std::snprintf(line, sizeof line, "%s,reference_uncertainty,1e-14,%llu,%.6g,%.6g,,,,\n", base.name.c_str(),
                  static_cast<unsigned long long>(ref.summary.rhs_evaluations + ref78.summary.rhs_evaluations),
                  ref.summary.wall_time_s + ref78.summary.wall_time_s, uncertainty);
    csv << line;
    struct Case {
      Method method;
      const char* name;
      double setting;
    };
    std::vector<Case> cases;
    for (double h : {1e-2, 1e-3, 1e-4, 1e-5})
      if (!quick || h >= 1e-3) cases.push_back({Method::kRk4, "rk4", h});
    for (int e = 4; e <= 13; ++e)
      if (!quick || e % 4 == 0)
        for (auto [m, name] : {std::pair{Method::kDopri5, "dopri5"}, std::pair{Method::kRkf78, "rkf78"},
                               std::pair{Method::kBulirschStoer, "bulirsch_stoer"}})
          cases.push_back({m, name, std::pow(10.0, -e)});
    for (const Case& c : cases) {
      Scene s = base;
      s.method = c.method;
      (c.method == Method::kRk4 ? s.step : s.tolerance) = c.setting;
      const RunResult run = plant_sim::run_scene(s);
      const auto [worst, final] = trajectory_error(run, ref);
      double independent = std::nan("");
      if (s.name == "pendulum_fig1") independent = testing::compare_with_angle_model(s, run).max_difference;
      else if (s.tracking.model == "coupled_duffing" && s.control_mode == plant_sim::ControlMode::kContinuous)
        independent = minimal_coordinate_difference(s, run);
      std::snprintf(line, sizeof line, "%s,%s,%g,%llu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", base.name.c_str(), c.name,
                    c.setting, static_cast<unsigned long long>(run.summary.rhs_evaluations), run.summary.wall_time_s,
                    worst, final, independent, run.summary.max_tracking_error, run.summary.max_constraint_residual);
      csv << line;
    }
    std::printf("  integrators: %s (%zu runs; reference uncertainty %.2g)\n", base.name.c_str(), cases.size(),
                uncertainty);
  }
}

// Strategies on one constraint set. The reference force comes from the KKT system in long
// double, with redundant rows removed first (they change neither the motion nor Q').
void strategies(std::ofstream& csv, bool quick) {
  csv << "case,strategy,damping,force_error,constraint_residual,force_norm,ns_per_call,warnings\n";
  constexpr int N = 6, P = 3;
  using Mat = Eigen::Matrix<double, N, N>;
  using Dm = Eigen::Matrix<double, P, N>;
  std::mt19937_64 rng(1993);
  std::uniform_real_distribution<double> u(-1, 1);
  auto random = [&](auto& m) {
    for (Eigen::Index i = 0; i < m.size(); ++i) m(i) = u(rng);
  };
  Mat r;
  random(r);
  const Mat A = r * r.transpose() + N * Mat::Identity();
  Dm base;
  random(base);
  // D = U diag(s) V^T with chosen singular values.
  Eigen::JacobiSVD<Dm> svd(base, Eigen::ComputeFullU | Eigen::ComputeFullV);
  auto with_singular_values = [&](double s2) {
    Eigen::Matrix<double, P, N> S = Eigen::Matrix<double, P, N>::Zero();
    S(0, 0) = 1, S(1, 1) = 0.5, S(2, 2) = s2;
    return Dm(svd.matrixU() * S * svd.matrixV().transpose());
  };
  struct Case {
    const char* name;
    Dm D;
  };
  Dm redundant = base;
  redundant.row(2) = redundant.row(0) + 2 * redundant.row(1);
  const Case cases[] = {{"normal", with_singular_values(0.25)},
                        {"near_singular_1e-6", with_singular_values(1e-6)},
                        {"near_singular_1e-10", with_singular_values(1e-10)},
                        {"redundant", redundant}};
  for (const Case& c : cases) {
    // A manufactured solution: pick q''* and multipliers lambda*, then g = D q''* and
    // Q - f = A q''* - D^T lambda*, so that the exact force is Q' = D^T lambda* whatever the
    // conditioning of D (a solve in higher precision cannot be trusted when D's smallest singular
    // value is 1e-10: the KKT matrix then has condition near 1e20).
    Eigen::Matrix<double, N, 1> qdd;
    Eigen::Matrix<double, P, 1> lambda;
    random(qdd);
    random(lambda);
    const Eigen::Matrix<double, P, 1> g = c.D * qdd;
    const Eigen::Matrix<double, N, 1> reference = c.D.transpose() * lambda;
    const Eigen::Matrix<double, N, 1> Qm = A * qdd - reference;  // Q - f, with f = 0
    const Eigen::Matrix<double, N, 1> f = Eigen::Matrix<double, N, 1>::Zero(), Q = Qm;
    struct Choice {
      InverseStrategy s;
      const char* name;
      double damping;
    };
    const Choice choices[] = {{InverseStrategy::kCholeskyWithFallback, "cholesky", 0},
                              {InverseStrategy::kSvd, "svd", 0},
                              {InverseStrategy::kCompleteOrthogonal, "cod", 0},
                              {InverseStrategy::kDampedLeastSquares, "damped", 1e-12},
                              {InverseStrategy::kDampedLeastSquares, "damped", 1e-8},
                              {InverseStrategy::kDampedLeastSquares, "damped", 1e-4}};
    for (const Choice& ch : choices) {
      SolverOptions<double> o;
      o.strategy = ch.s;
      o.damping = ch.damping;
      ConstraintSolver<N, P> solver(o);
      ConstraintSolution<N, P> sol;
      solver.solve(A, f, Q, c.D, g, sol);
      const int calls = quick ? 100 : 20000;
      const auto t0 = std::chrono::steady_clock::now();
      for (int k = 0; k < calls; ++k) {
        solver.solve(A, f, Q, c.D, g, sol);
        asm volatile("" : : "g"(sol.constraint_force.data()) : "memory");
      }
      const double ns = seconds_since(t0) * 1e9 / calls;
      char line[256];
      std::snprintf(line, sizeof line, "%s,%s,%g,%.6g,%.6g,%.6g,%.4g,%u\n", c.name, ch.name, ch.damping,
                    (sol.constraint_force - reference).norm() / reference.norm(), sol.diagnostics.residual_norm,
                    sol.constraint_force.norm(), ns, sol.diagnostics.warnings);
      csv << line;
    }
  }
  std::printf("  strategies: normal, near-singular and redundant constraint sets\n");
}

Scene duffing_scene(const fs::path& dir) { return plant_sim::load_scene((dir / "duffing_alpha4.yaml").string()); }

void control_rate(const fs::path& dir, std::ofstream& csv, bool quick) {
  csv << "rate_hz,stabilization_omega,hold,max_tracking_error,rms_tracking_error,control_evaluations,wall_s\n";
  for (double rate : {100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0, 10000.0}) {
    if (quick && rate != 1000.0) continue;
    for (double omega : {0.0, 20.0}) {
      for (tracking::HoldLaw hold : tracking::kHoldLaws) {
        Scene s = duffing_scene(dir);
        if (quick) s.duration = 1.0;
        s.control_mode = plant_sim::ControlMode::kSampled;
        s.control_rate = rate;
        s.tracking.zeta = 1.0;
        s.tracking.stabilization_omega = omega;
        s.tracking.hold = hold;
        const RunResult run = plant_sim::run_scene(s);
        char line[256];
        std::snprintf(line, sizeof line, "%g,%g,%s,%.6g,%.6g,%llu,%.6g\n", rate, omega, tracking::to_string(hold),
                      run.summary.max_tracking_error, run.summary.rms_tracking_error,
                      static_cast<unsigned long long>(run.summary.control_evaluations), run.summary.wall_time_s);
        csv << line;
      }
    }
  }
  std::printf("  control rate: 100 Hz to 10 kHz\n");
}

void stabilization(const fs::path& dir, std::ofstream& csv, bool quick) {
  csv << "plant,stabilization_omega,max_tracking_error,rms_tracking_error,final_tracking_error\n";
  for (const char* plant : {"exact", "k1_10pct_high"}) {
    for (double omega : {0.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 500.0}) {
      if (quick && omega != 20.0) continue;
      Scene s = duffing_scene(dir);
      if (quick) s.duration = 1.0;
      s.control_mode = plant_sim::ControlMode::kSampled;
      s.control_rate = 1000.0;
      s.tracking.zeta = 1.0;
      s.tracking.stabilization_omega = omega;
      if (std::string(plant) != "exact") s.effects[0].value *= 1.1;  // the k1 spring
      const RunResult run = plant_sim::run_scene(s);
      char line[256];
      std::snprintf(line, sizeof line, "%s,%g,%.6g,%.6g,%.6g\n", plant, omega, run.summary.max_tracking_error,
                    run.summary.rms_tracking_error, std::abs(run.samples.back().tracking_error));
      csv << line;
    }
  }
  std::printf("  stabilization gains at 1 kHz\n");
}

// Constraint drift in the plant (Fig. 2 and Fig. 3's a): dopri5 at several tolerances, with and
// without projection onto the constraint manifolds after each step, against a reference from
// another method (Fehlberg 7(8) at 1e-13, projected).
void projection(const fs::path& dir, std::ofstream& csv, bool quick) {
  csv << "a,tolerance,projection,rhs_evaluations,projections,wall_s,max_constraint_residual,max_error,final_error\n";
  for (double a : {0.5, 1.0, 2.0, 4.0}) {
    if (quick && a != 4.0) continue;
    Scene base = plant_sim::load_scene((dir / "pendulum_fig2.yaml").string(),
                                       {"plant.initial.qd1=" + std::to_string(a)});
    if (quick) base.duration = 1.0;
    Scene ref_scene = base;
    ref_scene.method = Method::kRkf78;
    ref_scene.tolerance = 1e-13;
    ref_scene.projection = true;
    const RunResult ref = plant_sim::run_scene(ref_scene);
    for (double tol : {1e-6, 1e-8, 1e-10, 1e-12}) {
      if (quick && tol != 1e-8) continue;
      for (bool project : {false, true}) {
        Scene s = base;
        s.tolerance = tol;
        s.projection = project;
        const RunResult run = plant_sim::run_scene(s);
        const auto [worst, final] = trajectory_error(run, ref);
        char line[320];
        std::snprintf(line, sizeof line, "%g,%g,%d,%llu,%llu,%.6g,%.6g,%.6g,%.6g\n", a, tol, project ? 1 : 0,
                      static_cast<unsigned long long>(run.summary.rhs_evaluations),
                      static_cast<unsigned long long>(run.summary.projections), run.summary.wall_time_s,
                      run.summary.max_constraint_residual, worst, final);
        csv << line;
      }
    }
  }
  std::printf("  projection: Fig. 2 and Fig. 3's a, with and without\n");
}

}  // namespace

int main(int argc, char** argv) {
  fs::path scene_dir, out;
  bool quick = false;
  std::vector<std::string> only;
  CLI::App app("What accuracy costs: integrators, strategies, control rates and stabilization gains on the scenes.");
  app.add_option("scene_dir", scene_dir, "the scenes (plant_sim/scenes)")->required()->check(CLI::ExistingDirectory);
  app.add_option("out_dir", out, "where the CSVs and tables go")->required();
  app.add_flag("--quick", quick, "a short run of every part (for the tests)");
  app.add_option("--only", only, "run these parts alone")
      ->check(CLI::IsMember({"integrators", "peer", "strategies", "control_rate", "stabilization", "projection"}));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help, or a usage error (printed)
  }
  try {
    fs::create_directories(out);
    std::vector<fs::path> scenes;
    for (const auto& e : fs::directory_iterator(scene_dir))
      if (e.path().extension() == ".yaml") scenes.push_back(e.path());
    std::sort(scenes.begin(), scenes.end());
    if (scenes.empty()) throw std::runtime_error("no scenes in " + scene_dir.string());
    const auto t0 = std::chrono::steady_clock::now();
    auto open = [&](const char* name) {
      std::ofstream f(out / name);
      if (!f) throw std::runtime_error("cannot write " + (out / name).string());
      return f;
    };
    // Each part writes its CSV (NAME.csv).
    const std::pair<const char*, std::function<void(std::ofstream&)>> parts[] = {
        {"integrators", [&](std::ofstream& f) { integrators(scenes, f, quick); }},
        {"peer", [&](std::ofstream& f) { study::peer(f, quick); }},
        {"strategies", [&](std::ofstream& f) { strategies(f, quick); }},
        {"control_rate", [&](std::ofstream& f) { control_rate(scene_dir, f, quick); }},
        {"stabilization", [&](std::ofstream& f) { stabilization(scene_dir, f, quick); }},
        {"projection", [&](std::ofstream& f) { projection(scene_dir, f, quick); }},
    };
    for (const auto& [name, run] : parts) {
      if (!only.empty() && std::find(only.begin(), only.end(), name) == only.end()) continue;
      auto f = open((std::string(name) + ".csv").c_str());
      run(f);
    }
    std::printf("accuracy_vs_time: %.1f s -> %s\n", seconds_since(t0), out.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
