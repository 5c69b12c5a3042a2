"""Experiments and diagnoses from Python, against the model API and data made in NumPy.

Run from the repository root after `pip install ./python pytest`: `pytest python/tests`.
"""

import math
from pathlib import Path

import numpy as np
import pytest

import mech

ROOT = Path(__file__).resolve().parents[2]


# ---------------------------------------------------------------- experiment files


def test_experiment_returns_the_tables_and_the_linearized_modes(tmp_path, monkeypatch):
    """The Bode experiment of HAMR-VI: its modes are the model's own linearization about rest
    (the same leg through `Model.linearize`), its tables have headers and rows; files are
    written only where asked, and all of them."""
    monkeypatch.chdir(ROOT)  # the experiment's model path is relative to the repository
    result = mech.experiment(ROOT / "experiments" / "hamr_vi_bode.toml")
    assert result["title"].startswith("5. Dynamic regime")
    assert result["files"] == []
    leg = mech.load(ROOT / "models" / "hamr_vi.mech")
    modes = leg.linearize(independent=["qsact", "qlact"])["frequency_hz"]
    assert result["values"]["mode1_hz"] == pytest.approx(modes[0], rel=1e-9)
    assert result["values"]["mode2_hz"] == pytest.approx(modes[1], rel=1e-9)
    for table in result["tables"]:
        assert table["header"] and table["rows"]
        assert all(len(row) == len(table["header"]) for row in table["rows"])
    written = mech.experiment(ROOT / "experiments" / "hamr_vi_bode.toml", out_dir=tmp_path)
    assert written["files"]
    assert all(Path(f).is_file() and Path(f).is_relative_to(tmp_path) for f in written["files"])


def test_experiment_errors_are_raised():
    with pytest.raises(mech.MechError, match="no_such.toml"):
        mech.experiment(ROOT / "experiments" / "no_such.toml")


# ---------------------------------------------------------------- diagnosis of a ring-down


def ring_down(eta, seconds=2.5, noise_deg=0.05, seed=3):
    """The flexure rig (`models/flexure_rig.mech`'s parameters) released from 10° at rest,
    integrated here by RK4 (1e-4 s) from its equation of motion,
    I_p θ̈ = −k θ − b θ̇ − m g L sin θ with k = E w h³/(12 l), b = k η / ω_ref, and sampled at
    1 kHz with Gaussian noise: data mech did not make."""
    m, inertia, length, g = 0.2e-3, 2.4e-9, 3e-3, 9.81
    modulus, width, thickness, hinge, omega_ref = 2.56e9, 2e-3, 25e-6, 0.5e-3, 89.0
    k = modulus * width * thickness**3 / (12 * hinge)
    b = k * eta / omega_ref

    def acceleration(theta, omega):
        return (-k * theta - b * omega - m * g * length * math.sin(theta)) / inertia

    dt, every = 1e-4, 10
    theta, omega = math.radians(10.0), 0.0
    samples = []
    for step in range(int(round(seconds / dt)) + 1):
        if step % every == 0:
            samples.append((step * dt, theta))
        k1 = (omega, acceleration(theta, omega))
        k2 = (omega + dt / 2 * k1[1], acceleration(theta + dt / 2 * k1[0], omega + dt / 2 * k1[1]))
        k3 = (omega + dt / 2 * k2[1], acceleration(theta + dt / 2 * k2[0], omega + dt / 2 * k2[1]))
        k4 = (omega + dt * k3[1], acceleration(theta + dt * k3[0], omega + dt * k3[1]))
        theta += dt / 6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
        omega += dt / 6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
    rng = np.random.default_rng(seed)
    times = np.array([t for t, _ in samples])
    angles = np.degrees([a for _, a in samples]) + noise_deg * rng.standard_normal(len(samples))
    return times, angles


def diagnose_ring_down(tmp_path, eta):
    times, angles = ring_down(eta)
    data = tmp_path / "ringdown.csv"
    data.write_text(
        "time [s], angle [deg]\n" + "".join(f"{t:.6f}, {a:.6f}\n" for t, a in zip(times, angles))
    )
    experiment = tmp_path / "ringdown.toml"
    experiment.write_text(
        'kind = "pendulum"\ntitle = "ring-down"\n'
        f'model = "{(ROOT / "models" / "flexure_rig.mech").as_posix()}"\n'
        'angle = "angle"\nnoise = "0.05 deg"\n'
    )
    return mech.diagnose(experiment, data)


def test_diagnose_finds_nothing_in_a_ring_down_of_the_model_as_written(tmp_path):
    result = diagnose_ring_down(tmp_path, eta=0.05)
    assert result["verdict"] == "no_significant_discrepancy", result["summary"]


