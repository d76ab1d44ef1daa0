// One full controller evaluation (model terms + eq. 32) per generalized-inverse strategy, beside
// baselines computed from the same model terms in the same run:
//   literal_fixed  the paper's formulas with fixed-size SVD pseudo-inverses and A^(1/2)
//                  (reference/literal_formulas.hpp);
//   dynamic_user   what a typical user writes with dynamic-size Eigen: MatrixXd, the symmetric
//                  square root from SelfAdjointEigenSolver, completeOrthogonalDecomposition()
//                  .pseudoInverse(), Q' = A^(1/2) (D A^(-1/2))^+ (g - D a);
//   dynamic_kkt    the KKT system [A D^T; D 0] [q''; -lambda] = [Q - f; g] solved by a
//                  dynamic-size LU, Q' = A q'' + f - Q;
//   plain_fixed    the general case's mathematics on the law's own kernels (small_dense.hpp)
//                  with no checks and no diagnostics: Cholesky of A, B^T = L^-1 D^T with
//                  L^-1 (Q - f) beside it, Cholesky of B B^T applied by two triangular solves,
//                  both parts of eq. (32) and q'' (checked against the law's first); the
//                  floor the checks and diagnostics are measured against (law/<m>/
//                  cholesky_dense_refactor, or cholesky_refactor for a dense model);
//   model_terms    the model's terms A, f, Q, D, g alone (one evaluate_model, as every row
//                  above and the law do): the part of each row that is not the solve;
//   closed_form    (Duffing only) the hand-derived force Q' = (r, -r) / (1/m1 + 1/m2),
//                  r = s'' - (a1 - a2): the floor.
// The law runs as the default (law/<m>/cholesky: the mass matrix as the model declares it, the
// factorization kept while A and D are unchanged, as they are for the Duffing systems) and
// factoring on every call (cholesky_refactor, as a configuration-dependent A and D need); a model
// that declares a diagonal A also runs as if it had not (cholesky_dense_refactor: the general
// case at the same size).
// Each benchmark's time is Google Benchmark's (calls back to back over a set of 64 states).
// After its loop, a second pass times calls one by one for the counters p50_ns, p99_ns, p999_ns
// and max_ns (these include two clock reads; `timer_overhead` measures them), and
// allocs_per_call counts heap allocations (operator new and malloc) in the main loop.
#pragma once

#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "allocation_counter.hpp"
#include "dynamic_baselines.hpp"
#include "gausstrack/nodes/latency_recorder.hpp"
#include "gausstrack/reference/literal_formulas.hpp"
#include "gausstrack/small_dense.hpp"
#include "gausstrack/tracking_controller.hpp"

namespace gausstrack::bench {

template <typename M>
struct States {
  static constexpr int kCount = 64;
  using V = Eigen::Matrix<typename M::Scalar, M::kDof, 1>;
  std::array<V, kCount> q, qd;
  std::array<double, kCount> t;
  States() {
    std::mt19937_64 rng(1993);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int k = 0; k < kCount; ++k) {
      for (int i = 0; i < M::kDof; ++i) {
        q[k](i) = u(rng);
        qd[k](i) = u(rng);
      }
      t[k] = 0.5 * (u(rng) + 1);
    }
  }
};

/// Runs `call(k)` for the benchmark loop, counting allocations, then times calls one by one.
template <typename F>
void measure(benchmark::State& state, F&& call) {
  static nodes::LatencyRecorder ns(1 << 20);  // reserved once, outside every counted region
  std::size_t k = 0;
  support::start_counting_allocations();
  for (auto _ : state) call(k++ & 63);
  const long allocations = support::stop_counting_allocations();
  ns.clear();
  const std::size_t timed = std::clamp<std::size_t>(k, 1000, 100000);
  for (std::size_t i = 0; i < timed; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    call(i & 63);
    const auto t1 = std::chrono::steady_clock::now();
    ns.add(static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()));
  }
  state.counters["p50_ns"] = ns.quantile(0.5);
  state.counters["p99_ns"] = ns.quantile(0.99);
  state.counters["p999_ns"] = ns.quantile(0.999);
  state.counters["max_ns"] = ns.max();
  state.counters["allocs_per_call"] = static_cast<double>(allocations) / static_cast<double>(std::max<std::size_t>(k, 1));
}

