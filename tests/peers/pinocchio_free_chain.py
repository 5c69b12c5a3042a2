#!/usr/bin/env python
"""Pinocchio (ABA) and MuJoCo (mj_forward) accelerations of the floating chain, for
`tests/equations/pinocchio_free_chain.rs`: writes `tests/peers/free_chain.json`.

The model is mech-bench's `floating_chain_source(n)` (bench/src/source.rs): the peers' chain
(`../shared/peers/chain_model.py`: links of mass 1, mass centre 0.5 below the joint, the
full inertia tensor, joints 1 apart along -z, axes alternating x, y) on a floating base, a
body like the links on a free joint, with link 1 pinned 1 below the base's origin about
the base's x. Gravity 9.81 along -z.

Each state is drawn from `random.Random('mech-peer:free_chain<N>')`, in mech's layout:
  q = (q1 … qN, e0, e1, e2, e3, x, y, z)   joint angles, the base's unit quaternion (scalar
                                           first), base origin in the world
  u = (u1 … uN, wx, wy, wz, vx, vy, vz)    joint rates, the base's angular velocity and its
                                           origin's velocity, both in the base's frame
(position, angles and speeds uniform in [-1, 1], the quaternion four normal deviates
normalized). Conventions converted here:
  * Pinocchio's free flyer: q = (x, y, z, qx, qy, qz, qw, q1 … qN), v = (v_body, ω_body,
    u1 … uN), and its `aba` returns dv/dt, the rates of those measure numbers: mech's
    layout up to the order.
  * MuJoCo's free joint: qpos = (x, y, z, w, x, y, z, q…), qvel = (C v_body, ω_body, u…),
    qacc in the same layout, whose linear part is the world acceleration a: mech's
    u̇_lin = d/dt (Cᵀ v_world) = Cᵀ a − ω × v_body.
The script asserts that the two peers agree to 1e-12 (relative to the largest |u̇|).

From the repository root (tests/peers/README.md, "Pinocchio and MuJoCo"):
    python3 -m venv .venv-peers
    .venv-peers/bin/pip install pin==4.1.0 mujoco==4.0.0 numpy==2.4.6
    .venv-peers/bin/python tests/peers/pinocchio_free_chain.py
`--xml N` prints the MJCF of the chain of N links instead (bench/run.sh times it).
"""
import json
import random
import sys

import mujoco
import numpy as np
import pinocchio as pin

SIZES = (1, 2, 4)
STATES = 3
OUT = 'tests/peers/free_chain.json'
# (Ixx, Iyy, Izz, Ixy, Iyz, Izx) of chain_model.py: the tensor, about the mass centre
I3 = np.array([[0.0845, 0.001, 0.003],
               [0.001, 0.0855, 0.002],
               [0.003, 0.002, 0.0125]])
FULLINERTIA = "0.0845 0.0855 0.0125 0.001 0.003 0.002"  # MuJoCo: Ixx Iyy Izz Ixy Ixz Iyz


def axis_of(k):
    """Axis of pin k (1-based) in its parent: x for odd k, y for even k."""
    return 'x' if k % 2 == 1 else 'y'


def pinocchio_model(n):
    model = pin.Model()
    inertia = pin.Inertia(1.0, np.array([0.0, 0.0, -0.5]), I3)
    parent = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), 'float')
    model.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
    for k in range(1, n + 1):
        joint = pin.JointModelRX() if axis_of(k) == 'x' else pin.JointModelRY()
        placement = pin.SE3(np.eye(3), np.array([0.0, 0.0, -1.0]))
        parent = model.addJoint(parent, joint, placement, f'q{k}')
        model.appendBodyToJoint(parent, inertia, pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([0.0, 0.0, -9.81]), np.zeros(3))
    return model


def mujoco_xml(n):
    inertial = f'<inertial pos="0 0 -0.5" mass="1" fullinertia="{FULLINERTIA}"/>'
    body = ''
    for k in reversed(range(1, n + 1)):
        axis = '1 0 0' if axis_of(k) == 'x' else '0 1 0'
        body = (f'<body name="link{k}" pos="0 0 -1"><joint name="q{k}" type="hinge" '
                f'axis="{axis}"/>{inertial}{body}</body>')
    return (f'<mujoco model="free_chain{n}"><option gravity="0 0 -9.81">'
            '<flag contact="disable"/></option><worldbody>'
            f'<body name="base"><freejoint name="float"/>{inertial}{body}</body>'
            '</worldbody></mujoco>')


