// gausstrack-plant --scene S [common options] [--lockstep] [--out DIR] [--timeout-ms T]
//                  [--watchdog-ms W] [--safe-action zero|hold]
#include "gausstrack/nodes/plant_process.hpp"

int main(int argc, char** argv) { return gausstrack::nodes::plant_main(argc, argv); }
