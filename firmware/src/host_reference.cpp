// The host's run of the firmware loop (loop.hpp) in double precision: the reference the target's
// trajectory is compared with. usage: firmware_reference duffing|arm|closed_form|duffing_held|arm_held|cart_pole|arm_passive_wrist|differential_drive
// OUT.bin. Writes per period t, q, q', u as float64 in the target's layout.
#include <cstdio>
#include <cstring>
#include <vector>

#include "loop.hpp"

namespace {

template <firmware::Law L>
int run(const char* path) {
  firmware::Loop<L, double> loop;
  constexpr int N = firmware::Loop<L, double>::N;
  std::vector<double> rows;
  rows.reserve(static_cast<std::size_t>(firmware::kPeriods) * (1 + 3 * N));
  Eigen::Matrix<double, N, 1> u;
  for (int k = 0; k < firmware::kPeriods; ++k) {
    const double t = k * firmware::kPeriod;
    const Eigen::Matrix<double, N, 1> q = loop.q(), qd = loop.qd();
    if (gausstrack::failed(loop.control(q, qd, t, u))) return std::fprintf(stderr, "law failed at t = %g\n", t), 1;
    rows.push_back(t);
    for (int i = 0; i < N; ++i) rows.push_back(q(i));
    for (int i = 0; i < N; ++i) rows.push_back(qd(i));
    for (int i = 0; i < N; ++i) rows.push_back(u(i));
    loop.advance(u, t, firmware::kPeriod);
  }
  // The library's laws track: the run ends on the path (a start off it, as the differential
  // drive's 0.14 m, is forgotten within the 10 s). The closed form carries no stabilization.
  const double final_error = loop.tracking_error(firmware::kPeriods * firmware::kPeriod);
  std::printf("final_tracking_error %.3g\n", final_error);
  if (L != firmware::Law::kClosedForm && !(final_error <= 1e-3))
    return std::fprintf(stderr, "the law did not track: final tracking error %g m\n", final_error), 1;
  std::FILE* f = std::fopen(path, "wb");
  if (!f || std::fwrite(rows.data(), sizeof(double), rows.size(), f) != rows.size() || std::fclose(f) != 0)
    return std::fprintf(stderr, "cannot write %s\n", path), 1;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) return std::fprintf(stderr, "usage: %s duffing|arm|closed_form|duffing_held|arm_held|cart_pole|arm_passive_wrist|differential_drive OUT.bin\n", argv[0]), 2;
  if (!std::strcmp(argv[1], "duffing")) return run<firmware::Law::kDuffing>(argv[2]);
  if (!std::strcmp(argv[1], "arm")) return run<firmware::Law::kArm>(argv[2]);
  if (!std::strcmp(argv[1], "closed_form")) return run<firmware::Law::kClosedForm>(argv[2]);
  if (!std::strcmp(argv[1], "duffing_held")) return run<firmware::Law::kDuffingHeld>(argv[2]);
  if (!std::strcmp(argv[1], "arm_held")) return run<firmware::Law::kArmHeld>(argv[2]);
  if (!std::strcmp(argv[1], "cart_pole")) return run<firmware::Law::kCartPole>(argv[2]);
  if (!std::strcmp(argv[1], "arm_passive_wrist")) return run<firmware::Law::kArmPassiveWrist>(argv[2]);
  if (!std::strcmp(argv[1], "differential_drive")) return run<firmware::Law::kDifferentialDrive>(argv[2]);
  return std::fprintf(stderr, "unknown law %s\n", argv[1]), 2;
}
