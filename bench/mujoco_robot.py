#!/usr/bin/env python3
"""The whole HAMR-VI robot in MuJoCo beside mech (issue 16): the same URDF, the same trot.

    python bench/mujoco_robot.py [--mech target/release/mech] [--frequencies 10 5 2]
        [--timestep-us 10 20 50] [--mech-contact-timestep-us 5] [--ensemble 5]
        [--json OUT.jsonl] [--table OUT.md] [--mjcf OUT.xml]

Each walk starts from rest at the zero pose, as mech's locomotion experiment does, and its
forward speed is the chassis origin's over the measured cycles. MuJoCo's walks run in this
process (CPU and wall time of the stepping loop only); with --mech, the same walks run as
`mech experiment` on a one-walk copy of the TOML, and once more with 0.01 cycles for the
fixed cost (load, JIT compile) that the table subtracts.

Versions: mujoco==4.0.0 and numpy as pinned in ../shared/peers/requirements.txt.

What is read at run time (nothing is copied into this file):
- `../shared/reference/hamr-vi-urdf/HAMR_scaledV2.urdf` (`--urdf`): links (mass, centre of
  mass, inertia), tree joints, the Drake `<loop_joint>` closures and the foot collision
  points; in the file's units, mm, g, ms (so forces are in N, torques in N*mm).
- `models/robots/hamr_vi_robot.mech` (`--model`): its `param`s (flexure stiffnesses, loss
  factor, actuator F_b, delta_f, V_rated, contact k, alpha, mu, v_slip), its `flexure ... on
  JOINT` and `actuator ... on SLIDER` lines, and its bodies' inertias (checked against the
  URDF with the model's one documented change: the leg links L4 with products negated).
- `experiments/hamr_vi_locomotion.toml` (`--experiment`): amplitude, gait, lift phase, the
  legs' wiring signs, settle and measured cycles.

The MuJoCo model (MJCF written here from the URDF):
- the chassis on a free joint; every tree joint a hinge or slide;
- each loop closure (`loop_joint` LINK1-LINK2 about an axis) is cut inside LINK2: LINK2's
  mass and inertia are split in halves between LINK2 and a copy `LINK2_loop` hung on LINK1 by
  a hinge (the closure's axis, at LINK1's point), and an `<equality><weld>` holds the copy on
  LINK2. The closure's flexure is then a joint stiffness and damping like every other one;
- each flexure: joint `stiffness` k and `damping` b = k eta / (2 pi f_ref) (mech's Eq. 5);
- each actuator: the slide's `stiffness` k_a = F_b / delta_f and a `<motor>` whose control is
  the force source F_b V(t) / V_rated;
- each foot: a sphere of radius `--foot-radius` at the URDF's collision point (mech: a point),
  the floor plane lowered by that radius so the gap is the same; then either
  - MuJoCo's soft contact: friction mu on feet and floor (elliptic cone), `solref` = (time
    constant, damping ratio 1) with the time constant calibrated at each timestep so that
    each foot at rest sinks as far as mech's (m g / (4 k_ground), about 36 um): MuJoCo's
    contact stiffness is in the constraint's acceleration units, so mech's k_ground cannot be
    entered as such;
  - or mech's contact law, computed here and applied as a force before each step
    (`MechContact`; `--mech-contact-timestep-us`).
"""
import argparse
import json
import math
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
import tomllib
import xml.etree.ElementTree as ET

import numpy as np
import mujoco

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# .mech units of the parameters this script reads, in the URDF's mm, g, ms system
# (force N, torque N*mm, frequency 1/ms).
UNITS = {
    'N*mm/rad': 1.0, 'mN': 1e-3, 'N': 1.0, 'um': 1e-3, 'mm': 1.0, 'V': 1.0, 'N/m': 1e-3,
    's/m': 1.0, 'mm/s': 1e-3, 'g': 1.0, 'Hz': 1e-3, '': 1.0,
}


def numbers(text):
    """A URDF vector; some of the file's attributes separate numbers with commas."""
    return [float(x) for x in text.replace(',', ' ').split()]


def mech_params(path):
    """`param NAME = VALUE UNIT;` of a .mech file, converted to mm, g, ms."""
    params = {}
    for name, value, unit in re.findall(
            r'^param (\w+) = ([-+0-9.eE]+) ?([\w*/^]*);', open(path).read(), re.M):
        params[name] = float(value) * UNITS[unit]
    return params