def test_diagnose_names_a_larger_loss_factor(tmp_path):
    """η = 0.07 in the data, 0.05 in the model: the loss factor is named, within 3σ."""
    result = diagnose_ring_down(tmp_path, eta=0.07)
    assert result["verdict"] == "explained", result["summary"]
    best = result["ranked"][0]
    assert best["cause"] == "loss factor differs"
    (eta,) = [p for p in best["parameters"] if p["name"] == "eta"]
    assert abs(eta["value"] - 0.07) < 3 * eta["standard_error"], eta
    assert result["summary"].startswith("cause: loss factor differs")


def test_diagnose_errors_are_raised(tmp_path):
    with pytest.raises(mech.MechError, match="missing.csv"):
        mech.diagnose(ROOT / "docs/examples/diagnose/flexure_rig_ringdown.toml", tmp_path / "missing.csv")


# ------------------------------------------------------------------------ the whole report


def test_report_writes_the_pages_and_each_experiments_files(tmp_path, monkeypatch):
    """Two experiments (the trajectory and force tests of HAMR-VI) copied into a folder of
    their own: both pages written, in title order, each experiment's values those of
    `mech.experiment` on the same file."""
    monkeypatch.chdir(ROOT)
    folder = tmp_path / "experiments"
    folder.mkdir()
    for name in ("hamr_vi_force", "hamr_vi_trajectory"):
        (folder / f"{name}.toml").write_text((ROOT / "experiments" / f"{name}.toml").read_text())
    out = tmp_path / "report"
    result = mech.report(out, experiments=folder)
    html, markdown = Path(result["html"]), Path(result["markdown"])
    assert html == out / "report.html" and markdown == out / "report.md"
    titles = [e["title"] for e in result["experiments"]]
    assert titles == sorted(titles) and len(titles) == 2
    page = html.read_text()
    assert all(title in page for title in titles) and "<svg" in page
    assert all(title in markdown.read_text() for title in titles)
    for outcome in result["experiments"]:
        assert outcome["files"] and all(Path(f).exists() for f in outcome["files"])
        alone = mech.experiment(folder / f"{outcome['name']}.toml")
        assert outcome["values"] == alone["values"]
    with pytest.raises(mech.MechError, match="experiments folder"):
        mech.report(out, experiments=tmp_path / "nothing")


# ---------------------------------------------------------------- steady motion

# Meijaard, Papadopoulos, Ruina & Schwab (2007), eq. (A 24): the benchmark bicycle's
# M q̈ + v C1 q̇ + (g K0 + v² K2) q = 0 in q = (roll, steer).
BICYCLE_M = np.array([[80.81722, 2.31941332208709], [2.31941332208709, 0.29784188199686]])
BICYCLE_C1 = np.array([[0.0, 33.86641391492494], [-0.85035641456978, 1.68540397397560]])
BICYCLE_K0 = np.array([[-80.95, -2.59951685249872], [-2.59951685249872, -0.80329488458618]])
BICYCLE_K2 = np.array([[0.0, 76.59734589573222], [0.0, 2.65431523794604]])


def test_linearize_steady_gives_the_benchmark_bicycle():
    """`models/benchmarks/whipple_bicycle.mech` at 3 and 5 m/s (`set("v=…")` moves the rear wheel's
    `u0 = v / rR`): the second-order matrices are the paper's, and the eigenvalues but the
    forward speed's zero are those of the paper's equations, solved here in NumPy."""
    bicycle = mech.load(ROOT / "models" / "benchmarks" / "whipple_bicycle.mech")
    for v in (3.0, 5.0):
        bicycle.set(f"v={v} m/s")
        steady = bicycle.linearize_steady(independent=["roll", "steer", "rear"])
        assert steady["cyclic"] == ["x", "y", "yaw", "rear", "front"]
        assert steady["states"] == ["q_roll", "q_steer", "u_roll", "u_rear", "u_steer"]
        assert steady["coordinates"] == ["roll", "steer"]
        assert steady["unsteadiness"] < 1e-12
        np.testing.assert_allclose(steady["M"], BICYCLE_M, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(steady["C"], v * BICYCLE_C1, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(
            steady["K"], 9.81 * BICYCLE_K0 + v * v * BICYCLE_K2, rtol=1e-9, atol=1e-9
        )
        a = np.block(
            [
                [np.zeros((2, 2)), np.eye(2)],
                [
                    -np.linalg.solve(BICYCLE_M, 9.81 * BICYCLE_K0 + v * v * BICYCLE_K2),
                    -np.linalg.solve(BICYCLE_M, v * BICYCLE_C1),
                ],
            ]
        )
        expected = np.sort_complex(np.linalg.eigvals(a))
        ours = steady["eigenvalues"]
        ours = np.sort_complex(ours[np.abs(ours) > 1e-9])
        np.testing.assert_allclose(ours, expected, rtol=1e-9)


def test_linearize_steady_refuses_a_quaternion_model():
    pendulum = mech.load(ROOT / "models" / "ball_double_pendulum.mech")
    with pytest.raises(mech.MechError, match="steady-motion linearization"):
        pendulum.linearize_steady()