/// The model's terms of eq. (32) at one of the benchmark states (one evaluate_model, as the law
/// does), as the baselines take them.
template <typename M>
struct BaselineTerms {
  Eigen::Matrix<double, M::kDof, M::kDof> A;
  Eigen::Matrix<double, M::kDof, 1> f, Q;
  Eigen::Matrix<double, M::kConstraints, M::kDof> D;
  Eigen::Matrix<double, M::kConstraints, 1> g;
  BaselineTerms(const M& m, const States<M>& s, std::size_t k) {
    TermsOf<M> t;
    evaluate_model(m, s.q[k], s.qd[k], s.t[k], t);
    A = t.mass_matrix;
    f = t.nonlinear_force;
    Q = t.applied_force;
    D = t.constraint_matrix;
    g = t.constraint_rhs;
  }
};

/// Model M with its mass matrix declared dense (the general case), all else the same.
template <typename M>
struct DenseMass : M {
  static constexpr MassMatrix kMassMatrix = MassMatrix::kDense;
};

template <typename M>
void bench_law(benchmark::State& state, InverseStrategy strategy, bool reuse = true) {
  static const States<M> s;
  ControllerOptions<double> options;
  options.solver.strategy = strategy;
  options.solver.damping = 1e-9;
  options.solver.reuse_factorization = reuse;
  TrackingController<M> controller(M{}, options);
  typename TrackingController<M>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], s.t[k], out));
    benchmark::DoNotOptimize(out.force.data());
  });
}

/// The law with a sampled-data hold of 1 ms (docs/sampled_law.md): two evaluations per call, the
/// second at the predicted state. Consecutive states 1 ms apart, so that the jerk term is used
/// (every 64th call goes back in time and starts a new motion). The times stay in [0, 0.064) s,
/// within the other rows' [0, 1] s: a time that grew with the call count would, from about 186 s,
/// time the Duffing trajectory's e^(-alpha t) on the C library's underflow path (about 18 ns per
/// exp against 4) instead of the hold.
template <typename M>
void bench_law_held(benchmark::State& state) {
  static const States<M> s;
  TrackingController<M> controller(M{}, {});
  controller.set_hold({1e-3, 0.0});
  typename TrackingController<M>::Output out;
  measure(state, [&](std::size_t k) {
    benchmark::DoNotOptimize(controller.compute(s.q[k], s.qd[k], 1e-3 * static_cast<double>(k), out));
    benchmark::DoNotOptimize(out.force.data());
  });
}

template <typename M>
void bench_literal_fixed(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  measure(state, [&](std::size_t k) {
    const BaselineTerms<M> m(model, s, k);
    const auto out = reference::literal_formulas<M::kDof, M::kConstraints, double>(m.A, m.f, m.Q, m.D, m.g);
    benchmark::DoNotOptimize(out.constraint_force.data());
  });
}

template <typename M>
void bench_dynamic_user(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  measure(state, [&](std::size_t k) {
    const BaselineTerms<M> m(model, s, k);
    const Eigen::VectorXd force = dynamic_user_force(m.A, m.f, m.Q, m.D, m.g);
    benchmark::DoNotOptimize(force.data());
  });
}

template <typename M>
void bench_dynamic_kkt(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  measure(state, [&](std::size_t k) {
    const BaselineTerms<M> m(model, s, k);
    const Eigen::VectorXd force = dynamic_kkt_force(m.A, m.f, m.Q, m.D, m.g);
    benchmark::DoNotOptimize(force.data());
  });
}

