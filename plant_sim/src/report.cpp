#include "report.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "gausstrack/plant_sim/simulation.hpp"

namespace gausstrack::plant_sim {
namespace detail {

std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

std::string describe_state(const Eigen::VectorXd& x) {
  const auto n = x.size() / 2;
  std::string v = "q = (";
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    if (i == n) v += "), q' = (";
    else if (i > 0) v += ", ";
    v += number(x(i));
  }
  return v + ")";
}

}  // namespace detail

void write_trajectory_csv(const Scene& scene, const RunResult& result, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  const int n = scene.dof();
  out << "t";
  for (const char* p : {"q", "qd", "u"})
    for (int i = 1; i <= n; ++i) out << "," << p << i;
  out << ",tracking_error,constraint_residual\n";
  char buf[64];
  auto put = [&](double v) {
    std::snprintf(buf, sizeof buf, ",%.17g", v);
    out << buf;
  };
  for (const Sample& s : result.samples) {
    std::snprintf(buf, sizeof buf, "%.17g", s.t);
    out << buf;
    for (double v : s.q) put(v);
    for (double v : s.qd) put(v);
    for (double v : s.u) put(v);
    put(s.tracking_error);
    put(s.constraint_residual);
    out << "\n";
  }
  if (!out) throw std::runtime_error("error writing " + path);
}

std::function<void(double t)> terminal_progress(const Scene& scene) {
  if (isatty(fileno(stderr)) == 0) return {};
  const auto start = std::chrono::steady_clock::now();
  return [start, name = scene.name, duration = scene.duration](double t) {
    if (std::chrono::steady_clock::now() - start < std::chrono::seconds(1)) return;
    std::fprintf(stderr, "\r%s: t = %.3f / %.3f s (%3.0f%%)%s", name.c_str(), t, duration, 100.0 * t / duration,
                 t >= duration ? "\n" : "");
  };
}

nlohmann::ordered_json summary_json(const Scene& scene, const RunResult& result) {
  const RunSummary& s = result.summary;
  nlohmann::ordered_json j;
  j["scene"] = scene.name;
  // Whether the run reached its duration; if not, why (a failure) or that it was stopped.
  j["completed"] = s.failure.empty() && !s.stopped_early;
  j["failure"] = s.failure.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.failure);
  if (!s.failure.empty()) j["failed_at"] = s.failed_at;
  j["max_tracking_error"] = s.max_tracking_error;
  j["rms_tracking_error"] = s.rms_tracking_error;
  j["max_constraint_residual"] = s.max_constraint_residual;
  j["force_total_variation"] = s.force_total_variation;
  j["steps"] = s.steps;
  j["rhs_evaluations"] = s.rhs_evaluations;
  j["control_evaluations"] = s.control_evaluations;
  j["control_failures"] = s.control_failures;
  // Each warning kind: the evaluations (periods) that carried it; whether the rows held.
  nlohmann::ordered_json& warnings = j["warnings"] = nlohmann::ordered_json::object();
  for (int b = 0; b < warning::kCount; ++b) warnings[warning::name(b)] = s.warnings.by_kind[static_cast<std::size_t>(b)];
  j["rows_not_met_share"] = s.warnings.rows_not_met_share();
  j["rows_not_met"] = s.rows_not_met.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.rows_not_met);
  j["projections"] = s.projections;
  nlohmann::ordered_json& effects = j["effect_evaluations"] = nlohmann::ordered_json::object();
  for (std::size_t k = 0; k < s.effect_evaluations.size(); ++k)
    effects[to_string(static_cast<EffectKind>(k))] = s.effect_evaluations[k];
  // Which engine stepped the plant, and which of its effects were on (all others were off).
  j["engine"] = s.engine.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(s.engine);
  if (!s.engine.empty()) j["engine_effects"] = s.engine_effects;
  j["wall_time_s"] = s.wall_time_s;
  return j;
}

std::string rows_not_met(const Scene& scene, const WarningTally& w, const char* unit) {
  const double share = w.rows_not_met_share();
  if (!scene.tracking.enabled || share <= scene.tracking.unmet_limit) return "";
  char head[256];
  std::snprintf(head, sizeof head, "the task rows were not met in %.1f %% of the %s (%llu of %llu; tracking.unmet_limit %g %%)",
                100 * share, unit, static_cast<unsigned long long>(w.rows_not_met),
                static_cast<unsigned long long>(w.calls), 100 * scene.tracking.unmet_limit);
  const std::string kinds = warning_counts(w);
  return std::string(head) + (kinds.empty() ? "" : ": " + kinds);
}

std::string warning_counts(const WarningTally& w) {
  std::string kinds;
  for (int b = 0; b < warning::kCount; ++b)
    if (const auto n = w.by_kind[static_cast<std::size_t>(b)]; n > 0)
      kinds += (kinds.empty() ? "" : ", ") + std::string(warning::name(b)) + " " + std::to_string(n);
  if (w.failed > 0) kinds += (kinds.empty() ? "" : ", ") + std::string("failed ") + std::to_string(w.failed);
  return kinds;
}

void write_json(const nlohmann::ordered_json& document, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  // Text that is not UTF-8 (a scene's name, an engine's message) is written with replacement
  // characters rather than lose the summary.
  out << document.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << "\n";
  if (!out) throw std::runtime_error("error writing " + path);
}

void write_summary_json(const Scene& scene, const RunResult& result, const std::string& path) {
  write_json(summary_json(scene, result), path);
}

}  // namespace gausstrack::plant_sim