def mech_elements(path, params):
    """The flexures (joint -> stiffness, damping) and actuators (slider -> input) of a .mech."""
    text = open(path).read()
    flexures = {}
    for m in re.finditer(r'^flexure (\w+) on (\w+) \{([^}]*)\}', text, re.M):
        fields = dict(re.findall(r'(\w+) = ([^;]+);', m.group(3)))
        k = params[fields['stiffness'].strip()]
        eta = params[fields['loss_factor'].strip()]
        f_ref = float(fields['reference_frequency'].split()[0]) * UNITS['Hz']
        flexures[m.group(2)] = (k, k * eta / (2 * math.pi * f_ref))
    actuators = {}
    for m in re.finditer(r'^actuator (\w+) on (\w+) \{([^}]*)\}', text, re.M):
        fields = dict(re.findall(r'(\w+) = ([^;]+);', m.group(3)))
        actuators[m.group(2)] = {key: fields[key].strip() for key in
                                 ('blocked_force', 'free_deflection', 'rated_voltage', 'voltage')}
    return flexures, actuators


def mech_inertias(path):
    """The bodies' [ixx, iyy, izz, ixy, iyz, ixz] (g*mm^2) of a .mech file."""
    return {name: numbers(values) for name, values in re.findall(
        r'^body (\w+) \{[^}]*?inertia = \[([^\]]*)\]', open(path).read(), re.M)}


def read_urdf(path):
    root = ET.parse(path).getroot()
    links = {}
    for link in root.findall('link'):
        inertial = link.find('inertial')
        i = inertial.find('inertia').attrib
        origin = inertial.find('origin')
        feet = [numbers(c.find('origin').get('xyz')) for c in link.findall('collision')]
        links[link.get('name')] = {
            'mass': float(inertial.find('mass').get('value')),
            'com': numbers(origin.get('xyz')) if origin is not None else [0, 0, 0],
            # MuJoCo's fullinertia order; both files give the tensor's own elements.
            'inertia': [float(i[k]) for k in ('ixx', 'iyy', 'izz', 'ixy', 'ixz', 'iyz')],
            'feet': feet,
        }
    joints = []
    for joint in root.findall('joint'):
        for tag in ('origin',):
            rpy = numbers(joint.find(tag).get('rpy', '0 0 0'))
            assert rpy == [0, 0, 0], 'every rpy of these files is zero (reference README)'
        joints.append({
            'name': joint.get('name'), 'type': joint.get('type'),
            'parent': joint.find('parent').get('link'), 'child': joint.find('child').get('link'),
            'xyz': numbers(joint.find('origin').get('xyz')),
            'axis': numbers(joint.find('axis').get('xyz')),
        })
    loops = []
    for loop in root.findall('loop_joint'):
        l1, l2 = loop.find('link1'), loop.find('link2')
        loops.append({
            'name': loop.get('name'), 'axis': numbers(loop.find('axis').get('xyz')),
            'link1': l1.get('link'), 'p1': numbers(l1.get('xyz')),
            'link2': l2.get('link'), 'p2': numbers(l2.get('xyz')),
        })
    return links, joints, loops


def leg_link_inertia(name, inertia):
    """mech's documented change (hamr_vi.mech caveat 2): each leg link L4's products negated."""
    if name.endswith('L4'):
        return inertia[:3] + [-x for x in inertia[3:]]
    return inertia


def fmt(values):
    return ' '.join(f'{v:.12g}' for v in values)


