#!/usr/bin/env python3
"""Independent SymPy reference for mech: derives each model below with
sympy.physics.mechanics.KanesMethod and writes M(q), forcing F(q, u) (with
M u' = F, q' = u; q' = W(q) u for the unit quaternions of ball joints and for speeds chosen
by `speed`), kinetic and potential energy at fixed pseudo-random states
to tests/peers/fixture.json.  For the loop models (four_bar, slider_crank: open tree plus
coincident closures; compliant_four_bar: a flexure at every pin, one of them on a revolute
closure) also phi(q), J = dphi/dq and J'u.  Model definitions and conventions:
README.md.

Regenerate (from the repository root):
    python3 -m venv .venv && .venv/bin/pip install sympy==1.14.0
    .venv/bin/python tests/peers/sympy_models.py
The output is deterministic (same bytes on every run with the same SymPy).
"""
import json
import math
import os
import random
import sys
import time

import mpmath
import sympy as sm
import sympy.physics.mechanics as me

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, 'fixture.json')
G_ACC = '9.81'
N_STATES = 3
DPS = 50                       # mpmath working precision (decimal digits)
t = me.dynamicsymbols._t


def R(v):
    """Exact rational of a decimal literal (0.0845 -> 169/2000)."""
    return sm.Rational(str(v))