/// plain_fixed's solve for the terms t: the two parts of eq. (32) (y's columns) and [a, q''] (z's).
template <typename M>
[[gnu::always_inline]] inline void plain_fixed_solve(const TermsOf<M>& t, Eigen::Matrix<double, M::kDof, 2>& y,
                                                     Eigen::Matrix<double, M::kDof, 2>& z) noexcept {
  constexpr int N = M::kDof, P = M::kConstraints;
  // The law's kernels (small_dense) and its order of work with none of its checks: no
  // finiteness tests, no condition bound (so no L_G^-1: the Gram matrix is applied by two
  // triangular solves), no residual. As the law does, u = L^-1 (Q - f) rides along B^T's
  // solve, and B^T's solve and the Gram matrix skip what D's rows leave exactly zero.
  Eigen::Matrix<double, N, N> l = t.mass_matrix;
  Eigen::Matrix<double, N, 1> reciprocal;  // 1 / L_kk
  small_dense::cholesky_in_place(l, reciprocal.data());
  Eigen::Matrix<double, N, P> dt = t.constraint_matrix.transpose();
  Eigen::Matrix<double, N, 1> u = t.applied_force - t.nonlinear_force;
  // Where D's rows can be nonzero (D^T's columns), and B^T's columns below them; u's is dense.
  int first[P], d_end[P], bt_end[P];
  small_dense::column_supports(dt, first, d_end);
  for (int c = 0; c < P; ++c) bt_end[c] = d_end[c];
  small_dense::fill_in_below<N>(bt_end, P);
  constexpr bool supports = N > 8;  // as the law: above 8 coordinates
  const int* from = supports ? first : nullptr;
  Eigen::Matrix<double, N, P> bt = dt;
  small_dense::solve_lower_in_place(l, reciprocal.data(), bt, u, from);
  Eigen::Matrix<double, P, 2> w;  // the multipliers of -D a = -B u and of g
  for (int i = 0; i < P; ++i) {
    const int lo = supports ? first[i] : 0, hi = supports ? bt_end[i] : N;
    w(i, 0) = -small_dense::dot(bt.data() + i * N + lo, u.data() + lo, hi - lo);
    w(i, 1) = t.constraint_rhs(i);
  }
  if constexpr (P == 1) {  // as the law: one row's B B^T is the scalar |b|^2
    const double inverse_gram = 1.0 / small_dense::squared_norm(bt.data(), N);
    w *= inverse_gram;
  } else {
    Eigen::Matrix<double, P, P> gram;
    small_dense::gram(bt, gram, from, supports ? bt_end : nullptr);
    small_dense::cholesky_in_place(gram);
    small_dense::solve_lower_in_place(gram, w);
    small_dense::solve_lower_transposed_in_place(gram, w);
  }
  // The two parts of eq. (32), D^T w.
  small_dense::multiply_columns<supports>(dt, w.data(), y.data(), from, d_end);
  small_dense::multiply_columns<supports>(dt, w.data() + P, y.data() + N, from, d_end);
  const Eigen::Matrix<double, P, 1> w_sum = w.col(0) + w.col(1);
  // [u, u + B^T (w_0 + w_1)], then L^-T of both: [a, q''].
  small_dense::multiply_columns<supports>(bt, w_sum.data(), z.data() + N, from, bt_end);
  z.col(0) = u;
  z.col(1) += u;
  small_dense::solve_lower_transposed_in_place(l, reciprocal.data(), z);
}

template <typename M>
void bench_plain_fixed(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  constexpr int N = M::kDof;
  Eigen::Matrix<double, N, 2> y, z;
  // The floor computes what the row it is the floor of computes (the general case: a dense A
  // factored every call): both parts and q'' at every state, to rounding, and a = A^-1 (Q - f).
  ControllerOptions<double> options;
  options.solver.reuse_factorization = false;
  TrackingController<DenseMass<M>> law(DenseMass<M>{}, options);
  typename TrackingController<DenseMass<M>>::Output out;
  for (std::size_t k = 0; k < States<M>::kCount; ++k) {
    TermsOf<M> t;
    evaluate_model(model, s.q[k], s.qd[k], s.t[k], t);
    plain_fixed_solve<M>(t, y, z);
    law.compute(s.q[k], s.qd[k], s.t[k], out);
    const auto close = [](const auto& x, const auto& ref) {
      return (x - ref).norm() <= 1e-9 * (1 + ref.norm());
    };
    const Eigen::Matrix<double, N, 1> a = t.mass_matrix.llt().solve(t.applied_force - t.nonlinear_force);
    if (!close(y.col(0), out.closed_loop) || !close(y.col(1), out.feedforward) || !close(z.col(1), out.acceleration) ||
        !close(z.col(0), a)) {
      state.SkipWithError("plain_fixed and the law disagree");
      return;
    }
  }
  measure(state, [&](std::size_t k) {
    TermsOf<M> t;
    evaluate_model(model, s.q[k], s.qd[k], s.t[k], t);
    plain_fixed_solve<M>(t, y, z);
    benchmark::DoNotOptimize(y.data());
    benchmark::DoNotOptimize(z.data());
  });
}