def build_mjcf(args, params, flexures, actuators):
    links, joints, loops = read_urdf(args.urdf)
    # Cross-check the inertias against the .mech model (its order ixx iyy izz ixy iyz ixz).
    mismatches = []
    for name, mech in mech_inertias(args.model).items():
        if name in links:
            mine = leg_link_inertia(name, links[name]['inertia'])
            mine = [mine[0], mine[1], mine[2], mine[3], mine[5], mine[4]]
            if max(abs(a - b) for a, b in zip(mine, mech)) > 1e-12 * max(map(abs, mech)):
                mismatches.append(name)
    split = {loop['link2'] for loop in loops}
    children = {}
    for j in joints:
        children.setdefault(j['parent'], []).append(j)
    hung = {}
    for loop in loops:
        hung.setdefault(loop['link1'], []).append(loop)
    all_children = {j['child'] for j in joints}
    (root,) = [name for name in links if name not in all_children]

    def inertial(name, link):
        share = 0.5 if name in split else 1.0
        inertia = [share * x for x in leg_link_inertia(name, link['inertia'])]
        return (f'<inertial pos="{fmt(link["com"])}" mass="{share * link["mass"]:.12g}" '
                f'fullinertia="{fmt(inertia)}"/>')

    def joint_xml(name, kind, pos, axis):
        k, b = flexures.get(name, (0.0, 0.0))
        if kind == 'slide':
            act = actuators[name]
            k = params[act['blocked_force']] / params[act['free_deflection']]
        return (f'<joint name="{name}" type="{kind}" pos="{fmt(pos)}" axis="{fmt(axis)}" '
                f'stiffness="{k:.12g}" damping="{b:.12g}"/>')

    def body(name, pos, joint, depth):
        link = links[name]
        pad = '  ' * depth
        out = [f'{pad}<body name="{name}" pos="{fmt(pos)}">', pad + '  ' + joint,
               pad + '  ' + inertial(name, link)]
        for n, foot in enumerate(link['feet']):
            out.append(f'{pad}  <geom name="{name}_foot{n}" type="sphere" size="{args.foot_radius}" '
                       f'pos="{fmt(foot)}" contype="1" conaffinity="0" condim="3" '
                       f'friction="{params["mu"]} 0 0"/>')
        for j in children.get(name, []):
            kind = {'prismatic': 'slide', 'revolute': 'hinge', 'continuous': 'hinge'}[j['type']]
            out += body(j['child'], j['xyz'], joint_xml(j['name'], kind, [0, 0, 0], j['axis']),
                        depth + 1)
        for loop in hung.get(name, []):
            # LINK2's copy: its frame where LINK2's is at the zero pose (every rpy is zero),
            # the hinge at LINK1's point of the closure.
            other = links[loop['link2']]
            pos = [a - b for a, b in zip(loop['p1'], loop['p2'])]
            out += [f'{pad}  <body name="{loop["link2"]}_loop" pos="{fmt(pos)}">',
                    pad + '    ' + joint_xml(loop['name'], 'hinge', loop['p2'], loop['axis']),
                    pad + '    ' + inertial(loop['link2'], other),
                    f'{pad}  </body>']
        out.append(f'{pad}</body>')
        return out

    g = -9.81e-3  # mm/ms^2
    chassis = body(root, [0, 0, 0], '<freejoint name="base"/>', 2)
    mass = sum(link['mass'] for link in links.values())
    # Normal contact: MuJoCo's soft contact, solref = (time constant, damping ratio) and
    # solimp; see the module's doc for what these change against mech's law.
    contact = (f'solimp="{args.contact_solimp}" '
               f'solref="{args.contact_timeconst:.12g} {args.contact_dampratio:.12g}"')
    eq = []
    for loop in loops:
        eq.append(f'    <weld name="{loop["name"]}" body1="{loop["link2"]}_loop" '
                  f'body2="{loop["link2"]}" solref="{2 * args.timestep_us * 1e-3:.12g} 1" '
                  f'solimp="{args.eq_impedance} {args.eq_impedance} 0.001 0.5 2"/>')
    motors = []
    for slider, act in actuators.items():
        motors.append(f'    <motor name="{act["voltage"]}" joint="{slider}" gear="1"/>')
    xml = '\n'.join([
        '<mujoco model="hamr_vi_robot_mujoco">',
        '  <compiler angle="radian" balanceinertia="false" boundmass="0" boundinertia="0"/>',
        f'  <option timestep="{args.timestep_us * 1e-3:.12g}" gravity="0 0 {g}" '
        f'integrator="{args.integrator}" cone="elliptic" solver="Newton" '
        f'iterations="{args.iterations}" tolerance="{args.tolerance}"/>',
        f'  <default><geom {contact}/></default>',
        '  <worldbody>',
        # The floor's friction is the feet's: MuJoCo takes the larger of the two geoms'
        # (its default 1 would otherwise override any smaller mu).
        '    <geom name="floor" type="plane" size="100 100 1" '
        f'friction="{params["mu"]} 0 0" '
        f'pos="0 0 FLOOR" contype="0" conaffinity="{int(args.contact == "mujoco")}"/>',
        *chassis,
        '  </worldbody>',
        '  <equality>', *eq, '  </equality>',
        '  <actuator>', *motors, '  </actuator>',
        '</mujoco>',
    ])
    return xml, {'mass': mass, 'mismatches': mismatches,
                 'loops': len(loops), 'links': len(links)}


