// The actuated law (actuation.hpp) beside the plain law of eq. (32) on the same model and beside
// a Lagrange-multiplier solve of the same problem, in the same run, all factoring A on every call:
//   actuation/<case>/actuated   ActuatedController: the commands of K actuators (Gauss's weight),
//                               reuse_factorization off
//   actuation/<case>/law        TrackingController on the same model, every coordinate actuated,
//                               reuse_factorization off
//   actuation/<case>/kkt        the same least-cost problem (and physical rows) as one dynamic-size
//                               LU (dynamic_kkt_control), the model's terms and B included; its
//                               answer is checked against the law's before timing
// Cases <family>_no_b are models that declare no B, controlled through B = I by ActuatedController:
// the actuated law's cost where it is eq. (32) (its plain case, solved by the plain law's solver).
#include <string>

#include "controller_bench.hpp"
#include "gausstrack/actuation.hpp"
#include "gausstrack/systems/cart_pole.hpp"
#include "gausstrack/systems/coupled_duffing.hpp"
#include "gausstrack/systems/differential_drive.hpp"
#include "gausstrack/systems/duffing_chain.hpp"
#include "gausstrack/systems/planar_arm.hpp"

namespace gausstrack::bench {
namespace {

// A model with the actuators `Columns` name: B's column j pushes coordinate Columns[j].
template <typename M, int... Columns>
struct Actuated : M {
  static constexpr int kActuators = sizeof...(Columns);
  void actuation(const Eigen::Matrix<double, M::kDof, 1>&, double,
                 Eigen::Matrix<double, M::kDof, kActuators>& b) const noexcept {
    b.setZero();
    int j = 0;
    ((b(Columns, j++) = 1.0), ...);
  }
};

template <typename A>
void bench_actuated(benchmark::State& state) {
  static const States<A> s;
  ControllerOptions<double> options;
  options.solver.reuse_factorization = false;  // as the plain law's row: A factored every call
  ActuatedController<A> controller(A{}, options);
  typename ActuatedController<A>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.control.data());
  });
}

// The terms, B and the rows split into task and physical, as the KKT baseline takes them.
template <typename A>
struct ActuatedTerms {
  Eigen::MatrixXd mass, dc, dp, b;
  Eigen::VectorXd f, q_force, gc, gp;
  ActuatedTerms(const A& model, const States<A>& s, std::size_t k) {
    TermsOf<A> t;
    evaluate_model(model, s.q[k], s.qd[k], s.t[k], t);
    Eigen::Matrix<double, A::kDof, kActuatorsOf<A>> bm;
    if constexpr (ActuatedModel<A>)
      model.actuation(s.q[k], s.t[k], bm);
    else
      bm.setIdentity();
    constexpr int kTask = RowLayout<A>::kTask, kPhysical = RowLayout<A>::kPhysical;
    mass = t.mass_matrix;
    f = t.nonlinear_force;
    q_force = t.applied_force;
    b = bm;
    dc.resize(kTask, A::kDof);
    gc.resize(kTask);
    dp.resize(kPhysical, A::kDof);
    gp.resize(kPhysical);
    for (int i = 0, c = 0, p = 0; i < A::kConstraints; ++i) {
      if (RowLayout<A>::physical(i)) {
        dp.row(p) = t.constraint_matrix.row(i);
        gp(p++) = t.constraint_rhs(i);
      } else {
        dc.row(c) = t.constraint_matrix.row(i);
        gc(c++) = t.constraint_rhs(i);
      }
    }
  }
  Eigen::VectorXd control() const {
    return dynamic_kkt_control(mass, f, q_force, dc, gc, dp, gp, b);
  }
};

template <typename A>
void bench_kkt(benchmark::State& state) {
  static const States<A> s;
  const A model{};
  {  // the same problem: the law without stabilization gives the same commands
    ControllerOptions<double> o;
    o.stabilization = {0.0, 0.0};
    ActuatedController<A> law(model, o);
    typename ActuatedController<A>::Output out;
    law.compute(s.q[0], s.qd[0], s.t[0], out);
    const Eigen::VectorXd u = ActuatedTerms<A>(model, s, 0).control();
    if (!((u - out.control).norm() <= 1e-8 * (1.0 + u.norm()))) {
      const std::string why = "the KKT baseline does not answer as the law (rank " +
                              std::to_string(out.diagnostics.rank) + ", gap " +
                              std::to_string((u - out.control).norm()) + ")";
      state.SkipWithError(why.c_str());
      return;
    }
  }
  measure(state, [&](std::size_t k) {
    const Eigen::VectorXd u = ActuatedTerms<A>(model, s, k).control();
    benchmark::DoNotOptimize(u.data());
  });
}

template <typename M>
void bench_plain(benchmark::State& state) {
  static const States<M> s;
  ControllerOptions<double> o;
  o.solver.reuse_factorization = false;
  TrackingController<M> controller{M{}, o};
  typename TrackingController<M>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.force.data());
  });
}

using Duffing = systems::CoupledDuffing<double>;
using Arm = systems::PlanarArm<double>;
using Chain = systems::DuffingChain<8, 4, double>;
using Drive = systems::DifferentialDrive<double>;
using CartPole = systems::CartPole<double>;

// with_kkt false: the task rows cannot all be actuated (the law answers in the least-squares
// sense, rank below P), where the KKT system is singular.
template <typename A>
void add_case(const std::string& name, bool with_kkt = true) {
  benchmark::RegisterBenchmark(("actuation/" + name + "/actuated").c_str(), bench_actuated<A>);
  if (with_kkt) benchmark::RegisterBenchmark(("actuation/" + name + "/kkt").c_str(), bench_kkt<A>);
}

const bool registered = [] {
  add_case<Duffing>("duffing_no_b");
  add_case<Actuated<Duffing, 0>>("duffing_1_of_2");
  benchmark::RegisterBenchmark("actuation/duffing_1_of_2/law", bench_plain<Duffing>);
  add_case<Arm>("arm_no_b");
  add_case<Actuated<Arm, 0, 1, 2>>("arm_3_of_3");
  add_case<Actuated<Arm, 0, 1>>("arm_2_of_3");
  benchmark::RegisterBenchmark("actuation/arm_3_of_3/law", bench_plain<Arm>);
  add_case<Chain>("chain8_no_b");
  add_case<Actuated<Chain, 0, 2, 4, 6>>("chain8_4_of_8", false);  // rank 3 of 4
  add_case<Actuated<Chain, 0, 1, 2, 3, 4, 5, 6, 7>>("chain8_8_of_8");
  benchmark::RegisterBenchmark("actuation/chain8_8_of_8/law", bench_plain<Chain>);
  add_case<CartPole>("cartpole_1_of_2");
  add_case<Drive>("drive_2_of_3_no_slip");
  return true;
}();

}  // namespace
}  // namespace gausstrack::bench