class Model:
    """A tree of rigid bodies built from pin/slider joints, plus loads."""

    def __init__(self, name):
        self.name = name
        self.N = me.ReferenceFrame('N')
        self.O = me.Point('O')
        self.O.set_vel(self.N, 0)
        self.q, self.u, self.coords = [], [], []
        # Ball joints, in mech's layout after the pins' and sliders' coordinates and speeds:
        # quaternion coordinates (scalar first), angular speeds and q' = W(q) u.
        self.quaternions, self.angular_speeds, self.quaternion_rates = [], [], []
        self.quaternion_names, self.speed_names = [], []
        # Free joints' positions, after the quaternions: coordinates x, y, z along N's axes,
        # speeds the origin's velocity in the child's basis, q' = R v.
        self.translations, self.velocity_speeds, self.translation_rates = [], [], []
        self.translation_names, self.velocity_names = [], []
        self.bodies, self.loads, self.nc_loads = [], [], []
        self.joints, self.pe, self.params = {}, sm.S(0), {'g': float(G_ACC)}
        self.up = self.N.z             # gravity acts along -up
        self.loops, self.loop_names = [], []   # closure rows phi_k(q) (vectors . N axes)
        self.chosen_speeds = []        # (name, u_r as an expression of q, q'), or [] for u = q'

    def point(self, name, base, offset):
        p = base.locatenew(name, offset)
        p.set_vel(self.N, p.pos_from(self.O).dt(self.N))
        return p

    def vec(self, frame, xyz):
        return sum((R(c) * e for c, e in zip(xyz, (frame.x, frame.y, frame.z))), me.Vector(0))

    def _coord(self, name):
        q, u = me.dynamicsymbols(f'{name} u_{name}')
        self.q.append(q), self.u.append(u), self.coords.append(name)
        return q

    def pin(self, name, parent, joint_pt, axis, frame_name):
        """Child frame = parent rotated by q about `axis` (fixed in parent)."""
        q = self._coord(name)
        B = parent.orientnew(frame_name, 'Axis', [q, axis])
        self.joints[name] = ('pin', parent, B, axis, joint_pt, None)
        return B

    def ball(self, name, parent, frame_name):
        """Child frame = parent turned by the unit quaternion e (scalar first, SymPy's
        'Quaternion' orientation: parent.dcm(child) = (e0^2 - eps.eps) I + 2 eps eps^T
        + 2 e0 [eps]x); speeds w = the child's angular velocity relative to the parent in the
        child's basis, e' = 1/2 e (x) (0, w) (Hamilton product)."""
        e = me.dynamicsymbols(' '.join(f'{name}.e{k}' for k in range(4)))
        w = me.dynamicsymbols(' '.join(f'u_{name}.w{a}' for a in 'xyz'))
        B = parent.orientnew(frame_name, 'Quaternion', e)
        B.set_ang_vel(parent, w[0] * B.x + w[1] * B.y + w[2] * B.z)
        p = [0, *w]
        rates = [(e[0] * p[0] - e[1] * p[1] - e[2] * p[2] - e[3] * p[3]) / 2,
                 (e[0] * p[1] + e[1] * p[0] + e[2] * p[3] - e[3] * p[2]) / 2,
                 (e[0] * p[2] - e[1] * p[3] + e[2] * p[0] + e[3] * p[1]) / 2,
                 (e[0] * p[3] + e[1] * p[2] - e[2] * p[1] + e[3] * p[0]) / 2]
        self.quaternions += e
        self.angular_speeds += w
        self.quaternion_rates += rates
        self.quaternion_names += [f'{name}.e{k}' for k in range(4)]
        self.speed_names += [f'{name}.w{a}' for a in 'xyz']
        return B

    def free(self, name, frame_name):
        """A free joint in N: the ball `name` turning `frame_name`, and the child's origin P at
        x N.x + y N.y + z N.z with speeds v = (vx, vy, vz), its velocity in N in the child's
        basis (Kane's choice), so (x', y', z') = the N measure numbers of v."""
        A = self.ball(name, self.N, frame_name)
        x = me.dynamicsymbols(' '.join(f'{name}.{a}' for a in 'xyz'))
        v = me.dynamicsymbols(' '.join(f'u_{name}.v{a}' for a in 'xyz'))
        P = self.point('P', self.O, x[0] * self.N.x + x[1] * self.N.y + x[2] * self.N.z)
        velocity = v[0] * A.x + v[1] * A.y + v[2] * A.z
        self.translations += x
        self.velocity_speeds += v
        self.translation_rates += [velocity.dot(e) for e in (self.N.x, self.N.y, self.N.z)]
        self.translation_names += [f'{name}.{a}' for a in 'xyz']
        self.velocity_names += [f'{name}.v{a}' for a in 'xyz']
        return A, P

    def slider(self, name, parent, parent_origin, offset, axis, frame_name):
        """Child frame parallel to parent; child origin = parent_origin + offset + q*axis."""
        q = self._coord(name)
        B = parent.orientnew(frame_name, 'Axis', [0, parent.z])
        P = self.point(f'{frame_name}o', parent_origin, offset + q * axis)
        self.joints[name] = ('slider', parent, B, axis, P, parent_origin)
        return B, P

    def body(self, name, frame, origin, m, com, I):
        G = self.point(f'G_{name}', origin, self.vec(frame, com))
        self.bodies.append(me.RigidBody(name, G, frame, R(m), (me.inertia(frame, *map(R, I)), G)))
        self.loads.append((G, -R(m) * R(G_ACC) * self.up))
        self.pe += R(m) * R(G_ACC) * G.pos_from(self.O).dot(self.up)
        self.params.update({f'{name}.mass': m, f'{name}.com': list(com), f'{name}.inertia': list(I)})
        return G

    def _joint_load(self, coord, mag, conservative):
        """Equal/opposite torque (pin) or force (slider) along the joint axis."""
        kind, parent, child, axis, pt, porigin = self.joints[coord]
        if kind == 'pin':
            pairs = [(child, mag * axis)] + ([(parent, -mag * axis)] if parent != self.N else [])
        else:
            pairs = [(pt, mag * axis)]
            if parent != self.N:   # reaction at the parent's material point under the child origin
                pp = porigin.locatenew(pt.name + '_p', pt.pos_from(porigin))
                pp.v2pt_theory(porigin, self.N, parent)
                pairs.append((pp, -mag * axis))
        self.loads += pairs
        if not conservative:
            self.nc_loads += pairs

    def spring(self, coord, k, rest):
        q = self.q[self.coords.index(coord)]
        self.pe += R(k) / 2 * (q - R(rest)) ** 2
        self._joint_load(coord, -R(k) * (q - R(rest)), True)
        self.params.update({f'{coord}.spring_k': k, f'{coord}.spring_rest': rest})

    def damper(self, coord, c):
        self._joint_load(coord, -R(c) * self.u[self.coords.index(coord)], False)
        self.params[f'{coord}.damper_c'] = c

    def point_spring(self, a, b, k, rest, c):
        """A spring-damper between points a and b: with d = r_b - r_a, L = |d|, e = d/L and
        L' = e.(v_b - v_a), the tension T = k (L - rest) + c L' acts as -T e on b and +T e on
        a; (1/2) k (L - rest)^2 of potential energy; the damper's part is non-conservative."""
        d = b.pos_from(a)
        length = d.magnitude()
        e = d / length
        rate = e.dot(b.vel(self.N) - a.vel(self.N))
        self.pe += R(k) / 2 * (length - R(rest)) ** 2
        spring, damper = R(k) * (length - R(rest)), R(c) * rate
        self.loads += [(b, -(spring + damper) * e), (a, (spring + damper) * e)]
        self.nc_loads += [(b, -damper * e), (a, damper * e)]
        return length, rate

    def contact(self, centre, body, anchor, plane, normal, radius, k, exponent, depth, alpha,
                mu, v_s):
        """Hunt-Crossley contact of a sphere (radius, centre fixed in `body`) with the plane
        through `anchor` (fixed in `plane`) of unit normal `normal` (a vector fixed in `plane`):
        gap h = n.(centre - anchor) - radius, penetration d = max(0, -h), C = centre - radius n
        as a material point of each frame (v2pt_theory), v = v_C(body) - v_C(plane),
        d' = -n.v; f_n = max(0, kk d^e (1 + 3/2 alpha d')) with kk = k depth^(1-e),
        f_t = -mu f_n v_t / sqrt(|v_t|^2 + v_s^2), v_t = v - (n.v) n; f = f_n n + f_t on the
        body at C, -f on the plane at C; kk d^(e+1)/(e+1) of potential energy, the rest of
        f non-conservative."""
        n, e = normal, R(exponent)
        h = n.dot(centre.pos_from(anchor)) - R(radius)
        on_body = centre.locatenew('C_body', -R(radius) * n)
        on_body.v2pt_theory(centre, self.N, body)
        on_plane = anchor.locatenew('C_plane', on_body.pos_from(anchor))
        on_plane.v2pt_theory(anchor, self.N, plane)
        v = on_body.vel(self.N) - on_plane.vel(self.N)
        rate = -n.dot(v)
        depth_now = sm.Piecewise((-h, h < 0), (0, True))
        kk = R(k) * R(depth) ** (1 - e)
        elastic = kk * depth_now ** e
        raw = elastic * (1 + sm.Rational(3, 2) * R(alpha) * rate)
        normal_force = sm.Piecewise((raw, raw > 0), (0, True))
        slip = v - n.dot(v) * n
        friction = -R(mu) * normal_force / sm.sqrt(slip.dot(slip) + R(v_s) ** 2) * slip
        f = normal_force * n + friction
        self.loads += [(on_body, f), (on_plane, -f)]
        dissipative = f - elastic * n
        self.nc_loads += [(on_body, dissipative), (on_plane, -dissipative)]
        self.pe += kk * depth_now ** (e + 1) / (e + 1)

    def external(self, key, target, vector, value):
        self.loads.append((target, vector)), self.nc_loads.append((target, vector))
        self.params[key] = value

    def coincident(self, name, parent_pt, child_pt, components):
        """Loop rows: the listed N components of r(child_pt) - r(parent_pt), in order."""
        r = child_pt.pos_from(self.O) - parent_pt.pos_from(self.O)
        for c in components:
            self.loops.append((r, getattr(self.N, c)))
            self.loop_names.append(f'{name}.{c}')

    def revolute(self, name, parent_pt, child_pt, axis_parent, e1_child, e2_child):
        """Revolute closure rows: r(child_pt) - r(parent_pt) in N (x, y, z), then the axis
        (fixed in the parent) dotted with two directions perpendicular to it fixed in the child."""
        self.coincident(name, parent_pt, child_pt, 'xyz')
        for k, e in enumerate((e1_child, e2_child), start=1):
            self.loops.append((axis_parent, e))
            self.loop_names.append(f'{name}.align{k}')

    def _flexure_params(self, name, k, eta, f_ref, rest_deg):
        """Torsional spring k and viscous damper b = k eta / (2 pi f_ref) (Eq. 5), rest in rad."""
        self.params.update({f'{name}.loss_factor': eta, f'{name}.reference_frequency_Hz': f_ref,
                            f'{name}.rest_deg': rest_deg})
        return R(eta) * k / (2 * sm.pi * R(f_ref)), R(rest_deg) * sm.pi / 180

    def flexure(self, name, coord, k, eta, f_ref, rest_deg):
        """A flexure on a pin joint: spring -k (q - rest) and damper -b u along the joint axis."""
        b, rest = self._flexure_params(name, k, eta, f_ref, rest_deg)
        q, u = (v[self.coords.index(coord)] for v in (self.q, self.u))
        self.pe += k / 2 * (q - rest) ** 2
        self._joint_load(coord, -k * (q - rest), True)
        self._joint_load(coord, -b * u, False)

    def loop_flexure(self, name, parent, child, axis, theta, k, eta, f_ref, rest_deg):
        """A flexure on a revolute closure: the torque -k (theta - rest) - b theta' about `axis`
        on the child frame and the opposite on the parent. theta is the child's rotation
        relative to the parent about `axis`; theta' comes from the frames' angular velocities."""
        b, rest = self._flexure_params(name, k, eta, f_ref, rest_deg)
        qd = {qi.diff(t): ui for qi, ui in zip(self.q, self.u)}
        rate = (child.ang_vel_in(self.N) - parent.ang_vel_in(self.N)).dot(axis).xreplace(qd)
        self.pe += k / 2 * (theta - rest) ** 2
        for mag, conservative in ((-k * (theta - rest), True), (-b * rate, False)):
            pairs = [(child, mag * axis), (parent, -mag * axis)]
            self.loads += pairs
            if not conservative:
                self.nc_loads += pairs


# ---------------------------------------------------------------- models
# Chain parameters copied from ../shared/peers/chain_model.py (PARAM_VALUES).
CHAIN = dict(m=1.0, l=1.0, d=0.5, Ixx=0.0845, Iyy=0.0855, Izz=0.0125, Ixy=0.001, Iyz=0.002, Izx=0.003)


