#!/usr/bin/env python3
"""SymPy KanesMethod reference for the planar four-bar (models/four_bar.mech), independent
of mech: the numbers quoted by tests/equations/loops.rs and tests/equations/reduced.rs.

Trimmed from the shared benchmark script peers/sympy_fourbar.py (the derivation is
unchanged; timings, operation counts and the PyDy runs are left out).

Regenerate (from the repository root; README.md lists the versions used):
    python3 -m venv .venv && .venv/bin/pip install sympy==1.14.0 numpy==2.4.6 scipy==1.17.1
    .venv/bin/python tests/peers/sympy_fourbar.py

Model: absolute link angles from N.x, rotation about N.z, gravity -g N.y.
  ground  O=(0,0) -> D=(L0,0)            (fixed)
  crank   O -> A = O + L1*B1.x            angle q1 (independent)
  coupler A -> B = A + L2*B2.x            angle q2 (dependent)
  rocker  D -> C = D + L3*B3.x            angle q3 (dependent)
  loop closure (configuration constraints): (B - C).N.x = 0, (B - C).N.y = 0
  velocity constraints: time derivative of the above (in u1, u2, u3)
  uniform slender rods: mass m_i, centroidal inertia m_i L_i^2/12 about z,
  mass centre at the link midpoint.
Values: L0=3, L1=1, L2=2.5, L3=2 (Grashof crank-rocker, no toggle), m_i=1, g=9.81.
Initial state: q1=1.0 rad, u1=2.0 rad/s, q2, q3, u2, u3 solved for consistency (the "open"
assembly branch, q2 ~ 0.4755, q3 ~ 1.6896 rad; fsolve at xtol 1e-14).
Motion: full state (q1,q2,q3,u1,u2,u3), xdot = solve(M_full, f_full) (KanesMethod's
mass_matrix_full/forcing_full, the dependent speeds eliminated), scipy solve_ivp over 1 s
with rtol = atol = 1e-9 (RK45 and DOP853), no projection.

mech's coupler angle is relative to the crank: its absolute angle is q1 + q2 here.
"""
import json

import numpy as np
import scipy
import sympy as sm
import sympy.physics.mechanics as me
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

VALUES = dict(L0=3.0, L1=1.0, L2=2.5, L3=2.0, m1=1.0, m2=1.0, m3=1.0, g=9.81)
Q1_0, U1_0 = 1.0, 2.0


def build():
    q1, q2, q3 = me.dynamicsymbols('q1:4')
    u1, u2, u3 = me.dynamicsymbols('u1:4')
    L0, L1, L2, L3, m1, m2, m3, g = sm.symbols('L0 L1 L2 L3 m1 m2 m3 g')
    t = me.dynamicsymbols._t
    N = me.ReferenceFrame('N')
    B1 = N.orientnew('B1', 'Axis', [q1, N.z])
    B2 = N.orientnew('B2', 'Axis', [q2, N.z])
    B3 = N.orientnew('B3', 'Axis', [q3, N.z])
    B1.set_ang_vel(N, u1 * N.z)
    B2.set_ang_vel(N, u2 * N.z)
    B3.set_ang_vel(N, u3 * N.z)
    O = me.Point('O')
    O.set_vel(N, 0)
    D = O.locatenew('D', L0 * N.x)
    D.set_vel(N, 0)
    A = O.locatenew('A', L1 * B1.x)
    A.v2pt_theory(O, N, B1)
    Bp = A.locatenew('B', L2 * B2.x)
    Bp.v2pt_theory(A, N, B2)
    C = D.locatenew('C', L3 * B3.x)
    C.v2pt_theory(D, N, B3)
    G1 = O.locatenew('G1', L1 / 2 * B1.x)
    G1.v2pt_theory(O, N, B1)
    G2 = A.locatenew('G2', L2 / 2 * B2.x)
    G2.v2pt_theory(A, N, B2)
    G3 = D.locatenew('G3', L3 / 2 * B3.x)
    G3.v2pt_theory(D, N, B3)

    loop = Bp.pos_from(O) - C.pos_from(O)
    config_cons = [loop.dot(N.x), loop.dot(N.y)]
    vloop = Bp.vel(N) - C.vel(N)
    vel_cons = [vloop.dot(N.x), vloop.dot(N.y)]
    kd = [q1.diff(t) - u1, q2.diff(t) - u2, q3.diff(t) - u3]

    bodies = []
    loads = []
    for nm, fr, G, m, L in [('crank', B1, G1, m1, L1), ('coupler', B2, G2, m2, L2),
                            ('rocker', B3, G3, m3, L3)]:
        I = me.inertia(fr, 0, 0, m * L ** 2 / 12)
        bodies.append(me.RigidBody(nm, G, fr, m, (I, G)))
        loads.append((G, -m * g * N.y))

    kane = me.KanesMethod(N, q_ind=[q1], u_ind=[u1], kd_eqs=kd,
                          q_dependent=[q2, q3], configuration_constraints=config_cons,
                          u_dependent=[u2, u3], velocity_constraints=vel_cons)
    kane.kanes_equations(bodies, loads)
    return dict(kane=kane, q=[q1, q2, q3], u=[u1, u2, u3],
                p=[L0, L1, L2, L3, m1, m2, m3, g], cc=config_cons, vc=vel_cons)


def main():
    mdl = build()
    kane = mdl['kane']
    q, u, p = mdl['q'], mdl['u'], mdl['p']
    pv = [VALUES[str(s)] for s in p]
    eom = sm.lambdify([q, u, p], [kane.mass_matrix_full, kane.forcing_full], cse=True)
    cc_f = sm.lambdify([q, p], mdl['cc'], cse=True)
    vc_f = sm.lambdify([q, u, p], mdl['vc'], cse=True)

    # consistent initial state (open branch)
    sol = fsolve(lambda z: cc_f([Q1_0, z[0], z[1]], pv), [0.3, 1.8], xtol=1e-14)
    q0 = [Q1_0, float(sol[0]), float(sol[1])]
    # velocity constraints are linear in (u2, u3)
    b = -np.array(vc_f(q0, [U1_0, 0.0, 0.0], pv), float)
    A = np.column_stack([np.array(vc_f(q0, [U1_0, 1.0, 0.0], pv), float) + b,
                         np.array(vc_f(q0, [U1_0, 0.0, 1.0], pv), float) + b])
    u23 = np.linalg.solve(A, b)
    x0 = np.array(q0 + [U1_0, float(u23[0]), float(u23[1])])

    def rhs(t, x):
        M, f = eom(x[:3], x[3:], pv)
        return np.linalg.solve(M, f).ravel()

    out = dict(script='tests/peers/sympy_fourbar.py', sympy=sm.__version__,
               numpy=np.__version__, scipy=scipy.__version__,
               x0=x0.tolist(), x0_constraint_residual=float(np.max(np.abs(cc_f(q0, pv)))))
    for method in ['RK45', 'DOP853']:
        res = solve_ivp(rhs, (0.0, 1.0), x0, method=method, rtol=1e-9, atol=1e-9)
        xf = res.y[:, -1]
        out[f'sim1s_{method}'] = dict(
            nfev=int(res.nfev), q1_final=float(xf[0]),
            constraint_residual=float(np.max(np.abs(cc_f(xf[:3], pv)))))
    print(json.dumps(out, indent=1), flush=True)


if __name__ == '__main__':
    main()