def load_model(args, params, flexures, actuators):
    xml, info = build_mjcf(args, params, flexures, actuators)
    # The floor: where the lowest foot is at the zero pose (mech: the plane z = -12.54 mm of
    # the chassis frame), lowered by the foot sphere's radius.
    probe = mujoco.MjModel.from_xml_string(xml.replace('FLOOR', '-1000'))
    data = mujoco.MjData(probe)
    mujoco.mj_kinematics(probe, data)
    feet = [i for i in range(probe.ngeom) if probe.geom(i).name.endswith('_foot0')]
    floor = min(data.geom_xpos[i][2] for i in feet)
    info['floor'] = floor
    xml = xml.replace('FLOOR', f'{floor - args.foot_radius:.12g}')
    t0 = time.perf_counter()
    model = mujoco.MjModel.from_xml_string(xml)
    info['compile_s'] = time.perf_counter() - t0
    return model, xml, info


def drives(spec, actuators, params, model, hz):
    """Per motor: amplitude (N) and phase (rad) of F_b V(t) / V_rated, as mech's locomotion
    experiment wires the trot (src/experiments/locomotion.rs, `drives`)."""
    amplitude = float(spec['amplitude'].split()[0])
    lift_phase = math.radians(float(spec['lift_phase'].split()[0]))
    assert spec['gait'] == 'trot'
    phases = {}
    for leg in spec['leg']:
        phase = math.pi * (leg['front'] != leg['left'])
        flip = lambda sign: math.pi if sign < 0 else 0.0
        phases[leg['swing']] = phase + flip(leg['swing_sign'])
        phases[leg['lift']] = phase + lift_phase + flip(leg['lift_sign'])
    amp = np.zeros(model.nu)
    ph = np.zeros(model.nu)
    for slider, act in actuators.items():
        i = model.actuator(act['voltage']).id
        amp[i] = params[act['blocked_force']] * amplitude / params[act['rated_voltage']]
        ph[i] = phases[act['voltage']]
    return amp, ph, 2 * math.pi * hz * 1e-3  # rad/ms


class MechContact:
    """mech's contact law at each foot point (docs/mech-language.md, `contact`), applied as a
    force on the leg link before each step: Hunt-Crossley f_n = max(0, k d (1 + 3/2 alpha
    d')), regularized Coulomb f_t = -mu f_n v_t / sqrt(|v_t|^2 + v_s^2). Explicit in the
    step: MuJoCo's integrators do not see its stiffness, hence the shorter timesteps."""

    def __init__(self, model, params, floor):
        self.feet = [i for i in range(model.ngeom) if model.geom(i).name.endswith('_foot0')]
        self.bodies = [model.geom_bodyid[i] for i in self.feet]
        self.floor = floor
        self.k, self.alpha = params['k_ground'], params['alpha_ground']
        self.mu, self.vs = params['mu'], params['v_slip']
        self.vel = np.zeros(6)

    def apply(self, model, data):
        for geom, body in zip(self.feet, self.bodies):
            p = data.geom_xpos[geom]
            depth = self.floor - p[2]
            data.xfrc_applied[body] = 0.0
            if depth <= 0.0:
                continue
            mujoco.mj_objectVelocity(model, data, mujoco.mjtObj.mjOBJ_GEOM, geom, self.vel, 0)
            v = self.vel[3:]
            fn = max(0.0, self.k * depth * (1.0 + 1.5 * self.alpha * -v[2]))
            scale = -self.mu * fn / math.sqrt(v[0] ** 2 + v[1] ** 2 + self.vs ** 2)
            f = np.array([scale * v[0], scale * v[1], fn])
            data.xfrc_applied[body, :3] = f
            data.xfrc_applied[body, 3:] = np.cross(p - data.xipos[body], f)