def chain(n):
    """chain_model.py's N-link chain: joint k about parent x (k odd) / y (k even)."""
    M = Model(f'chain{n}')
    parent, P = M.N, M.O
    inertia = [CHAIN[k] for k in ('Ixx', 'Iyy', 'Izz', 'Ixy', 'Iyz', 'Izx')]
    for k in range(1, n + 1):
        B = M.pin(f'q{k}', parent, P, parent.x if k % 2 else parent.y, f'B{k}')
        M.body(f'B{k}', B, P, CHAIN['m'], (0, 0, -CHAIN['d']), inertia)
        parent, P = B, M.point(f'P{k + 1}', P, -R(CHAIN['l']) * B.z)
    M.params = {'g': float(G_ACC), **CHAIN}
    return M


LINKS = [  # (joint axis in parent coords, m, l, mass centre, (Ixx, Iyy, Izz, Ixy, Iyz, Izx))
    ((1, 0, 0), 1.0, 1.0, (0.05, -0.02, -0.5), (0.09, 0.08, 0.012, 0.001, 0.002, 0.003)),
    ((0, 0.6, 0.8), 0.7, 0.8, (-0.03, 0.04, -0.35), (0.05, 0.045, 0.008, -0.002, 0.001, 0.0015)),
    ((1, 0, 0), 0.4, 0.6, (0.0, 0.01, -0.3), (0.02, 0.018, 0.004, 0.0005, -0.0007, 0.0002)),
]


def pendulum_3d(n, name):
    M = Model(name)
    parent, P = M.N, M.O
    for k, (axis, m, l, com, I) in enumerate(LINKS[:n], start=1):
        B = M.pin(f'q{k}', parent, P, M.vec(parent, axis), f'B{k}')
        M.body(f'B{k}', B, P, m, com, I)
        M.params.update({f'B{k}.axis': list(axis), f'B{k}.l': l})
        parent, P = B, M.point(f'P{k + 1}', P, -R(l) * B.z)
    return M


def cart_pendulum():
    M = Model('cart_pendulum')
    C, Co = M.slider('x', M.N, M.O, me.Vector(0), M.N.x, 'C')
    M.body('C', C, Co, 2.0, (0, 0, 0), (0.1, 0.1, 0.1, 0, 0, 0))
    P = M.pin('theta', C, Co, C.y, 'P')
    M.body('P', P, Co, 0.5, (0, 0, -0.4), (0.02, 0.025, 0.004, 0, 0, 0))
    M.spring('x', 5.0, 0.1)
    M.damper('x', 0.3)
    M.damper('theta', 0.05)
    M.external('force_on_C_origin_N', Co, R(0.7) * M.N.x, [0.7, 0, 0])
    return M


def mixed_chain():
    M = Model('mixed_chain')
    A, Ao = M.slider('s1', M.N, M.O, me.Vector(0), M.N.y, 'A')
    M.body('A', A, Ao, 1.5, (0, 0, 0), (0.05, 0.06, 0.07, 0, 0, 0))
    Bo = M.point('Bo', Ao, M.vec(A, (0.1, 0, 0)))
    B = M.pin('q2', A, Bo, A.z, 'B')
    M.body('B', B, Bo, 0.8, (0.3, 0, 0.02), (0.01, 0.03, 0.035, 0.001, 0.0, 0.002))
    C, Co = M.slider('s3', B, Bo, M.vec(B, (0.2, 0, 0)), B.x, 'C')
    M.body('C', C, Co, 0.3, (0.05, 0.01, 0), (0.002, 0.004, 0.004, 0, 0, 0.0005))
    Do = M.point('Do', Co, M.vec(C, (0.1, 0, 0)))
    D = M.pin('q4', C, Do, C.x, 'D')
    M.body('D', D, Do, 0.2, (0, 0.05, -0.05), (0.001, 0.0012, 0.0009, 0.0001, 0.0002, 0.0003))
    M.spring('s3', 20.0, 0.05)
    M.spring('q4', 0.4, 0.2)
    M.damper('q2', 0.02)
    M.external('force_on_D_N', M.point('Dp', Do, M.vec(D, (0, 0.1, -0.1))),
               M.vec(M.N, (0.3, -0.2, 0.1)), {'vector_N': [0.3, -0.2, 0.1], 'point_D': [0, 0.1, -0.1]})
    M.external('torque_on_B_B', B, M.vec(B, (0.05, 0, 0.02)), [0.05, 0, 0.02])
    return M


# Loop models: transcriptions of models/four_bar.mech and models/slider_crank.mech (default
# parameter values, SI).  The tree is derived open (all coordinates independent); the loop
# closure only enters through phi(q), J and J'u.
FOUR_BAR = dict(ground=3.0, crank_length=1.0, coupler_length=2.5, rocker_length=2.0, m=1.0)


def double_pendulum_speeds():
    """models/double_pendulum_speeds.mech: a planar double pendulum in speeds chosen by
    `speed`, written here from SymPy's own vector kinematics as KanesMethod's kd_eqs
    (u_r - Y_r(q) q' = 0, not q' = u): the upper link's angular velocity in N along z and
    the tip's velocity in N along the lower link's x."""
    M = Model('double_pendulum_speeds')
    M.up = M.N.y
    A = M.pin('shoulder', M.N, M.O, M.N.z, 'A')
    M.body('upper', A, M.O, 1.3, (0.1, -0.4, 0), (0.05, 0.07, 0.11, 0, 0, 0))
    E = M.point('E', M.O, -R(0.9) * A.y)
    B = M.pin('elbow', A, E, A.z, 'B')
    M.body('lower', B, E, 0.7, (0.05, -0.3, 0), (0.02, 0.03, 0.04, 0, 0, 0))
    tip = M.point('T', E, -R(0.6) * B.y)
    M.chosen_speeds = [('w_upper', A.ang_vel_in(M.N).dot(M.N.z)),
                       ('tip_speed', tip.vel(M.N).dot(B.x))]
    return M


def rod_inertia(m, l, axes):
    """Uniform slender rod along x about its centre: m l^2 / 12 on `axes` (exact)."""
    i = R(m) * R(l) ** 2 / 12
    return [i if k in axes else 0 for k in 'xyz'] + [0, 0, 0]


def rod(M, name, frame, origin, m, l, axes):
    """Body `name` of `M`: a uniform slender rod of mass m and length l along `frame`'s x from
    `origin` (com at l/2, inertia `rod_inertia` on `axes`)."""
    return M.body(name, frame, origin, m, (l / 2, 0, 0), rod_inertia(m, l, axes))


def four_bar_tree(M, p, m_crank, m_coupler, m_rocker):
    """The open tree of a planar four-bar in `M` (the lengths `crank_length`, `coupler_length`,
    `rocker_length` and `ground` of `p`): the crank pinned at O about N.z, the coupler pinned
    at the crank's tip, the rocker pinned at `ground` along N.x, each a slender rod of its mass
    about z. Returns the coupler's and rocker's frames and their tips (the closure's points)."""
    A = M.pin('crank_angle', M.N, M.O, M.N.z, 'A')
    rod(M, 'crank', A, M.O, m_crank, p['crank_length'], 'z')
    Bo = M.point('Bo', M.O, R(p['crank_length']) * A.x)
    B = M.pin('coupler_angle', A, Bo, A.z, 'B')
    rod(M, 'coupler', B, Bo, m_coupler, p['coupler_length'], 'z')
    Co = M.point('Co', M.O, R(p['ground']) * M.N.x)
    C = M.pin('rocker_angle', M.N, Co, M.N.z, 'C')
    rod(M, 'rocker', C, Co, m_rocker, p['rocker_length'], 'z')
    Bt = M.point('Bt', Bo, R(p['coupler_length']) * B.x)
    Ct = M.point('Ct', Co, R(p['rocker_length']) * C.x)
    return B, C, Bt, Ct


