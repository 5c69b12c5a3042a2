#!/usr/bin/env python
"""SymPy KanesMethod baseline: the spherical five-bar of models/spherical_five_bar.mech,
with dependent coordinates and speeds, integrated with SciPy.

Usage (from the repository root):
    bench/.venv/bin/python bench/sympy_fivebar.py [--reps R] [--no-pydy]

The companion of ../shared/peers/sympy_fourbar.py (same structure, same JSON keys, same
solve_ivp settings: rtol = atol = 1e-9, RK45 and DOP853, no t_eval), written for
docs/benchmarks.md. The geometry is transcribed from models/spherical_five_bar.mech:

  coordinates (mech's joint order and sign conventions, all pins, all hinge axes through O):
    qa  = ground_a : A = N rotated by qa  about N.x   (spring k, damper c)
    qab = a_b      : B = A rotated by qab about A.y
    qd  = ground_d : D = N rotated by qd  about N.y   (spring k, damper c)
    qdc = d_c      : C = D rotated by qdc about D.x
  every body's origin is O; mass centres (body coordinates): a (0, arm/2, -arm/2),
  b (arm/2, 0, -arm), c (-arm/2, 0, -arm), d (arm/2, 0, -arm/2); each body has mass m and
  central inertia diag(m arm^2/12) in its own frame; gravity -9.81 N.z.
  The loop b_c = revolute(b, c_link), axis z, at (0, 0, arm) in both B and C. mech writes
  5 rows (rank 2): the gap arm (C.z - B.z) in N (3 rows), align1 = B.z . C.y and
  align2 = B.z . (-C.x) (e1 = z x x = y, e2 = z x e1 = -x, perpendiculars of the axis).
  The loop is springy (stiffness k, rest 0): theta = atan2((B.y x C.y) . B.z, B.y . C.y),
  torque -k theta B.z on C and +k theta B.z on B, energy k theta^2 / 2.

KanesMethod needs independent constraint rows, as many as dependent coordinates; the
closure has rank 2, so this script gives it the two ALIGNMENT rows (align2, align1) as
configuration constraints and their time derivatives as velocity constraints. With the
two hinge axes through O, aligned axes imply the closing points coincide (same branch), so
the three gap rows are implied; the script checks all five mech rows at the start and end.
Independent: qa, qab (held during assembly, as mech's bench and tests/loops.rs hold
ground_a and a_b); dependent: qd, qdc (solved by fsolve from qd = qab, qdc = qa).
Initial state: qa = 5 deg, qab = 3 deg (the .mech q0), all speeds 0.

Prints ONE JSON line.
"""
import argparse
import json
import math
import statistics
import time

import numpy as np
import sympy as sm
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

# SI values of the .mech defaults: m = 2 mg, arm = 1 mm, k = 0.05 uN*m/rad, c = 2e-10 N*m*s/rad.
VALUES = dict(m=2e-6, arm=1e-3, k=0.05e-6, c=2e-10, g=9.81)
QA_0, QAB_0 = math.radians(5.0), math.radians(3.0)


