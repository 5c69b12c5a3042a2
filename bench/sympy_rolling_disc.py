#!/usr/bin/env python
"""SymPy + SciPy peer of the rolling disc benchmark (issue 15, docs/benchmarks.md).

SymPy's own rolling disc (`test_rolling_disc` of sympy.physics.mechanics, built by
`rolling_disc_kane()` of tests/peers/sympy_models.py: yaw q1, lean q2, spin q3, speeds the
disc's angular velocity in the lean frame, the contact at rest), with r = 0.5 m,
m = 1.5 kg, g = 9.81 m/s^2 as in models/rolling_disc.mech, and mech's start: lean 0.1 rad,
spin rate 4 rad/s, everything else 0 (u = (0, 4, 0)). The contact point's path, which mech
carries as two more coordinates x, y, is integrated beside: x' = r cos(q1) q3',
y' = r sin(q1) q3' (the no-slip rows of the .mech file). SciPy's `solve_ivp` integrates
`mass_matrix_full x' = forcing_full` (lambdified with cse, solved by numpy) over 10 s at
rtol = atol = 1e-9 with DOP853 (and RK45 for comparison).

Prints one JSON line: derivation and lambdify times, the median wall time of the
integration over --reps runs, its evaluation count, and the end state in mech's layout
(x, y, yaw, lean, spin and their rates), for bench/summarize.py to compare with mech's.

    bench/.venv/bin/python bench/sympy_rolling_disc.py [--reps 3]
"""
import argparse
import json
import os
import statistics
import sys
import time

import numpy as np
import scipy
import sympy as sm
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp

sys.path.insert(0, os.path.join(os.path.dirname(__file__), '..', 'tests', 'peers'))
from sympy_models import DISC, rolling_disc_kane  # noqa: E402

T_END = 10.0
TOL = 1e-9


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--reps', type=int, default=3)
    a = ap.parse_args()
    t0 = time.perf_counter()
    KM, (q1, q2, q3, u1, u2, u3), (r, m, g), *_ = rolling_disc_kane()
    derive_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    values = {r: DISC['r'], m: DISC['m'], g: DISC['g']}
    states = [q1, q2, q3, u1, u2, u3]
    mm = KM.mass_matrix_full.subs(values)
    ff = KM.forcing_full.subs(values)
    kd = KM.kindiffdict()
    f_mm = sm.lambdify(states, mm, cse=True)
    f_ff = sm.lambdify(states, ff, cse=True)
    f_qdot = sm.lambdify(states, [kd[q.diff(me.dynamicsymbols._t)].subs(values) for q in (q1, q2, q3)],
                         cse=True)
    lambdify_s = time.perf_counter() - t0
    radius = DISC['r']

    def rhs(_t, x):
        s = x[:6]
        xd = np.linalg.solve(np.asarray(f_mm(*s), dtype=float),
                             np.asarray(f_ff(*s), dtype=float).ravel())
        spin = f_qdot(*s)[2]
        return np.concatenate([xd, [radius * np.cos(s[0]) * spin,
                                    radius * np.sin(s[0]) * spin]])

    x0 = np.array([0.0, 0.1, 0.0, 0.0, 4.0, 0.0, 0.0, 0.0])
    out = dict(script='bench/sympy_rolling_disc.py', sympy=sm.__version__,
               numpy=np.__version__, scipy=scipy.__version__, t_end=T_END, rtol=TOL,
               atol=TOL, derive_s=derive_s, lambdify_s=lambdify_s)
    for method in ('DOP853', 'RK45'):
        walls = []
        for _ in range(a.reps):
            t0 = time.perf_counter()
            sol = solve_ivp(rhs, (0.0, T_END), x0, method=method, rtol=TOL, atol=TOL)
            walls.append(time.perf_counter() - t0)
        assert sol.success, sol.message
        s = sol.y[:, -1]
        qdot = [float(v) for v in f_qdot(*s[:6])]
        spin = qdot[2]
        # mech's layout: x, y, yaw, lean, spin; x', y', yaw', lean', spin'
        out[method] = dict(
            wall_s=statistics.median(walls), wall_s_all=walls, nfev=int(sol.nfev),
            q_final=[float(s[6]), float(s[7]), float(s[0]), float(s[1]), float(s[2])],
            u_final=[radius * np.cos(s[0]) * spin, radius * np.sin(s[0]) * spin] + qdot)
    print(json.dumps(out), flush=True)


if __name__ == '__main__':
    main()