def four_bar():
    p = FOUR_BAR
    M = Model('four_bar')
    M.up = M.N.y
    _, _, Bt, Ct = four_bar_tree(M, p, p['m'], p['m'], p['m'])
    M.coincident('tip', Bt, Ct, 'xy')
    M.params = {'g': float(G_ACC), 'gravity': [0, -float(G_ACC), 0], **p,
                'inertia': 'slender rods: m l^2/12 about com z', 'loop tip': 'coincident x, y in N'}
    return M


SLIDER_CRANK = dict(r=0.005, rod=0.015, m_crank=0.002, m_rod=0.001, m_slider=0.003, c_slider=0.0)


def slider_crank():
    p = SLIDER_CRANK
    M = Model('slider_crank')
    M.up = M.N.y
    A = M.pin('crank_angle', M.N, M.O, M.N.z, 'A')
    rod(M, 'crank', A, M.O, p['m_crank'], p['r'], 'yz')
    Bo = M.point('Bo', M.O, R(p['r']) * A.x)
    B = M.pin('rod_angle', A, Bo, A.z, 'B')
    rod(M, 'connecting_rod', B, Bo, p['m_rod'], p['rod'], 'yz')
    S, So = M.slider('slide', M.N, M.O, me.Vector(0), M.N.x, 'S')
    M.body('slider', S, So, p['m_slider'], (0, 0, 0), (0, 0, 0, 0, 0, 0))
    M.damper('slide', p['c_slider'])
    M.coincident('wrist', M.point('Bt', Bo, R(p['rod']) * B.x), So, 'xy')
    M.params = {'g': float(G_ACC), 'gravity': [0, -float(G_ACC), 0], **p,
                'inertia': 'crank, rod: m l^2/12 about com y and z; slider: 0',
                'loop wrist': 'coincident x, y in N'}
    return M


# A compliant four-bar at microrobot scale (models/compliant_four_bar.mech): a flexure at each of
# its four pins, the fourth on the revolute closure coupler tip -> rocker tip.
COMPLIANT = dict(ground=0.03, crank_length=0.01, coupler_length=0.025, rocker_length=0.02,
                 m_crank=1e-6, m_coupler=2e-6, m_rocker=1.5e-6)
KAPTON = dict(E=2.56e9, loss_factor=0.05)   # Doshi et al. Sec. IV.B (measured E; eta)


def compliant_four_bar():
    p = COMPLIANT
    M = Model('compliant_four_bar')
    M.up = M.N.y
    B, C, Bt, Ct = four_bar_tree(M, p, p['m_crank'], p['m_coupler'], p['m_rocker'])
    # mech's perpendiculars for axis z are e1 = z x x = y and e2 = z x e1 = -x (child
    # frame); in this planar model both rows are identically zero for any choice.
    M.revolute('tip', Bt, Ct, B.z, C.y, -C.x)
    M.params = {'g': float(G_ACC), 'gravity': [0, -float(G_ACC), 0], **p,
                'inertia': 'slender rods: m l^2/12 about com z', 'loop tip': 'revolute about z',
                'kapton': KAPTON}
    M.flexure('crank_hinge', 'crank_angle', R(5e-8), 0.1, 0.1, 60)
    # Kapton film: k = E w t^3 / (12 l) (Eq. 2), w = 0.5 mm, t = 12.5 um, l = 2 mm
    w, h, l = R(0.5e-3), R(12.5e-6), R(2e-3)
    M.flexure('coupler_hinge', 'coupler_angle', R(KAPTON['E']) * w * h ** 3 / (12 * l),
              KAPTON['loss_factor'], 0.2, -35)
    M.params['coupler_hinge.geometry'] = {'width': 0.5e-3, 'thickness': 12.5e-6, 'length': 2e-3}
    M.flexure('rocker_hinge', 'rocker_angle', R(8e-8), 0.06, 0.05, 100)
    # The rocker's rotation relative to the coupler (absolute angles: q3 and q1 + q2). mech
    # measures it with atan2, in (-pi, pi]: the states keep |q3 - q1 - q2| <= 3 < pi.
    q1, q2, q3 = M.q
    assert all(abs(q[2] - q[0] - q[1]) < math.pi for q, _ in states(M.name, 3))
    M.loop_flexure('tip_hinge', B, C, M.N.z, q3 - q1 - q2, R(3e-8), 0.12, 0.15, 20)
    for name, k in (('crank_hinge', 5e-8), ('rocker_hinge', 8e-8), ('tip_hinge', 3e-8)):
        M.params[f'{name}.stiffness'] = k
    return M


def ball_double_pendulum():
    """models/ball_double_pendulum.mech: two links on ball joints under gravity."""
    M = Model('ball_double_pendulum')
    A = M.ball('shoulder', M.N, 'A')
    M.body('upper', A, M.O, 1.0, (0, 0, -0.15), (0.02, 0.015, 0.01, 0, 0, 0))
    E = M.point('E', M.O, -R(0.3) * A.z)
    B = M.ball('elbow', A, 'B')
    M.body('lower', B, E, 0.5, (0.02, 0, -0.1), (0.004, 0.003, 0.002, 0, 0, 0))
    M.params['upper.tip'] = [0, 0, -0.3]
    return M


def floating_chain():
    """models/floating_chain.mech: a free joint (a ball, and the origin's position in N with
    its velocity in the base's frame as speeds), an arm on a sprung pin about the base's z, a
    hand on a ball joint."""
    M = Model('floating_chain')
    A, P = M.free('float', 'A')
    M.body('base', A, P, 2.0, (0.01, 0, 0), (0.05, 0.04, 0.03, 0, 0, 0))
    S = M.point('S', P, M.vec(A, (0.1, 0, 0)))
    B = M.pin('shoulder', A, S, A.z, 'B')
    M.body('arm', B, S, 0.5, (0.1, 0, 0), (0.001, 0.004, 0.0045, 0, 0, 0))
    W = M.point('W', S, M.vec(B, (0.2, 0, 0)))
    C = M.ball('wrist', B, 'C')
    M.body('hand', C, W, 0.2, (0.03, 0.01, 0), (0.0002, 0.0003, 0.00025, 0, 0, 0))
    M.spring('shoulder', 2.0, 0.1)
    M.params.update({'base.shoulder': [0.1, 0, 0], 'arm.wrist': [0.2, 0, 0]})
    return M