def walk(model, spec, actuators, params, hz, contact=None):
    """From rest at the zero pose: settle_cycles + cycles of the trot; the chassis origin's
    forward speed over the measured cycles (mech's `measure`). `contact`: a MechContact, or
    None for MuJoCo's own."""
    data = mujoco.MjData(model)
    amp, ph, omega = drives(spec, actuators, params, model, hz)
    period = 1e3 / hz  # ms
    settle, cycles = spec.get('settle_cycles', 1), spec.get('cycles', 2)
    n_settle = round(settle * period / model.opt.timestep)
    n_total = round((settle + cycles) * period / model.opt.timestep)
    chassis = model.body('Chassis').id
    r0 = resource.getrusage(resource.RUSAGE_SELF)
    w0 = time.perf_counter()
    x_start = None
    weld_err = 0.0
    for n in range(n_total):
        if n == n_settle:
            x_start = data.xpos[chassis].copy()
        data.ctrl[:] = amp * np.sin(omega * data.time + ph)
        if contact is not None:
            contact.apply(model, data)
        mujoco.mj_step(model, data)
        if n % 100 == 0:
            weld_err = max(weld_err, np.max(np.abs(data.efc_pos[data.efc_type == 0]), initial=0))
    wall = time.perf_counter() - w0
    r1 = resource.getrusage(resource.RUSAGE_SELF)
    duration = (n_total - n_settle) * model.opt.timestep  # ms
    x_end = data.xpos[chassis]
    return {
        'speed_mm_s': float((x_end[0] - x_start[0]) / duration * 1e3),
        'sideways_mm_s': float((x_end[1] - x_start[1]) / duration * 1e3),
        'simulated_s': n_total * model.opt.timestep * 1e-3,
        'steps': n_total, 'wall_s': wall,
        'cpu_s': r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime,
        'max_weld_violation': float(weld_err),
        'height_mm': float(x_end[2]),
    }


