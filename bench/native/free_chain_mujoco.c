// MuJoCo's mj_forward on the floating chain of issue 15: the MJCF of
// `tests/peers/pinocchio_free_chain.py --xml N`. Usage: free_chain_mujoco MODEL.xml N REPS.
// Times mj_forward, wall and thread CPU time (the whole forward pipeline: positions, velocities, mass matrix and its
// factorization, the accelerations; contacts are disabled in the model) at the state mech
// times: base at the origin, unrotated and at rest, joints at 0.5 rad, joint rates
// 0.3 ((i mod 3) - 1) + 0.1 i. Prints one JSON line: the median over REPS batches of the
// time per call, and qacc in mech's order (base linear, joints, base angular).
#include <mujoco/mujoco.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
static double cpu_now(void) {  // CPU time of this thread: the cost on a shared machine
  struct timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
static int cmp(const void* a, const void* b) {
  double x = *(const double*)a, y = *(const double*)b;
  return (x > y) - (x < y);
}

int main(int argc, char** argv) {
  if (argc < 4) { fprintf(stderr, "usage: %s model.xml N reps\n", argv[0]); return 2; }
  char err[1000];
  mjModel* m = mj_loadXML(argv[1], NULL, err, sizeof err);
  if (!m) { fprintf(stderr, "%s\n", err); return 1; }
  int N = atoi(argv[2]), reps = atoi(argv[3]);
  if (m->nv != N + 6) { fprintf(stderr, "expected %d speeds, the model has %d\n", N + 6, m->nv); return 1; }
  mjData* d = mj_makeData(m);
  mj_resetData(m, d);
  d->qpos[3] = 1.0;  // quaternion (w, x, y, z)
  for (int i = 0; i < N; i++) {
    d->qpos[7 + i] = 0.5;
    d->qvel[6 + i] = 0.3 * ((i % 3) - 1) + 0.1 * i;
  }
  const int K = 100000;
  double* w = malloc(sizeof(double) * reps);
  double* c = malloc(sizeof(double) * reps);
  for (int i = 0; i < 1000; i++) mj_forward(m, d);
  for (int r = 0; r < reps; r++) {
    double t0 = now(), c0 = cpu_now();
    for (int i = 0; i < K; i++) mj_forward(m, d);
    c[r] = (cpu_now() - c0) / K;
    w[r] = (now() - t0) / K;
  }
  qsort(w, reps, sizeof(double), cmp);
  qsort(c, reps, sizeof(double), cmp);
  printf("{\"script\": \"free_chain_mujoco\", \"N\": %d, \"mujoco\": \"%s\", \"forward_ns\": %.6g, "
         "\"forward_ns_min\": %.6g, \"forward_cpu_ns\": %.6g, \"reps\": %d, \"calls_per_rep\": %d, "
         "\"udot\": [",
         N, mj_versionString(), w[reps / 2] * 1e9, w[0] * 1e9, c[reps / 2] * 1e9, reps, K);
  // mech's order: joints, base angular, base linear. The base is unrotated and at rest, so
  // its world acceleration is also the rate of its velocity in its own frame (mech's speeds).
  int k = 0;
  for (int i = 0; i < N; i++) printf("%s%.17g", k++ ? ", " : "", d->qacc[6 + i]);
  for (int i = 3; i < 6; i++) printf("%s%.17g", k++ ? ", " : "", d->qacc[i]);
  for (int i = 0; i < 3; i++) printf("%s%.17g", k++ ? ", " : "", d->qacc[i]);
  printf("]}\n");
  mj_deleteData(d);
  mj_deleteModel(m);
  free(w);
  free(c);
  return 0;
}