def state_forces():
    """models/state_forces.mech: forces of the motion (the coordinates, speeds, a distance and
    its rate) and a spring-damper between two moving bodies. The loads other than the
    spring's are all counted as non-conservative in the energy balance."""
    M = Model('state_forces')
    C, Co = M.slider('s', M.N, M.O, me.Vector(0), M.N.x, 'C')
    M.body('cart', C, Co, 1.2, (0, 0, 0), (0.02, 0.03, 0.04, 0, 0, 0))
    So = M.point('So', Co, M.vec(C, (0.1, 0, 0)))
    A = M.pin('swing', C, So, C.y, 'A')
    M.body('arm', A, So, 0.6, (0, 0, -0.25), (0.01, 0.012, 0.003, 0.001, 0, 0.0005))
    tip = M.point('tip', So, M.vec(A, (0.02, 0.01, -0.5)))
    anchor = M.point('anchor', M.O, M.vec(M.N, (0.4, 0.3, 0.2)))
    Rk = M.pin('rock', M.N, anchor, M.N.z, 'Rk')
    M.body('rocker', Rk, anchor, 0.4, (0.15, 0.02, 0), (0.002, 0.006, 0.007, 0, 0, 0))
    end = M.point('end', anchor, M.vec(Rk, (0.3, 0, 0.05)))
    M.point_spring(tip, end, 30, 0.2, 0.4)
    (s, swing, rock), (us, _, urock) = M.q, M.u
    cubic = (-8 * s ** 3 - R(0.5) * us * sm.cos(swing)) * M.N.x
    wind = (R(0.3) * sm.sin(swing) - R(0.05) * urock) * A.y
    post = M.point('post', M.O, M.vec(M.N, (-0.2, 0.1, 0.6)))
    d = end.pos_from(post)
    length = d.magnitude()
    rate = (d / length).dot(end.vel(M.N))
    tether = (-3 * (length - R(0.1)) - R(0.2) * rate) * Rk.y
    for load in ((Co, cubic), (A, wind), (end, tether)):
        M.loads.append(load), M.nc_loads.append(load)
    M.params.update({'spring link': {'tip': [0.02, 0.01, -0.5], 'end': [0.3, 0, 0.05], 'k': 30,
                                     'rest_length': 0.2, 'damping': 0.4},
                     'force cubic at cart (N)': '-8 s^3 - 0.5 u_s cos(swing)',
                     'torque wind on arm (arm y)': '0.3 sin(swing) - 0.05 u_rock',
                     'force tether at rocker.end (rocker y)': '-3 (L - 0.1) - 0.2 L\', L = |end - post|',
                     'post': [-0.2, 0.1, 0.6], 'anchor': [0.4, 0.3, 0.2], 'swing.joint': [0.1, 0, 0]})
    return M


def contact_plate():
    """models/contact_plate.mech: a ball (x, y sliders and a spin) whose sphere, off its
    origin, touches a plate turning about a Newtonian anchor: Hunt-Crossley contact with
    regularized friction, the reaction on the plate."""
    M = Model('contact_plate')
    C, Co = M.slider('x', M.N, M.O, me.Vector(0), M.N.x, 'C')
    L, Lo = M.slider('y', C, Co, me.Vector(0), C.y, 'L')
    B = M.pin('spin', L, Lo, L.z, 'B')
    M.body('ball', B, Lo, 0.2, (0, 0, 0), (0.001, 0.002, 0.003, 0, 0, 0))
    anchor = M.point('anchor', M.O, M.vec(M.N, (0.1, -0.2, 0)))
    P = M.pin('tilt', M.N, anchor, M.N.z, 'P')
    M.body('plate', P, anchor, 0.5, (0.2, 0, 0), (0.001, 0.004, 0.005, 0, 0, 0))
    centre = M.point('centre', Lo, M.vec(B, (0.05, 0.02, 0)))
    surface = M.point('surface', anchor, M.vec(P, (0.3, 0.1, 0)))
    M.contact(centre, B, surface, P, P.y, 0.04, 50, 1.5, 0.1, 0.2, 0.3, 0.1)
    M.params.update({'contact touch': {'centre': [0.05, 0.02, 0], 'surface': [0.3, 0.1, 0],
                                       'normal': 'plate y', 'radius': 0.04, 'stiffness': 50,
                                       'exponent': 1.5, 'reference_depth': 0.1, 'damping': 0.2,
                                       'friction': 0.3, 'transition_speed': 0.1},
                     'anchor': [0.1, -0.2, 0]})
    return M


MODELS = [lambda: chain(1), lambda: chain(2), lambda: chain(4),
          lambda: pendulum_3d(2, 'double_pendulum_3d'), lambda: pendulum_3d(3, 'triple_pendulum_3d'),
          cart_pendulum, mixed_chain, four_bar, slider_crank, compliant_four_bar, ball_double_pendulum,
          floating_chain, state_forces, contact_plate, double_pendulum_speeds]


# ---------------------------------------------------------------- nonholonomic
DISC = {'r': 0.5, 'm': 1.5, 'g': float(G_ACC)}


def rolling_disc_kane():
    """SymPy's test_rolling_disc up to kanes_equations, as written there (also used by
    bench/sympy_rolling_disc.py): KanesMethod, (q1, q2, q3, u1, u2, u3), (r, m, g), and the
    frames, points and body that rolling_disc() reads."""
    q1, q2, q3, u1, u2, u3 = me.dynamicsymbols('q1 q2 q3 u1 u2 u3')
    r, m, g = sm.symbols('r m g')
    N = me.ReferenceFrame('N')
    Y = N.orientnew('Y', 'Axis', [q1, N.z])
    L = Y.orientnew('L', 'Axis', [q2, Y.x])
    R = L.orientnew('R', 'Axis', [q3, L.y])
    w_R_N_qd = R.ang_vel_in(N)
    R.set_ang_vel(N, u1 * L.x + u2 * L.y + u3 * L.z)
    C = me.Point('C')
    C.set_vel(N, 0)
    Dmc = C.locatenew('Dmc', r * L.z)
    Dmc.v2pt_theory(C, N, R)
    I = me.inertia(L, m / 4 * r**2, m / 2 * r**2, m / 4 * r**2)
    kd = [me.dot(R.ang_vel_in(N) - w_R_N_qd, uv) for uv in L]
    ForceList = [(Dmc, - m * g * Y.z)]
    BodyD = me.RigidBody('BodyD', Dmc, R, m, (I, Dmc))
    KM = me.KanesMethod(N, q_ind=[q1, q2, q3], u_ind=[u1, u2, u3], kd_eqs=kd)
    KM.kanes_equations([BodyD], ForceList)
    return KM, (q1, q2, q3, u1, u2, u3), (r, m, g), N, L, w_R_N_qd, C, Dmc, BodyD


