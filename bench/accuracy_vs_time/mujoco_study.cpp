// mujoco_study SCENE_DIR MODEL_DIR OUT_DIR [--quick]
// What the MuJoCo plant's accuracy costs in time, on the planar arm (planar_arm_mujoco.yaml):
//   mujoco_plant.csv  for each MuJoCo integrator (euler, rk4, implicit) and timestep (1 ms down to
//                     10 us): the plant's own error in a 1 s free swing under gravity against
//                     plant_sim's integration of the arm's model (dopri5 at 1e-12), and the
//                     closed loop's tracking error at 1 kHz over 10 s, each with its wall time.
//   mujoco_mismatch.csv the closed loop on a plant whose link 2 is 10% heavier (arm3_heavy.xml)
//                     than the controller's model, with and without stabilization.
// Writes mujoco_study.md, the two tables in Markdown. --quick: one timestep, 0.2 s (for CI).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "gausstrack/plant_sim/mujoco.hpp"
#include "gausstrack/plant_sim/scene.hpp"
#include "gausstrack/plant_sim/simulation.hpp"

namespace {

using namespace gausstrack::plant_sim;

RunResult run(const std::string& scene, const std::vector<std::string>& sets) {
  RunOptions o;
  o.engines.push_back(mujoco_engine());
  return run_scene(load_scene(scene, sets), o);
}

std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenes, models, out;
  bool quick = false;
  CLI::App app("MuJoCo as the plant: each integrator and timestep on the planar arm, free swing and closed loop.");
  app.add_option("scene_dir", scenes, "the scenes (plant_sim/scenes)")->required()->check(CLI::ExistingDirectory);
  app.add_option("model_dir", models, "the MJCF models (plant_sim/models)")->required()->check(CLI::ExistingDirectory);
  app.add_option("out_dir", out, "where the CSVs and tables go")->required();
  app.add_flag("--quick", quick, "one timestep, 0.2 s (for the tests)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help, or a usage error (printed)
  }
  std::filesystem::create_directories(out);
  const std::string arm = scenes + "/planar_arm_mujoco.yaml";
  const std::string swing = quick ? "duration=0.2" : "duration=1.0";
  const std::string loop = quick ? "duration=0.2" : "duration=10.0";

  try {
    // The reference free swing: plant_sim's own integration of the same arm.
    const RunResult reference =
        run_scene(load_scene(scenes + "/planar_arm.yaml", {"tracking=null", swing, "integrator.tolerance=1e-12"}));

    std::ofstream csv(out + "/mujoco_plant.csv");
    std::ofstream md(out + "/mujoco_study.md");
    csv << "integrator,timestep,swing_max_error,swing_wall_s,loop_max_tracking_error,loop_rms_tracking_error,loop_wall_s,"
           "loop_failure\n";
    md << "| MuJoCo integrator | timestep | free swing: max joint error [rad] | wall [s] | closed loop: max hand "
          "error [m] | rms [m] | wall [s] |\n|---|---|---|---|---|---|---|\n";
    const std::vector<double> steps = quick ? std::vector<double>{1e-4} : std::vector<double>{1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5};
    for (const char* integrator : {"euler", "rk4", "implicit"}) {
      for (double h : steps) {
        const std::vector<std::string> engine = {"plant.integrator=" + std::string(integrator),
                                                 "plant.timestep=" + fmt(h)};
        std::vector<std::string> free = engine;
        free.insert(free.end(), {"tracking=null", swing});
        const RunResult s = run(arm, free);
        double worst = 0;
        for (std::size_t k = 0; k < std::min(s.samples.size(), reference.samples.size()); ++k)
          for (std::size_t i = 0; i < 3; ++i)
            worst = std::max(worst, std::abs(s.samples[k].q[i] - reference.samples[k].q[i]));
        if (!s.summary.failure.empty() || s.samples.size() != reference.samples.size()) worst = INFINITY;
        std::vector<std::string> closed = engine;
        closed.push_back(loop);
        const RunResult c = run(arm, closed);
        csv << integrator << "," << h << "," << worst << "," << s.summary.wall_time_s << "," << c.summary.max_tracking_error
            << "," << c.summary.rms_tracking_error << "," << c.summary.wall_time_s << ",\"" << c.summary.failure << "\"\n";
        md << "| " << integrator << " | " << fmt(h) << " | " << fmt(worst) << " | " << fmt(s.summary.wall_time_s) << " | "
           << (c.summary.failure.empty() ? fmt(c.summary.max_tracking_error) : "failed") << " | "
           << fmt(c.summary.rms_tracking_error) << " | " << fmt(c.summary.wall_time_s) << " |\n";
        std::printf("%-8s h = %-7s swing error %-9s (%.3f s)  loop max %-9s rms %-9s (%.3f s)\n", integrator, fmt(h).c_str(),
                    fmt(worst).c_str(), s.summary.wall_time_s, fmt(c.summary.max_tracking_error).c_str(),
                    fmt(c.summary.rms_tracking_error).c_str(), c.summary.wall_time_s);
      }
    }

    std::ofstream mm(out + "/mujoco_mismatch.csv");
    mm << "plant,stabilization_omega,max_tracking_error,rms_tracking_error,failure\n";
    md << "\n| plant (MuJoCo, rk4, 0.1 ms) | stabilization | max hand error [m] | rms [m] |\n|---|---|---|---|\n";
    for (const char* model : {"arm3.xml", "arm3_heavy.xml"})
      for (double omega : {20.0, 0.0}) {
        const RunResult r = run(arm, {"plant.model=" + models + "/" + model, loop,
                                      "tracking.stabilization={zeta: 1.0, omega: " + fmt(omega) + "}"});
        mm << model << "," << omega << "," << r.summary.max_tracking_error << "," << r.summary.rms_tracking_error << ",\""
           << r.summary.failure << "\"\n";
        md << "| " << model << " | " << (omega > 0 ? "zeta 1, omega " + fmt(omega) : std::string("none")) << " | "
           << fmt(r.summary.max_tracking_error) << " | " << fmt(r.summary.rms_tracking_error) << " |\n";
        std::printf("%-15s omega %-4s max %-9s rms %s\n", model, fmt(omega).c_str(),
                    fmt(r.summary.max_tracking_error).c_str(), fmt(r.summary.rms_tracking_error).c_str());
      }
    if (!csv || !mm || !md) throw std::runtime_error("cannot write into " + out);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
