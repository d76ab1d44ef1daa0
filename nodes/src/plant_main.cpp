// gausstrack-plant --scene S [common options] [--lockstep] [--out DIR] [--timeout-ms T]
//                  [--watchdog-ms W] [--safe-action zero|hold] [--hold-lag L] [--spin-us S]
#include "gausstrack/nodes/plant_process.hpp"
#ifdef GAUSSTRACK_HAVE_MUJOCO
#include "gausstrack/plant_sim/mujoco.hpp"
#endif

int main(int argc, char** argv) {
#ifdef GAUSSTRACK_HAVE_MUJOCO
  return gausstrack::nodes::plant_main(argc, argv, {}, {gausstrack::plant_sim::mujoco_engine()});
#else
  return gausstrack::nodes::plant_main(argc, argv);
#endif
}