def build():
    qa, qab, qd, qdc = me.dynamicsymbols('qa qab qd qdc')
    ua, uab, ud, udc = me.dynamicsymbols('ua uab ud udc')
    m, arm, k, c, g = sm.symbols('m arm k c g')
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame('N')
    A = N.orientnew('A', 'Axis', [qa, N.x])
    B = A.orientnew('B', 'Axis', [qab, A.y])
    D = N.orientnew('D', 'Axis', [qd, N.y])
    C = D.orientnew('C', 'Axis', [qdc, D.x])
    A.set_ang_vel(N, ua * N.x)
    B.set_ang_vel(A, uab * A.y)
    D.set_ang_vel(N, ud * N.y)
    C.set_ang_vel(D, udc * D.x)
    O = me.Point('O')
    O.set_vel(N, 0)
    coms = {
        'a': (A, arm / 2 * A.y - arm / 2 * A.z),
        'b': (B, arm / 2 * B.x - arm * B.z),
        'c_link': (C, -arm / 2 * C.x - arm * C.z),
        'd': (D, arm / 2 * D.x - arm / 2 * D.z),
    }
    bodies, loads = [], []
    pe = 0
    for name, (frame, offset) in coms.items():
        G = O.locatenew('G_' + name, offset)
        G.v2pt_theory(O, N, frame)
        inertia = m * arm ** 2 / 12
        body = me.RigidBody(name, G, frame, m, (me.inertia(frame, inertia, inertia, inertia), G))
        bodies.append(body)
        loads.append((G, -m * g * N.z))
        pe += m * g * G.pos_from(O).dot(N.z)
    # Ground hinge springs and dampers (parent N: no reaction).
    loads.append((A, (-k * qa - c * ua) * N.x))
    loads.append((D, (-k * qd - c * ud) * N.y))
    pe += k * qa ** 2 / 2 + k * qd ** 2 / 2
    # The springy closing hinge.
    theta = sm.atan2(B.y.cross(C.y).dot(B.z), B.y.dot(C.y))
    loads.append((C, -k * theta * B.z))
    loads.append((B, k * theta * B.z))
    pe += k * theta ** 2 / 2

    gap = arm * (C.z - B.z)
    all_rows = [gap.dot(N.x), gap.dot(N.y), gap.dot(N.z), B.z.dot(C.y), -B.z.dot(C.x)]
    # align2 first: near the rest position align2 ~ qd - qab and align1 ~ qdc - qa, so this
    # order keeps the diagonal of d(rows)/d(qd, qdc) away from zero (KanesMethod eliminates
    # the dependent speeds symbolically, without pivoting).
    config_cons = [all_rows[4], all_rows[3]]
    q = [qa, qab, qd, qdc]
    u = [ua, uab, ud, udc]
    qdot_to_u = dict(zip([s.diff(t) for s in q], u))
    vel_cons = [sm.diff(row, t).subs(qdot_to_u) for row in config_cons]
    kd = [s.diff(t) - v for s, v in zip(q, u)]
    kane = me.KanesMethod(N, q_ind=[qa, qab], u_ind=[ua, uab], kd_eqs=kd,
                          q_dependent=[qd, qdc], configuration_constraints=config_cons,
                          u_dependent=[ud, udc], velocity_constraints=vel_cons)
    ke = sum(b.kinetic_energy(N) for b in bodies)
    return dict(kane=kane, bodies=bodies, loads=loads, q=q, u=u, p=[m, arm, k, c, g],
                cc=config_cons, vc=vel_cons, rows=all_rows, energy=ke + pe)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--reps', type=int, default=5, help='repetitions of numeric timings')
    ap.add_argument('--no-pydy', action='store_true')
    a = ap.parse_args()
    out = dict(script='sympy_fivebar', sympy=sm.__version__,
               constraint_rows='align2, align1 (of mech b_c.x, .y, .z, .align1, .align2)')

    t0 = time.perf_counter()
    mdl = build()
    out['setup_s'] = time.perf_counter() - t0
    kane = mdl['kane']
    t0 = time.perf_counter()
    kane.kanes_equations(mdl['bodies'], mdl['loads'])
    out['kanes_equations_s'] = time.perf_counter() - t0
    Mf, ff = kane.mass_matrix_full, kane.forcing_full
    out['ops_mass_matrix_full'] = int(sum(sm.count_ops(e) for e in Mf))
    out['ops_forcing_full'] = int(sum(sm.count_ops(e) for e in ff))

    q, u, p = mdl['q'], mdl['u'], mdl['p']
    pv = [VALUES[str(s)] for s in p]
    t0 = time.perf_counter()
    eom = sm.lambdify([q, u, p], [Mf, ff], cse=True)
    cc_f = sm.lambdify([q, p], mdl['cc'], cse=True)
    vc_f = sm.lambdify([q, u, p], mdl['vc'], cse=True)
    rows_f = sm.lambdify([q, p], mdl['rows'], cse=True)
    en_f = sm.lambdify([q, u, p], mdl['energy'], cse=True)
    out['lambdify_s'] = time.perf_counter() - t0

    # Consistent initial state: qa, qab held, (qd, qdc) from the two alignment rows.
    sol = fsolve(lambda z: cc_f([QA_0, QAB_0, z[0], z[1]], pv), [QAB_0, QA_0], xtol=1e-14)
    q0 = [QA_0, QAB_0, float(sol[0]), float(sol[1])]
    # Velocity constraints are linear in (ud, udc); the independent speeds are 0.
    b = -np.array(vc_f(q0, [0.0, 0.0, 0.0, 0.0], pv), float)
    A = np.column_stack([np.array(vc_f(q0, [0.0, 0.0, 1.0, 0.0], pv), float) + b,
                         np.array(vc_f(q0, [0.0, 0.0, 0.0, 1.0], pv), float) + b])
    u_dep = np.linalg.solve(A, b)
    x0 = np.array(q0 + [0.0, 0.0, float(u_dep[0]), float(u_dep[1])])
    out['x0'] = x0.tolist()
    out['x0_constraint_residual'] = float(np.max(np.abs(cc_f(q0, pv))))
    out['x0_mech_rows_residual'] = float(np.max(np.abs(rows_f(q0, pv))))

    def rhs(t, x):
        M, f = eom(x[:4], x[4:], pv)
        return np.linalg.solve(M, f).ravel()

    # u-dot at x0, for the cross-check against mech's constrained u-dot.
    out['udot0'] = rhs(0.0, x0)[4:].tolist()

    nev = 2000
    per = []
    for _ in range(a.reps):
        t0 = time.perf_counter()
        for _ in range(nev):
            rhs(0.0, x0)
        per.append((time.perf_counter() - t0) / nev)
    out['rhs_eval_us_median'] = statistics.median(per) * 1e6

    E0 = float(en_f(x0[:4], x0[4:], pv))
    for method in ['RK45', 'DOP853']:
        times = []
        for _ in range(a.reps):
            t0 = time.perf_counter()
            res = solve_ivp(rhs, (0.0, 1.0), x0, method=method, rtol=1e-9, atol=1e-9)
            times.append(time.perf_counter() - t0)
        xf = res.y[:, -1]
        out[f'sim1s_{method}'] = dict(
            wall_s_median=statistics.median(times), wall_s_all=times, nfev=int(res.nfev),
            q1_final=float(xf[0]), x_final=xf.tolist(),
            constraint_residual=float(np.max(np.abs(cc_f(xf[:4], pv)))),
            mech_rows_residual=float(np.max(np.abs(rows_f(xf[:4], pv)))),
            energy_drift=float(en_f(xf[:4], xf[4:], pv)) - E0)

    if not a.no_pydy:
        try:
            from pydy.system import System
            allc = dict(zip(p, pv))
            ics = dict(zip(q + u, x0.tolist()))
            times = np.linspace(0.0, 1.0, 101)
            for gen in ['lambdify', 'cython']:
                sysm = System(kane, initial_conditions=ics, times=times)
                sysm.constants = {s: allc[s] for s in sysm.constants_symbols}
                t0 = time.perf_counter()
                sysm.generate_ode_function(generator=gen)
                gen_s = time.perf_counter() - t0
                ws = []
                for _ in range(a.reps):
                    t0 = time.perf_counter()
                    traj = sysm.integrate(rtol=1e-9, atol=1e-9)
                    ws.append(time.perf_counter() - t0)
                names = [str(s) for s in sysm.states]
                out[f'pydy_system_{gen}'] = dict(
                    generate_s=gen_s, integrate_odeint_s_median=statistics.median(ws),
                    q1_final=float(traj[-1, names.index('qa(t)')]))
        except Exception as e:  # pragma: no cover
            out['pydy_error'] = repr(e)[:300]
    print(json.dumps(out), flush=True)


if __name__ == '__main__':
    main()