def draw_state(n, rng):
    position = [rng.uniform(-1, 1) for _ in range(3)]
    angles = [rng.uniform(-1, 1) for _ in range(n)]
    quaternion = np.array([rng.gauss(0, 1) for _ in range(4)])
    quaternion /= np.linalg.norm(quaternion)
    velocity = [rng.uniform(-1, 1) for _ in range(3)]
    rates = [rng.uniform(-1, 1) for _ in range(n)]
    omega = [rng.uniform(-1, 1) for _ in range(3)]
    return (np.array(position), np.array(angles), quaternion,
            np.array(velocity), np.array(rates), np.array(omega))


def pinocchio_udot(model, data, state):
    position, angles, e, v_body, rates, omega = state
    n = len(angles)
    q = np.concatenate([position, e[1:], e[:1], angles])
    v = np.concatenate([v_body, omega, rates])
    a = pin.aba(model, data, q, v, np.zeros(6 + n))
    return np.concatenate([a[6:], a[3:6], a[:3]])


def mujoco_udot(model, data, state):
    position, angles, e, v_body, rates, omega = state
    c = pin.Quaternion(e[0], e[1], e[2], e[3]).toRotationMatrix()  # (w, x, y, z) here
    data.qpos[:] = np.concatenate([position, e, angles])
    data.qvel[:] = np.concatenate([c @ v_body, omega, rates])
    mujoco.mj_forward(model, data)
    a = data.qacc
    linear = c.T @ a[:3] - np.cross(omega, v_body)
    return np.concatenate([a[6:], a[3:6], linear])


def numbers(values):
    return '[' + ', '.join(format(float(x), '.17g') for x in values) + ']'


def main():
    if len(sys.argv) == 3 and sys.argv[1] == '--xml':  # the MJCF, for bench/native
        print(mujoco_xml(int(sys.argv[2])))
        return
    models = {}
    worst = 0.0
    for n in SIZES:
        pin_model = pinocchio_model(n)
        pin_data = pin_model.createData()
        mj_model = mujoco.MjModel.from_xml_string(mujoco_xml(n))
        mj_data = mujoco.MjData(mj_model)
        rng = random.Random(f'mech-peer:free_chain{n}')
        states = []
        for _ in range(STATES):
            state = draw_state(n, rng)
            udot = pinocchio_udot(pin_model, pin_data, state)
            udot_mujoco = mujoco_udot(mj_model, mj_data, state)
            gap = np.max(np.abs(udot - udot_mujoco)) / np.max(np.abs(udot))
            assert gap < 1e-12, (n, gap, udot, udot_mujoco)
            worst = max(worst, gap)
            position, angles, e, v_body, rates, omega = state
            states.append(dict(q=np.concatenate([angles, e, position]),
                               u=np.concatenate([rates, omega, v_body]),
                               udot_pinocchio=udot, udot_mujoco=udot_mujoco))
        models[f'free_chain{n}'] = states
    lines = ['{',
             '  "generated_by": "tests/peers/pinocchio_free_chain.py (pinocchio.aba, mujoco.mj_forward)",',
             f'  "mujoco_version": "{mujoco.__version__}",',
             f'  "numpy_version": "{np.__version__}",',
             f'  "pinocchio_version": "{pin.__version__}",',
             f'  "pinocchio_vs_mujoco_max_rel": {format(worst, ".3g")},',
             '  "models": {']
    for i, (name, states) in enumerate(models.items()):
        lines.append(f'    "{name}": [')
        for j, s in enumerate(states):
            fields = ', '.join(f'"{k}": {numbers(s[k])}'
                               for k in ('q', 'u', 'udot_pinocchio', 'udot_mujoco'))
            lines.append('      {' + fields + '}' + (',' if j + 1 < len(states) else ''))
        lines.append('    ]' + (',' if i + 1 < len(models) else ''))
    lines += ['  }', '}']
    with open(OUT, 'w') as f:
        f.write('\n'.join(lines) + '\n')
    print(f'pinocchio {pin.__version__}, mujoco {mujoco.__version__}: '
          f'largest |pinocchio - mujoco| / max|u̇| = {worst:.3g}; wrote {OUT}', file=sys.stderr)


if __name__ == '__main__':
    main()
