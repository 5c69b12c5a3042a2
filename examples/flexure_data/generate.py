#!/usr/bin/env python3
"""Regenerates the example decay traces of this directory with the project's own simulator.

Each specimen is the rig `models/flexure_rig.mech` with a flexure of the seed's ranges and a
pendulum chosen so that gravity supplies about a third of the stiffness, simulated by
`mech simulate` from the default release angle (10 deg), then reduced to two columns
(time s, angle rad) at 7 significant digits, with Gaussian tracking noise of 0.05 deg
(seeded, reproducible). E = 2.56 GPa; eta = 0.05 (uncastellated),
eta' = 0.08 and l_eff = 66 um (castellated, seed Table III widths); the damping uses
omega_ref = the rig's own damped frequency (Eq. 5 with omega = omega_d).

Run from the repository root: python3 examples/flexure_data/generate.py
"""
import csv
import math
import os
import random
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
E = 2.56e9
RIGS = [  # mass kg, L_cm m; inertia about the pivot for a rod of length 2 L_cm
    (0.05e-3, 2e-3), (0.2e-3, 3e-3), (1e-3, 5e-3), (5e-3, 8e-3), (20e-3, 12e-3),
]
SPECIMENS = [  # name, kind, w m, t m, nominal l m, length in Eq. 2, eta
    ("u01", "uncastellated", 1.0e-3, 25e-6, 100e-6, 100e-6, 0.05),
    ("u02", "uncastellated", 3.0e-3, 25e-6, 200e-6, 200e-6, 0.05),
    ("u03", "uncastellated", 2.0e-3, 50e-6, 500e-6, 500e-6, 0.05),
    ("u04", "uncastellated", 6.0e-3, 12e-6, 500e-6, 500e-6, 0.05),
    ("c01", "castellated", 0.64e-3, 25e-6, 120e-6, 66e-6, 0.08),
    ("c02", "castellated", 1.23e-3, 25e-6, 120e-6, 66e-6, 0.08),
    ("c03", "castellated", 2.00e-3, 25e-6, 120e-6, 66e-6, 0.08),
]


def rig_for(k):
    best = min(RIGS, key=lambda r: abs(math.log(r[0] * 9.81 * r[1] / (0.5 * k))))
    m, l = best
    return m, m * l * l + m * (2 * l) ** 2 / 12, l


for name, kind, w, t, l, l_eq, eta in SPECIMENS:
    k = E * w * t**3 / (12 * l_eq)
    m, inertia, l_cm = rig_for(k)
    omega_n = math.sqrt((k + m * 9.81 * l_cm) / inertia)
    omega_d = omega_n
    for _ in range(50):
        b = k * eta / omega_d
        omega_d = omega_n * math.sqrt(1 - (b / (2 * inertia * omega_n)) ** 2)
    sigma = b / (2 * inertia)
    t_end = 4.0 / sigma
    dt = min(2e-3, 2 * math.pi / omega_d / 30)
    sets = {"m": f"{m} kg", "I_p": f"{inertia} kg*m^2", "L_cm": f"{l_cm} m", "E": f"{E} Pa",
            "w": f"{w} m", "h": f"{t} m", "l": f"{l_eq} m", "eta": f"{eta}",
            "omega_ref": f"{omega_d} rad/s"}
    with tempfile.TemporaryDirectory() as tmp:
        raw = os.path.join(tmp, "raw.csv")
        command = ["cargo", "run", "--release", "-q", "--", "simulate", "models/flexure_rig.mech",
                   "--t-end", f"{t_end} s", "--dt-out", f"{dt} s", "--out", raw]
        for key, value in sets.items():
            command += ["--set", f"{key}={value}"]
        subprocess.run(command, check=True)
        with open(raw) as f:
            rows = list(csv.DictReader(f))
    with open(os.path.join(HERE, f"{name}.csv"), "w") as f:
        f.write("t,angle\n")
        rng = random.Random(name)
        for row in rows:
            angle = float(row['angle']) + rng.gauss(0.0, math.radians(0.05))
            f.write(f"{float(row['t']):.7g},{angle:.7g}\n")
    castellation = '\ncastellation_length = "100 um"' if kind == "castellated" else ""
    with open(os.path.join(HERE, f"{name}.toml"), "w") as f:
        f.write(f"""# Synthetic specimen {name} (generate.py): {kind}, simulated with models/flexure_rig.mech.
name = "{name.upper()}"
traces = ["{name}.csv"]

[flexure]
kind = "{kind}"
width = "{w * 1e3:.4g} mm"
thickness = "{t * 1e6:.4g} um"
length = "{l * 1e6:.4g} um"{castellation}

[pendulum]
mass = "{m * 1e3:.6g} g"
inertia = "{inertia:.10g} kg*m^2"
com_distance = "{l_cm * 1e3:.6g} mm"
""")
    print(f"{name}: k = {k:.4e} N*m/rad, f_d = {omega_d / (2 * math.pi):.3f} Hz, {len(rows)} samples")