template <typename M>
void bench_model_terms(benchmark::State& state) {
  static const States<M> s;
  const M model{};
  TermsOf<M> t;
  measure(state, [&](std::size_t k) {
    evaluate_model(model, s.q[k], s.qd[k], s.t[k], t);
    benchmark::DoNotOptimize(t.constraint_rhs.data());
    benchmark::ClobberMemory();
  });
}

/// The general case's solve taken apart (where its time goes): each kernel of the law's
/// refactoring path alone, on the terms of the benchmark states, beside the KKT baseline's LU
/// alone (its matrix assembled outside the timed call). `phase` selects the kernel.
enum class Phase { kMassCholesky, kConstraintSolve, kGram, kGramCholesky, kGramInverse, kKktLu };

template <typename M>
void bench_phase(benchmark::State& state, Phase phase) {
  constexpr int N = M::kDof, P = M::kConstraints;
  struct Inputs {
    Eigen::Matrix<double, N, N> a, l;                // A and its factor
    Eigen::Matrix<double, N, 1> reciprocal;          // 1 / L_kk
    Eigen::Matrix<double, N, P> dt, bt;              // D^T and B^T = L^-1 D^T
    Eigen::Matrix<double, N, 1> r;                   // Q - f
    int first[P], end[P];      // B^T's columns' supports (used above 8 coordinates, as the law does)
    Eigen::Matrix<double, P, P> gram, gram_l;        // B B^T and its factor
    Eigen::MatrixXd kkt;                             // [A D^T; D 0]
  };
  static const std::vector<Inputs> inputs = [] {
    const States<M> s;
    const M model{};
    std::vector<Inputs> v(States<M>::kCount);
    for (std::size_t k = 0; k < v.size(); ++k) {
      const BaselineTerms<M> m(model, s, k);
      Inputs& in = v[k];
      in.a = m.A;
      in.l = m.A;
      small_dense::cholesky_in_place(in.l, in.reciprocal.data());
      in.dt = m.D.transpose();
      small_dense::column_supports(in.dt, in.first, in.end);
      small_dense::fill_in_below<N>(in.end, P);
      in.r = m.Q - m.f;
      in.bt = in.dt;
      small_dense::solve_lower_in_place(in.l, in.reciprocal.data(), in.bt);
      in.gram.noalias() = in.bt.transpose().lazyProduct(in.bt);
      in.gram_l = in.gram;
      small_dense::cholesky_in_place(in.gram_l);
      in.kkt = Eigen::MatrixXd::Zero(N + P, N + P);
      in.kkt.topLeftCorner(N, N) = m.A;
      in.kkt.topRightCorner(N, P) = m.D.transpose();
      in.kkt.bottomLeftCorner(P, N) = m.D;
    }
    return v;
  }();
  Eigen::Matrix<double, N, N> l;
  Eigen::Matrix<double, N, P> bt;
  Eigen::Matrix<double, N, 1> u;
  Eigen::Matrix<double, P, P> g, g_inv;
  measure(state, [&](std::size_t k) {
    const Inputs& in = inputs[k];
    switch (phase) {
      case Phase::kMassCholesky:
        l = in.a;
        benchmark::DoNotOptimize(small_dense::cholesky_in_place(l));
        benchmark::DoNotOptimize(l.data());
        break;
      case Phase::kConstraintSolve: {  // B^T = L^-1 D^T and u = L^-1 (Q - f), one substitution
        bt = in.dt;
        u = in.r;
        small_dense::solve_lower_in_place(in.l, in.reciprocal.data(), bt, u, N > 8 ? in.first : nullptr);
        benchmark::DoNotOptimize(bt.data());
        benchmark::DoNotOptimize(u.data());
        break;
      }
      case Phase::kGram:
        small_dense::gram(in.bt, g, N > 8 ? in.first : nullptr, N > 8 ? in.end : nullptr);
        benchmark::DoNotOptimize(g.data());
        break;
      case Phase::kGramCholesky:
        g = in.gram;
        benchmark::DoNotOptimize(small_dense::cholesky_in_place(g));
        benchmark::DoNotOptimize(g.data());
        break;
      case Phase::kGramInverse:
        benchmark::DoNotOptimize(small_dense::invert_lower(in.gram_l, g_inv));
        benchmark::DoNotOptimize(g_inv.data());
        break;
      case Phase::kKktLu:
        benchmark::DoNotOptimize(kkt_lu(in.kkt));
        break;
    }
  });
}