def settle_penetration(model, seconds=0.1):
    """Each foot's penetration after `seconds` at rest (mech: m g / (4 k) ~ 36 um)."""
    data = mujoco.MjData(model)
    for _ in range(round(seconds * 1e3 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    floor = model.geom('floor').pos[2]
    return [float(floor - (data.geom_xpos[i][2] - model.geom_size[i][0]))
            for i in range(model.ngeom) if model.geom(i).name.endswith('_foot0')]


def calibrate(args, params, flexures, actuators):
    """The contact time constant at which a foot at rest sinks mech's m g / (4 k_ground):
    MuJoCo's static penetration grows about as the square of the time constant."""
    timeconst = 2.0
    for _ in range(3):
        args.contact_timeconst = timeconst
        model, _, info = load_model(args, params, flexures, actuators)
        target = info['mass'] * 9.81e-3 / 4 / params['k_ground']
        sink = np.mean(settle_penetration(model))
        timeconst *= math.sqrt(target / sink)
    return timeconst


def run_mech(args, hz):
    """One walk of `mech experiment` (the locomotion TOML with one frequency, payload 0),
    and its fixed cost (model load and compile: the same TOML with 0.01 cycles)."""
    text = open(args.experiment).read()
    out = {}
    for label, cycles in (('fixed', None), ('walk', True)):
        t = re.sub(r'^frequencies = .*$', f'frequencies = ["{hz} Hz"]', text, flags=re.M)
        t = re.sub(r'^payloads = .*$', 'payloads = ["0 g"]', t, flags=re.M)
        # HAMR-VI alone (the file walks HAMR-V2.0 beside it).
        t = re.sub(r'^compare = .*$', '', t, flags=re.M)
        if cycles is None:
            t = re.sub(r'^settle_cycles = .*$', 'settle_cycles = 0', t, flags=re.M)
            t = re.sub(r'^cycles = .*$', 'cycles = 0.01', t, flags=re.M)
        with tempfile.TemporaryDirectory(prefix='mech_walk_') as d:
            out[label] = mech_walk(args, d, t)
    return out


def mech_walk(args, d, t):
    """`mech experiment` on the TOML text `t` in the folder `d`: its times and its CSV row."""
    path = os.path.join(d, 'walk.toml')
    # The model path in the TOML is relative to the repository root, where this runs.
    open(path, 'w').write(t)
    cmd = [args.mech, 'experiment', path, '--out-dir', d]
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    w0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    wall = time.perf_counter() - w0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    rec = {'cmd': ' '.join(cmd), 'rc': proc.returncode, 'wall_s': wall,
           'cpu_s': r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime}
    csv = [os.path.join(r, f) for r, _, fs in os.walk(d) for f in fs if f == 'locomotion.csv']
    if proc.returncode != 0 or not csv:
        rec['stderr'] = proc.stderr[-2000:]
    else:
        lines = open(csv[0]).read().splitlines()
        header = lines[0].split(',')
        row = dict(zip(header, lines[1].split(',')))
        rec['row'] = row
    return rec


def table(records, spec):
    """The measurements as a Markdown table (per simulated second: the walk's CPU and wall
    time over its simulated time; mech's less its fixed cost, the model's load and compile)."""
    cycles = spec.get('settle_cycles', 1) + spec.get('cycles', 2)
    L = ['| simulator | contact | step | gait | forward speed (mm/s) | sideways (mm/s) '
         '| CPU s per simulated s | wall s per simulated s | load average |',
         '|---|---|---|---|---|---|---|---|---|']
    groups = {}
    for r in records:
        if r['record'] == 'mujoco':
            groups.setdefault((r['contact'], r['timestep_us'], r['hz']), []).append(r)
    for r in records:
        load = r['loadavg'].split()[0] if 'loadavg' in r else '-'
        if r['record'] == 'mujoco' and r['member'] == 0:
            runs = groups[(r['contact'], r['timestep_us'], r['hz'])]
            law = 'MuJoCo soft contact' if r['contact'] == 'mujoco' else "mech's law, applied"
            speeds = [x['speed_mm_s'] for x in runs]
            speed = f'{speeds[0]:.1f}'
            if len(runs) > 1:
                speed += f' ({min(speeds):.1f} to {max(speeds):.1f} in {len(runs)} walks)'
            side = f"{r['sideways_mm_s']:.1f}"
            cpu = sum(x['cpu_s'] for x in runs) / sum(x['simulated_s'] for x in runs)
            wall = sum(x['wall_s'] for x in runs) / sum(x['simulated_s'] for x in runs)
            L.append(f"| MuJoCo {r['integrator']} | {law} | {r['timestep_us']:g} us "
                     f"| {r['hz']:g} Hz | {speed} | {side} | {cpu:.2f} | {wall:.2f} | {load} |")
        elif r['record'] == 'mech':
            walk, fixed = r['walk'], r['fixed']
            if 'row' not in walk or 'row' not in fixed:
                L.append(f"| mech | - | - | {r['hz']:g} Hz | failed: {walk.get('stderr', '')[-200:]!r} "
                         '| | | | |')
                continue
            simulated = cycles / r['hz']
            row = walk['row']
            integrator = f"{spec.get('method', 'dopri5')}, rtol {spec.get('rtol', 1e-6):g}"
            L.append(f"| mech ({integrator}) | Hunt-Crossley, regularized Coulomb "
                     f"| adaptive | {r['hz']:g} Hz | {float(row['speed_mm_s']):.1f} "
                     f"| {float(row['sideways_mm_s']):.1f} "
                     f"| {(walk['cpu_s'] - fixed['cpu_s']) / simulated:.2f} "
                     f"| {(walk['wall_s'] - fixed['wall_s']) / simulated:.2f} | {load} |")
    return '\n'.join(L) + '\n'


def main():
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--urdf', default=os.path.join(
        ROOT, '..', 'shared', 'reference', 'hamr-vi-urdf', 'HAMR_scaledV2.urdf'))
    p.add_argument('--model', default=os.path.join(ROOT, 'models', 'robots', 'hamr_vi_robot.mech'))
    p.add_argument('--experiment', default=os.path.join(ROOT, 'experiments', 'hamr_vi_locomotion.toml'))
    p.add_argument('--frequencies', type=float, nargs='+', default=[10.0])
    p.add_argument('--timestep-us', type=float, nargs='+', default=[10.0, 20.0, 50.0])
    p.add_argument('--mech-contact-timestep-us', type=float, nargs='*', default=[5.0],
                   help="timesteps of runs with mech's contact law in place of MuJoCo's")
    p.add_argument('--ensemble', type=int, default=5,
                   help="walks on MuJoCo's contact, its time constant changed by 1e-3 each")
    p.add_argument('--integrator', default='implicitfast')
    p.add_argument('--iterations', type=int, default=100)
    p.add_argument('--tolerance', type=float, default=1e-10)
    p.add_argument('--eq-impedance', type=float, default=0.9999,
                   help="the loop welds' solimp d (their solref time constant is 2 steps, "
                        "MuJoCo's stiffest)")
    p.add_argument('--contact-timeconst', type=float,
                   help="ms; default: calibrated at each timestep so that each foot at rest "
                        "sinks as far as mech's")
    p.add_argument('--contact-dampratio', type=float, default=1.0)
    p.add_argument('--contact-solimp', default='0.9 0.95 0.001 0.5 2')
    p.add_argument('--foot-radius', type=float, default=0.05, help='mm')
    p.add_argument('--mech', help='a mech binary: run the same walks with `mech experiment`')
    p.add_argument('--json', help='append one JSON line per measurement')
    p.add_argument('--mjcf', help='write the generated MJCF here')
    p.add_argument('--table', help='write the measurements as a Markdown table here')
    args = p.parse_args()

    params = mech_params(args.model)
    flexures, actuators = mech_elements(args.model, params)
    timesteps = args.timestep_us
    fixed_timeconst = args.contact_timeconst
    spec = tomllib.load(open(args.experiment, 'rb'))
    records = []
    header = None
    runs = [('mujoco', dt) for dt in timesteps]
    runs += [('mech', dt) for dt in args.mech_contact_timestep_us]
    for args.contact, dt in runs:
        args.timestep_us = dt
        if fixed_timeconst is None and args.contact == 'mujoco':
            # Calibrated at each timestep: MuJoCo's soft contact depends on it.
            args.contact_timeconst = calibrate(args, params, flexures, actuators)
        model, xml, info = load_model(args, params, flexures, actuators)
        if args.mjcf:
            open(args.mjcf, 'w').write(xml)
        if header is None or args.contact == 'mujoco':
            header = {
                'record': 'model', 'contact': args.contact, 'timestep_us': dt, 'mujoco': mujoco.__version__, 'numpy': np.__version__,
                'nq': model.nq, 'nv': model.nv, 'nbody': model.nbody, 'neq': model.neq,
                'nu': model.nu, 'mass_g': info['mass'], 'floor_mm': info['floor'],
                'contact_solref': [args.contact_timeconst, args.contact_dampratio],
                'contact_solimp': args.contact_solimp, 'inertia_mismatches': info['mismatches'],
                'flexures': len(flexures), 'actuators': len(actuators),
                'compile_s': info['compile_s'], 'loadavg': open('/proc/loadavg').read().strip(),
                'penetration_mm': settle_penetration(model),
                'mech_penetration_mm': info['mass'] * 9.81e-3 / 4 / params['k_ground'],
            }
            records.append(header)
            print(json.dumps(header), flush=True)
        law = MechContact(model, params, info['floor']) if args.contact == 'mech' else None
        # The walk on MuJoCo's contact is sensitive to its parameters: --ensemble N walks,
        # the contact's time constant changed by 1e-3 of itself each, show the spread.
        timeconst = args.contact_timeconst
        for member in range(args.ensemble if law is None else 1):
            if member:
                args.contact_timeconst = timeconst * (1 + 1e-3 * member)
                model = load_model(args, params, flexures, actuators)[0]
            for hz in args.frequencies:
                rec = {'record': 'mujoco', 'contact': args.contact, 'hz': hz, 'timestep_us': dt,
                       'member': member, 'integrator': args.integrator,
                       **walk(model, spec, actuators, params, hz, law),
                       'loadavg': open('/proc/loadavg').read().strip()}
                records.append(rec)
                print(json.dumps(rec), flush=True)
        args.contact_timeconst = timeconst
    if args.mech:
        for hz in args.frequencies:
            rec = {'record': 'mech', 'hz': hz, **run_mech(args, hz),
                   'loadavg': open('/proc/loadavg').read().strip()}
            records.append(rec)
            print(json.dumps(rec), flush=True)
    if args.table:
        with open(args.table, 'w') as f:
            f.write(table(records, spec))
    if args.json:
        with open(args.json, 'a') as f:
            for rec in records:
                f.write(json.dumps(rec) + '\n')


if __name__ == '__main__':
    sys.exit(main())