def rolling_disc():
    """SymPy's rolling disc, verbatim from sympy/physics/mechanics/tests/test_kane.py
    (test_rolling_disc): yaw q1 about N.z, lean q2 about Y.x, spin q3 about L.y, speeds the
    disc's angular velocity in the lean frame, u1 L.x + u2 L.y + u3 L.z, and the contact
    point C at rest (Dmc.v2pt_theory(C, N, R)): no slip is built in, no constraint is
    written. mech's models/rolling_disc.mech has the contact point's position x, y as two
    more coordinates, u = q' for all five, and the no-slip rows as a velocity constraint.
    Returns u' in mech's layout as a function of mech's (q, u), and the energies."""
    (KM, (q1, q2, q3, u1, u2, u3), (r, m, g), N, L, w_R_N_qd, C, Dmc,
     BodyD) = rolling_disc_kane()
    values = {s: sm.Rational(str(DISC[s.name])) for s in (r, m, g)}   # exact, as R() gives
    upright = rolling_disc_upright(KM, (q1, q2, q3, u1, u2, u3), (r, m, g))
    # mech's coordinates and speeds (u = q'): x, y, yaw, lean, spin.
    x, y, yaw, lean, spin = sm.symbols('x y yaw lean spin')
    vx, vy, vyaw, vlean, vspin = sm.symbols('u_x u_y u_yaw u_lean u_spin')
    angles = {q1: yaw, q2: lean, q3: spin}
    rates = [vyaw, vlean, vspin]
    # SymPy's speeds from q': u_k = (R's angular velocity in N) . L_k, with q' = mech's u.
    qd = dict(zip([q1.diff(t), q2.diff(t), q3.diff(t)], rates))
    speeds = [me.dot(w_R_N_qd, uv).xreplace(qd).xreplace(angles) for uv in L]
    T = sm.Matrix(speeds).jacobian(rates)       # u_sympy = T(lean) q'_angles
    Td_qd = sm.Matrix([sum(sm.diff(e, a) * w for a, w in zip([yaw, lean, spin], rates))
                       for e in T * sm.Matrix(rates)])
    sub = dict(zip([u1, u2, u3], speeds))
    Mm = KM.mass_matrix.xreplace(angles).xreplace(sub).xreplace(values)
    F = KM.forcing.xreplace(qd).xreplace(angles).xreplace(sub).xreplace(values)
    ke = BodyD.kinetic_energy(N).xreplace(angles).xreplace(sub).xreplace(values)
    pe = (m * g * Dmc.pos_from(C).dot(N.z)).xreplace(angles).xreplace(values)
    args = [x, y, yaw, lean, spin, vx, vy, vyaw, vlean, vspin]
    for e in (Mm, F, ke, pe, T, Td_qd):
        assert sm.sympify(e).free_symbols <= set(args), e
    f = sm.lambdify(args, [Mm, F, T.xreplace(values), Td_qd.xreplace(values), ke, pe],
                    modules='mpmath')
    return f, upright


def rolling_disc_upright(KM, symbols, constants):
    """The eigenvalues of SymPy's linearization (KM.linearize, as its test does) about
    upright rolling (q = 0, u1 = u3 = 0) at 1.1 and 0.9 times the critical spin
    u2 = sqrt(g / (3 r)), where they are all zero (SymPy's test asserts this at r = g = 1):
    a pair on the imaginary axis above it (stable), a real pair below (the disc falls).
    Only the nonzero eigenvalues, as [re, im], sorted."""
    q1, q2, q3, u1, u2, u3 = symbols
    r, m, g = constants
    values = {s: sm.Rational(str(DISC[s.name])) for s in constants}
    A, _, _ = KM.linearize(A_and_B=True)
    critical = sm.sqrt(values[g] / (3 * values[r]))
    out = []
    for factor in ('1.1', '0.9'):
        spin = sm.Rational(factor) * critical
        Au = A.xreplace(values).subs({q1: 0, q2: 0, q3: 0, u1: 0, u3: 0, u2: spin})
        eigenvalues = [complex(sm.N(e, 30)) for e in Au.eigenvals(multiple=True)]
        nonzero = sorted([[z.real, z.imag] for z in eigenvalues if abs(z) > 1e-12],
                         key=lambda z: (z[1], z[0]))
        out.append({'speed_factor': float(factor), 'spin': f64(sm.N(spin, 30)),
                    'eigenvalues': nonzero})
    return out


def rolling_disc_states():
    """Random (q, u) of mech's rolling disc that satisfy its no-slip rows: yaw, lean, spin
    and their rates uniform in [-1, 1], x and y too, and u_x, u_y = r u_spin (cos yaw,
    sin yaw) (the contact point moves along the heading at r times the spin rate)."""
    rng = random.Random('mech-peer:rolling_disc')
    out = []
    for _ in range(N_STATES):
        q = [rng.uniform(-1, 1) for _ in range(5)]
        rates = [rng.uniform(-1, 1) for _ in range(3)]
        u = [DISC['r'] * rates[2] * math.cos(q[2]), DISC['r'] * rates[2] * math.sin(q[2])] + rates
        out.append((q, u))
    return out


def rolling_disc_fixture():
    """mech's u' at each state from SymPy's equations: the angles' accelerations from
    M u_sympy' = F through u_sympy = T q' (q'' = T^-1 (u_sympy' - T' q')), and x'', y''
    by differentiating u_x, u_y = r u_spin (cos yaw, sin yaw) along the motion.
    Energy check: dE/dt = 0 (no work by the contact, no damping) at each state. And the
    eigenvalues of the linearization about upright rolling (rolling_disc_upright)."""
    f, upright = rolling_disc()
    r = mpmath.mpf(R(DISC['r']).p) / R(DISC['r']).q
    out = []
    for q, u in rolling_disc_states():
        args = list(map(mpmath.mpf, q + u))
        Ms, Fs, T, Td_qd, ke, pe = f(*args)
        ud_sympy = mpmath.lu_solve(mat(Ms), mat(Fs))
        qdd = mpmath.lu_solve(mat(T), ud_sympy - mat(Td_qd))
        yaw, wyaw, wspin = args[2], args[7], args[9]
        xdd = r * (qdd[2] * mpmath.cos(yaw) - wspin * wyaw * mpmath.sin(yaw))
        ydd = r * (qdd[2] * mpmath.sin(yaw) + wspin * wyaw * mpmath.cos(yaw))
        udot = [xdd, ydd, qdd[0], qdd[1], qdd[2]]
        # dE/dt along the motion, by a central difference at 50 digits (h = 1e-15) of E(q + h q', u + h u').
        h = mpmath.mpf(10) ** -15

        def energy(s):
            shifted = [a + s * h * d for a, d in zip(args, u + udot)]
            _, _, _, _, k, p = f(*shifted)
            return k + p
        rate = (energy(1) - energy(-1)) / (2 * h)
        assert abs(rate) < mpmath.mpf(10) ** -25, f'rolling_disc: dE/dt = {rate}'
        out.append({'q': q, 'u': u, 'udot': [f64(a) for a in udot],
                    'kinetic_energy': f64(ke), 'potential_energy': f64(pe)})
    return {'coordinates': ['x', 'y', 'yaw', 'lean', 'spin'], 'params': DISC, 'states': out,
            'upright': upright}


# ---------------------------------------------------------------- spring pendulum
# models/spring_pendulum.mech, written here independently of it: a bob on a spring-damper
# hung from an anchor, in polar coordinates about the anchor (r the spring's length, theta
# from straight down), Lagrange's equations d/dt dL/dq' - dL/dq = -dD/dq' with the Rayleigh
# function D = c r'^2 / 2 (the damper acts along the spring, at the stretch rate r').
SPRING_PENDULUM = {'m': '0.02', 'k': '40', 'L0': '0.05', 'c': '0.02', 'g': G_ACC,
                   'anchor': ['0.005', '0.01']}
