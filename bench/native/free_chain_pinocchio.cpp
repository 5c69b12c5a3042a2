// Pinocchio's ABA on the floating chain of issue 15 (the model of
// tests/peers/pinocchio_free_chain.py and mech-bench's floating_chain_source): a free flyer
// carrying N links (mass 1, mass centre 0.5 below the joint, the peers' full inertia tensor,
// joints 1 apart along -z, axes alternating x, y), gravity -9.81 z.
// Usage: free_chain_pinocchio N REPS. Times aba(model, data, q, v, tau) (wall and thread CPU
// time) at the state mech
// times: base at the origin, unrotated and at rest, joints at 0.5 rad, joint rates
// 0.3 ((i mod 3) - 1) + 0.1 i. Prints one JSON line: the median over REPS batches of the
// time per call, and u̇ there (base at rest and unrotated: Pinocchio's layout is mech's up
// to the order of the blocks).
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <vector>

using namespace pinocchio;
using Clock = std::chrono::steady_clock;

// CPU time of this thread, s: what the calls cost when the machine is shared.
static double cpu_now() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

int main(int argc, char** argv) {
  int N = argc > 1 ? atoi(argv[1]) : 4, reps = argc > 2 ? atoi(argv[2]) : 7;
  Model model;
  Eigen::Matrix3d I3;
  I3 << 0.0845, 0.001, 0.003, 0.001, 0.0855, 0.002, 0.003, 0.002, 0.0125;
  Inertia inertia(1.0, Eigen::Vector3d(0, 0, -0.5), I3);
  JointIndex parent = model.addJoint(0, JointModelFreeFlyer(), SE3::Identity(), "float");
  model.appendBodyToJoint(parent, inertia, SE3::Identity());
  for (int k = 1; k <= N; k++) {
    SE3 placement(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, -1.0));
    std::string name = "q" + std::to_string(k);
    parent = (k % 2 == 1) ? model.addJoint(parent, JointModelRX(), placement, name)
                          : model.addJoint(parent, JointModelRY(), placement, name);
    model.appendBodyToJoint(parent, inertia, SE3::Identity());
  }
  model.gravity.linear(Eigen::Vector3d(0, 0, -9.81));
  Data data(model);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.nq), v = Eigen::VectorXd::Zero(model.nv),
                  tau = Eigen::VectorXd::Zero(model.nv);
  q[6] = 1.0;  // quaternion (x, y, z, w)
  for (int i = 0; i < N; i++) {
    q[7 + i] = 0.5;
    v[6 + i] = 0.3 * ((i % 3) - 1) + 0.1 * i;
  }
  const int K = 100000;
  for (int i = 0; i < 1000; i++) aba(model, data, q, v, tau);
  std::vector<double> w, c;
  for (int r = 0; r < reps; r++) {
    auto t0 = Clock::now();
    double c0 = cpu_now();
    for (int i = 0; i < K; i++) aba(model, data, q, v, tau);
    c.push_back((cpu_now() - c0) / K);
    w.push_back(std::chrono::duration<double>(Clock::now() - t0).count() / K);
  }
  std::sort(w.begin(), w.end());
  std::sort(c.begin(), c.end());
  Eigen::VectorXd a = aba(model, data, q, v, tau);
  printf("{\"script\": \"free_chain_pinocchio\", \"N\": %d, \"aba_ns\": %.6g, \"aba_ns_min\": %.6g, "
         "\"aba_cpu_ns\": %.6g, \"reps\": %d, \"calls_per_rep\": %d, \"udot\": [",
         N, w[w.size() / 2] * 1e9, w[0] * 1e9, c[c.size() / 2] * 1e9, reps, K);
  // mech's order: joints, base angular, base linear (both in the base frame, as here)
  std::vector<double> out;
  for (int i = 0; i < N; i++) out.push_back(a[6 + i]);
  for (int i = 3; i < 6; i++) out.push_back(a[i]);
  for (int i = 0; i < 3; i++) out.push_back(a[i]);
  for (size_t i = 0; i < out.size(); i++) printf("%s%.17g", i ? ", " : "", out[i]);
  printf("]}\n");
  return 0;
}