/// Registers the phases of the general case's solve for model M, e.g. "phase/chain_16x8/gram".
template <typename M>
void register_solve_phases(const std::string& name) {
  const std::string size = name + "_" + std::to_string(M::kDof) + "x" + std::to_string(M::kConstraints);
  const std::pair<Phase, const char*> phases[] = {
      {Phase::kMassCholesky, "mass_cholesky"}, {Phase::kConstraintSolve, "constraint_solve"},
      {Phase::kGram, "gram"},                  {Phase::kGramCholesky, "gram_cholesky"},
      {Phase::kGramInverse, "gram_inverse"},   {Phase::kKktLu, "kkt_lu"}};
  for (const auto& [phase, label] : phases)
    benchmark::RegisterBenchmark(("phase/" + size + "/" + label).c_str(),
                                 [phase = phase](benchmark::State& st) { bench_phase<M>(st, phase); });
}

inline void bench_timer_overhead(benchmark::State& state) {
  measure(state, [](std::size_t k) { benchmark::DoNotOptimize(k); });
}

/// Registers the law (every strategy) and the baselines for model M under `name`, e.g.
/// "law/duffing_2x1/cholesky", "baseline/duffing_2x1/dynamic_kkt".
template <typename M>
void register_model(const std::string& name) {
  const std::string size = name + "_" + std::to_string(M::kDof) + "x" + std::to_string(M::kConstraints);
  for (InverseStrategy s : {InverseStrategy::kCholeskyWithFallback, InverseStrategy::kSvd,
                            InverseStrategy::kCompleteOrthogonal, InverseStrategy::kDampedLeastSquares})
    benchmark::RegisterBenchmark(("law/" + size + "/" + to_string(s)).c_str(),
                                 [s](benchmark::State& st) { bench_law<M>(st, s); });
  constexpr auto kDefault = InverseStrategy::kCholeskyWithFallback;
  benchmark::RegisterBenchmark(("law/" + size + "/cholesky_refactor").c_str(),
                               [](benchmark::State& st) { bench_law<M>(st, kDefault, false); });
  benchmark::RegisterBenchmark(("law/" + size + "/cholesky_held").c_str(), bench_law_held<M>);
  if constexpr (kMassMatrixOf<M> != MassMatrix::kDense)
    benchmark::RegisterBenchmark(("law/" + size + "/cholesky_dense_refactor").c_str(),
                                 [](benchmark::State& st) { bench_law<DenseMass<M>>(st, kDefault, false); });
  benchmark::RegisterBenchmark(("baseline/" + size + "/model_terms").c_str(), bench_model_terms<M>);
  benchmark::RegisterBenchmark(("baseline/" + size + "/plain_fixed").c_str(), bench_plain_fixed<M>);
  benchmark::RegisterBenchmark(("baseline/" + size + "/literal_fixed").c_str(), bench_literal_fixed<M>);
  benchmark::RegisterBenchmark(("baseline/" + size + "/dynamic_user").c_str(), bench_dynamic_user<M>);
  benchmark::RegisterBenchmark(("baseline/" + size + "/dynamic_kkt").c_str(), bench_dynamic_kkt<M>);
}

}  // namespace gausstrack::bench