SPRING_PENDULUM_START = {'q': [0.04, -0.06], 'u': [0.3, 0.2]}   # x, y of the bob; m, m/s
SPRING_PENDULUM_TIMES = ['0.25', '0.5', '1', '1.5', '2']


def spring_pendulum_lagrange():
    """The bob's x, y and their rates at SPRING_PENDULUM_TIMES from the start state, by
    mpmath's Taylor-series integrator (odefun) at 30 digits: an integration of the
    Lagrangian independent of mech's Kane equations, its frame tree and its integrators."""
    p = {k: R(v) for k, v in SPRING_PENDULUM.items() if k != 'anchor'}
    r, th = me.dynamicsymbols('r theta')
    rd, thd = r.diff(t), th.diff(t)
    T = p['m'] * (rd ** 2 + r ** 2 * thd ** 2) / 2
    V = p['k'] * (r - p['L0']) ** 2 / 2 - p['m'] * p['g'] * r * sm.cos(th)
    D = p['c'] * rd ** 2 / 2
    L = T - V
    eqs = [L.diff(v).diff(t) - L.diff(q) + D.diff(v) for q, v in ((r, rd), (th, thd))]
    acc = sm.solve(eqs, [r.diff(t, 2), th.diff(t, 2)], dict=True)[0]
    R_, TH, RD, THD = sm.symbols('R TH RD THD')
    plain = {rd: RD, thd: THD, r: R_, th: TH}
    rdd = sm.lambdify((R_, TH, RD, THD), acc[r.diff(t, 2)].subs(plain), 'mpmath')
    thdd = sm.lambdify((R_, TH, RD, THD), acc[th.diff(t, 2)].subs(plain), 'mpmath')
    mpmath.mp.dps = 30
    ax, ay = (mpmath.mpf(R(a).p) / R(a).q for a in SPRING_PENDULUM['anchor'])
    (x, y), (vx, vy) = (list(map(mpmath.mpf, v)) for v in SPRING_PENDULUM_START.values())
    dx, dy = x - ax, y - ay
    r0 = mpmath.sqrt(dx * dx + dy * dy)
    th0 = mpmath.atan2(dx, -dy)
    start = [r0, th0, (dx * vx + dy * vy) / r0, (dx * vy - dy * vx) / r0 ** 2]
    motion = mpmath.odefun(lambda _, s: [s[2], s[3], rdd(*s), thdd(*s)], 0, start)
    samples = []
    for text in SPRING_PENDULUM_TIMES:
        rr, tt, rv, tv = motion(mpmath.mpf(text))
        position = [ax + rr * mpmath.sin(tt), ay - rr * mpmath.cos(tt)]
        velocity = [rv * mpmath.sin(tt) + rr * tv * mpmath.cos(tt),
                    -rv * mpmath.cos(tt) + rr * tv * mpmath.sin(tt)]
        samples.append({'t': float(text), 'q': [f64(v) for v in position],
                        'u': [f64(v) for v in velocity]})
    mpmath.mp.dps = DPS
    return {'params': SPRING_PENDULUM, 'start': SPRING_PENDULUM_START, 'samples': samples}


# ---------------------------------------------------------------- evaluation
def derive(M):
    qd = {qi.diff(t): ui for qi, ui in zip(M.q, M.u)}
    qd.update({e.diff(t): rate for e, rate in zip(M.quaternions, M.quaternion_rates)})
    qd.update({x.diff(t): rate for x, rate in zip(M.translations, M.translation_rates)})
    kd_eqs = [a - b for a, b in qd.items()]
    if M.chosen_speeds:   # u = Y(q) q': KanesMethod solves kd_eqs for q' itself
        M.u = list(me.dynamicsymbols(' '.join(f'u_{name}' for name, _ in M.chosen_speeds)))
        kd_eqs = [u - y for u, (_, y) in zip(M.u, M.chosen_speeds)]
        qd = sm.solve(kd_eqs, [qi.diff(t) for qi in M.q], dict=True)[0]
    q_all = M.q + M.quaternions + M.translations
    u_all = M.u + M.angular_speeds + M.velocity_speeds
    kane = me.KanesMethod(M.N, q_ind=q_all, u_ind=u_all, kd_eqs=kd_eqs)
    kane.kanes_equations(M.bodies, M.loads)
    ke = sum(b.kinetic_energy(M.N) for b in M.bodies).xreplace(qd)
    power = sum(v.dot(x.vel(M.N) if isinstance(x, me.Point) else x.ang_vel_in(M.N))
                for x, v in M.nc_loads).xreplace(qd) if M.nc_loads else sm.S(0)
    E = ke + M.pe
    dE = [E.diff(s) for s in q_all + u_all]
    qdot = [d.xreplace(qd) for d in (s.diff(t) for s in q_all)]
    exprs = [kane.mass_matrix.xreplace(qd), kane.forcing.xreplace(qd), ke, M.pe, power, dE, qdot]
    args = q_all + u_all
    if M.loops:
        q, u = sm.Matrix(M.q), sm.Matrix(M.u)
        phi = sm.Matrix([r.dot(e) for r, e in M.loops])
        J = phi.jacobian(q)
        Jdu = (J * u).jacobian(q) * u                      # J'u = sum_i d(J u)/dq_i u_i
        # independent route for J'u: the second time derivative of the closure vector in N
        # (SymPy vector kinematics), with q'' = 0 and q' = u
        # (product rule: the direction e moves for alignment rows, is fixed in N otherwise)
        qdd = {qi.diff(t, 2): 0 for qi in M.q}
        acc = sm.Matrix([r.dt(M.N).dt(M.N).dot(e) + 2 * r.dt(M.N).dot(e.dt(M.N))
                         + r.dot(e.dt(M.N).dt(M.N)) for r, e in M.loops]).xreplace(qdd).xreplace(qd)
        vel = sm.Matrix([r.dt(M.N).dot(e) + r.dot(e.dt(M.N))
                         for r, e in M.loops]).xreplace(qd)   # = J u
        exprs += [phi, J, Jdu, acc - Jdu, vel - J * u]
    for e in exprs[:5] + exprs[7:10]:   # only q, u may remain (no q', no unsubstituted symbols)
        e = sm.sympify(e)
        assert e.free_symbols <= {t} and me.find_dynamicsymbols(e) <= set(args), e
    return sm.lambdify(args, exprs, modules='mpmath')


def mat(x):
    return mpmath.matrix(x.tolist() if hasattr(x, 'tolist') else x)


def check(name, Mm, F, ke, pe, power, dE, qdot, u):
    n = len(u)
    scale = max(abs(x) for x in Mm)
    asym = max(abs(Mm[i, j] - Mm[j, i]) for i in range(n) for j in range(n))
    assert asym <= mpmath.mpf(10) ** (-DPS + 10) * scale, f'{name}: M not symmetric ({asym})'
    mpmath.cholesky(Mm)  # raises ValueError unless positive definite
    assert ke > 0 or all(x == 0 for x in u)
    # energy balance: dE/dt = sum dE/dq q' + dE/du u' = power of non-conservative loads
    ud = mpmath.lu_solve(Mm, F)
    nq = len(qdot)
    rate = sum(dE[i] * qdot[i] for i in range(nq)) + sum(dE[nq + i] * ud[i] for i in range(n))
    err = abs(rate - power)
    assert err <= mpmath.mpf(10) ** (-DPS + 15) * (1 + abs(rate) + abs(power)), f'{name}: dE/dt {rate} != {power}'
    return err


def states(name, n, quaternions=0, translations=0):
    """Coordinates and speeds uniform in [-1, 1], then per quaternion a unit quaternion
    (four normal deviates, normalized) and three angular speeds in [-1, 1], then per free
    joint's translation three coordinates and three speeds in [-1, 1]."""
    rng = random.Random(f'mech-peer:{name}')

    def unit():
        e = [rng.gauss(0, 1) for _ in range(4)]
        norm = math.sqrt(sum(x * x for x in e))
        return [x / norm for x in e]
    out = []
    for _ in range(N_STATES):
        q, u = [rng.uniform(-1, 1) for _ in range(n)], [rng.uniform(-1, 1) for _ in range(n)]
        for _ in range(quaternions):
            q += unit()
            u += [rng.uniform(-1, 1) for _ in range(3)]
        for _ in range(translations):
            q += [rng.uniform(-1, 1) for _ in range(3)]
            u += [rng.uniform(-1, 1) for _ in range(3)]
        out.append((q, u))
    return out


def f64(x):
    v = float(x)
    assert math.isfinite(v)
    return v


def cross_check_shared(fixture):
    """If ../shared/peers/chain_model.py exists beside the repo, compare chain1/chain2 against it."""
    shared = os.path.join(HERE, '..', '..', '..', 'shared', 'peers')
    if not os.path.exists(os.path.join(shared, 'chain_model.py')):
        print('  (../shared/peers/chain_model.py not found; skipping cross-check)')
        return
    sys.path.insert(0, shared)
    import chain_model
    for n in (1, 2, 4):
        cm = chain_model.build_chain(n)
        Mm, F = chain_model.derive(cm)
        sub = dict(zip(cm['constants'], map(R, cm['const_values'])))
        f = sm.lambdify(cm['q'] + cm['u'], [Mm.xreplace(sub), F.xreplace(sub)], modules='mpmath')
        worst = 0.0
        for s in fixture[f'chain{n}']['states']:
            Ms, Fs = f(*s['q'], *s['u'])
            ref = [x for row in s['mass_matrix'] for x in row] + s['forcing']
            got = list(mat(Ms)) + list(mat(Fs))
            worst = max(worst, max(abs(float(a) - b) / (1 + abs(b)) for a, b in zip(got, ref)))
        assert worst < 1e-14, worst
        print(f'  chain{n} vs shared chain_model.py: max rel diff {worst:.1e}')


def encode(o, ind=0, short=False):
    """Deterministic JSON: sorted keys; floats with 17 significant digits
    (shortest round-trip repr inside "params", which are decimal literals)."""
    if isinstance(o, float):
        return repr(o) if short else format(o, '.17g')
    if isinstance(o, (str, int)):
        return json.dumps(o)
    pad, pad2 = ' ' * ind, ' ' * (ind + 2)
    if isinstance(o, list):
        if all(isinstance(x, (int, float, str)) for x in o):
            return '[' + ', '.join(encode(x, 0, short) for x in o) + ']'
        return '[\n' + ',\n'.join(pad2 + encode(x, ind + 2, short) for x in o) + '\n' + pad + ']'
    items = [f'{pad2}{json.dumps(k)}: {encode(o[k], ind + 2, short or k == "params")}' for k in sorted(o)]
    return '{\n' + ',\n'.join(items) + '\n' + pad + '}'


def main():
    mpmath.mp.dps = DPS
    models = {}
    for make in MODELS:
        M = make()
        t0 = time.perf_counter()
        f = derive(M)
        t_derive = time.perf_counter() - t0
        out, worst = [], 0
        for q, u in states(M.name, len(M.q), len(M.quaternions) // 4, len(M.translations) // 3):
            args = list(map(mpmath.mpf, q + u))
            # Each quaternion at unit norm to working precision (the equations hold on
            # |e| = 1; the doubles written to the fixture are within 1e-16 of it).
            for k in range(len(M.q), len(M.q) + len(M.quaternions), 4):
                norm = mpmath.sqrt(sum(x * x for x in args[k:k + 4]))
                args[k:k + 4] = [x / norm for x in args[k:k + 4]]
            Ms, Fs, ke, pe, power, dE, qdot, *loop = f(*args)
            Mm, F = mat(Ms), mat(Fs)
            worst = max(worst, check(M.name, Mm, F, ke, pe, power, dE, qdot, list(map(mpmath.mpf, u))))
            n = len(u)
            out.append({'q': q, 'u': u, 'mass_matrix': [[f64(Mm[i, j]) for j in range(n)] for i in range(n)],
                        'forcing': [f64(F[i]) for i in range(n)],
                        'kinetic_energy': f64(ke), 'potential_energy': f64(pe)})
            if M.quaternions or M.chosen_speeds:
                out[-1]['kinematic_rates'] = [f64(x) for x in qdot]
            if loop:
                phi, J, Jdu, acc_err, vel_err = map(mat, loop)
                nc = len(M.loops)
                for e in (acc_err, vel_err):   # vector kinematics agree with d/dt of phi
                    assert max(abs(x) for x in e) <= mpmath.mpf(10) ** (-DPS + 10), f'{M.name}: {e}'
                out[-1].update({'constraints': [f64(phi[i]) for i in range(nc)],
                                'constraint_jacobian': [[f64(J[i, j]) for j in range(len(q))] for i in range(nc)],
                                'constraint_bias': [f64(Jdu[i]) for i in range(nc)]})
        coordinates = M.coords + M.quaternion_names + M.translation_names
        models[M.name] = {'coordinates': coordinates, 'params': M.params, 'states': out}
        if M.quaternions:
            models[M.name]['speeds'] = M.coords + M.speed_names + M.velocity_names
        if M.chosen_speeds:
            models[M.name]['speeds'] = [name for name, _ in M.chosen_speeds]
        if M.loops:
            models[M.name]['constraint_names'] = M.loop_names
        print(f'{M.name:20s} n={len(u)}  derivation {t_derive:6.2f} s  '
              f'(M symmetric+PD, |dE/dt - P_nc| <= {mpmath.nstr(worst, 2)})')
    t0 = time.perf_counter()
    models['rolling_disc'] = rolling_disc_fixture()
    print(f'{"rolling_disc":20s} n=3 (+2 dependent)  derivation {time.perf_counter() - t0:6.2f} s  '
          f'(SymPy test_rolling_disc; dE/dt = 0 along the motion)')
    t0 = time.perf_counter()
    models['spring_pendulum_lagrange'] = spring_pendulum_lagrange()
    print(f'{"spring_pendulum":20s} polar Lagrangian, mpmath Taylor integration to t = 2 s '
          f'{time.perf_counter() - t0:6.2f} s')
    print('cross-check:')
    cross_check_shared(models)
    fixture = {'generated_by': 'tests/peers/sympy_models.py (sympy.physics.mechanics.KanesMethod)',
               'sympy_version': sm.__version__, 'mpmath_version': mpmath.__version__, 'models': models}
    with open(OUT, 'w') as fh:
        fh.write(encode(fixture) + '\n')
    print(f'wrote {os.path.relpath(OUT)}')


if __name__ == '__main__':
    main()
