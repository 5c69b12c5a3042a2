"""The Python package against closed forms and independent computations in NumPy.

Run from the repository root after `pip install ./python pytest`: `pytest python/tests`.
"""

import math
import threading
from pathlib import Path

import numpy as np
import pytest

import mech

MODELS = Path(__file__).resolve().parents[2] / "models"


def model(name, **kwargs):
    return mech.load(MODELS / f"{name}.mech", **kwargs)


# ---------------------------------------------------------------- a pendulum: closed forms


def test_pendulum_equations_are_the_closed_form():
    """M = m l², F = −m g l sin q − c u for a point mass on a massless rod."""
    pendulum = model("pendulum", set={"l": "30 mm", "c": 2e-6})
    m, l, g, c = (pendulum.parameters[k] for k in ("m", "l", "g", "c"))
    assert l == pytest.approx(0.03, rel=1e-15)
    for q, u in [(0.3, -1.2), (-2.0, 0.5), (3.0, 0.0)]:
        M = pendulum.mass_matrix(np.array([q]))
        F = pendulum.forcing(np.array([q]), np.array([u]))
        assert M.shape == (1, 1)
        assert M[0, 0] == pytest.approx(m * l**2, rel=1e-14)
        assert F[0] == pytest.approx(-m * g * l * math.sin(q) - c * u, rel=1e-13, abs=1e-18)


def test_mass_matrix_has_a_row_per_speed():
    """With quaternions there are fewer speeds than coordinates: M is nu × nu and F has nu
    rows, and ½ uᵀ M u is the kinetic energy the model sums body by body (an output)."""
    chain = model("floating_chain")
    nq, nu = len(chain.coordinates), len(chain.speeds)
    assert (nq, nu) == (12, 10)
    rng = np.random.default_rng(7)
    q = rng.uniform(-1, 1, nq)
    for name in ("float", "wrist"):
        part = [chain.coordinates.index(f"{name}.e{k}") for k in range(4)]
        q[part] /= np.linalg.norm(q[part])
    u = rng.uniform(-1, 1, nu)
    M, F = chain.mass_matrix(q), chain.forcing(q, u)
    assert M.shape == (nu, nu) and F.shape == (nu,)
    assert np.array_equal(M, M.T)
    ke = chain.evaluate_outputs(q, u)[chain.outputs.index("ke")]
    assert 0.5 * u @ M @ u == pytest.approx(ke, rel=1e-13)


def test_pendulum_frequency_and_energy():
    """The linearized frequency is √(g/l)/2π; undamped, the simulated energy stays constant and
    the small-amplitude period is the linear one."""
    pendulum = model("pendulum", set={"l": 0.04})
    g, l = pendulum.parameters["g"], pendulum.parameters["l"]
    f_n = math.sqrt(g / l) / (2 * math.pi)
    linear = pendulum.linearize()
    assert linear["frequency_hz"][0] == pytest.approx(f_n, rel=1e-6)
    assert linear["coordinates"] == ["hinge"]

    run = pendulum.simulate(t_end=2.0, dt_out=1e-3, rtol=1e-11, atol=1e-13)
    assert run["t"].shape == (2001,) and run["q"].shape == (2001, 1)
    names = pendulum.outputs
    energy = run["outputs"][:, names.index("ke")] + run["outputs"][:, names.index("pe")]
    assert np.max(np.abs(energy - energy[0])) <= 1e-9 * abs(energy[0])
    # Upward zero crossings of the angle: the period, against 2π√(l/g) corrected for the
    # amplitude (K(k) series to θ₀⁴, enough at the model's q0).
    angle = run["q"][:, 0]
    theta0 = abs(angle).max()
    up = np.nonzero((angle[:-1] < 0) & (angle[1:] >= 0))[0]
    t = run["t"]
    crossings = t[up] - angle[up] * (t[up + 1] - t[up]) / (angle[up + 1] - angle[up])
    period = np.mean(np.diff(crossings))
    closed = 2 * math.pi * math.sqrt(l / g) * (1 + theta0**2 / 16 + 11 * theta0**4 / 3072)
    assert period == pytest.approx(closed, rel=2e-5)


# ----------------------------------------------------- a two-mass chain: hand-written matrices


def test_two_mass_chain_linear_model_is_written_by_hand():
    """m2 sits at x1 + x21: M = [[m1 + m2, m2], [m2, m2]], K = diag(k1, k2), C = diag(c1, c2),
    B = [1, 1]ᵀ; the state-space form is rebuilt in NumPy and its response x2/push at ω
    compared with the direct solve of (−ω² M + iω C + K) z = B."""
    chain = model("two_mass_chain")
    p = chain.parameters
    linear = chain.linearize()
    M = np.array([[p["m1"] + p["m2"], p["m2"]], [p["m2"], p["m2"]]])
    K = np.diag([p["k1"], p["k2"]])
    C = np.diag([p["c1"], p["c2"]])
    np.testing.assert_allclose(linear["M"], M, rtol=1e-9)
    np.testing.assert_allclose(linear["K"], K, rtol=1e-7)
    np.testing.assert_allclose(linear["C"], C, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(linear["B"], [[1.0], [1.0]], rtol=1e-9)
    inverse = np.linalg.inv(M)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-inverse @ K, -inverse @ C]])
    np.testing.assert_allclose(linear["A"], A, rtol=1e-7, atol=1e-7)
    x2 = chain.outputs.index("x2.x")
    for omega in [1.0, 11.0, 30.0]:
        state = np.linalg.solve(1j * omega * np.eye(4) - linear["A"], linear["B_s"][:, 0])
        response = linear["C_s"][x2] @ state + linear["D_s"][x2, 0]
        z = np.linalg.solve(-(omega**2) * M + 1j * omega * C + K, np.ones(2))
        assert abs(response - z.sum()) <= 1e-6 * abs(z.sum())
    # Undamped modes: the generalized eigenvalues of (K, M).
    omega2 = np.sort(np.linalg.eigvals(inverse @ K).real)
    np.testing.assert_allclose(linear["frequency_hz"], np.sqrt(omega2) / (2 * math.pi), rtol=1e-6)


def test_bode_is_the_chains_response_written_by_hand():
    """x2/push at 0.1–30 Hz against (−ω² M + iω C + K)⁻¹ B summed over x1 + x21; no flexures,
    so hysteretic and viscous agree."""
    chain = model("two_mass_chain")
    p = chain.parameters
    frequencies = np.geomspace(0.1, 30.0, 25)
    gains = chain.bode("push", "x2.x", frequencies)
    viscous = chain.bode("push", "x2.x", frequencies, damping="viscous")
    M = np.array([[p["m1"] + p["m2"], p["m2"]], [p["m2"], p["m2"]]])
    C, K = np.diag([p["c1"], p["c2"]]), np.diag([p["k1"], p["k2"]])
    for f, gain, gain_viscous in zip(frequencies, gains, viscous):
        omega = 2 * math.pi * f
        expected = np.linalg.solve(-(omega**2) * M + 1j * omega * C + K, np.ones(2)).sum()
        assert abs(gain - expected) <= 1e-6 * abs(expected)
        assert gain_viscous == gain
    with pytest.raises(mech.MechError, match="push"):
        chain.bode("pull", "x2.x", frequencies)
    with pytest.raises(mech.MechError, match="hysteretic"):
        chain.bode("push", "x2.x", frequencies, damping="coulomb")


def test_a_driven_chain_settles_on_its_linear_response():
    """A sinusoidal push: after the transient (damping time 2m/c ≈ 3 s) the simulated x2 has
    the amplitude |H(ω)| of the chain's frequency response."""
    chain = model("two_mass_chain", inputs={"push": "sine(amplitude=2 N, frequency=1.5 Hz)"})
    p = chain.parameters
    run = chain.simulate(t_end=40.0, dt_out=1e-3)
    omega = 2 * math.pi * 1.5
    M = np.array([[p["m1"] + p["m2"], p["m2"]], [p["m2"], p["m2"]]])
    z = np.linalg.solve(
        -(omega**2) * M + 1j * omega * np.diag([p["c1"], p["c2"]]) + np.diag([p["k1"], p["k2"]]),
        np.ones(2),
    )
    x2 = run["outputs"][:, chain.outputs.index("x2.x")]
    late = run["t"] > 30.0
    amplitude = 0.5 * (x2[late].max() - x2[late].min())
    assert amplitude == pytest.approx(2.0 * abs(z.sum()), rel=1e-3)
    assert np.allclose(run["inputs"][:, 0], 2.0 * np.sin(omega * run["t"]), atol=1e-12)


# --------------------------------------------------------- a four-bar: loops, statics, threads


def four_bar_tip(p, crank, near):
    """The coupler–rocker joint of the four-bar at crank angle `crank`, written here from the
    geometry (the intersection of two circles), on the branch nearest `near`."""
    P = p["crank_length"] * np.array([math.cos(crank), math.sin(crank)])
    R = np.array([p["ground"], 0.0])
    a, b = p["coupler_length"], p["rocker_length"]
    d = np.linalg.norm(R - P)
    along = (a**2 - b**2 + d**2) / (2 * d)
    across = math.sqrt(a**2 - along**2)
    e = (R - P) / d
    normal = np.array([-e[1], e[0]])
    candidates = [P + along * e + sign * across * normal for sign in (1, -1)]
    return P, R, min(candidates, key=lambda T: np.linalg.norm(T - near))


def test_four_bar_equilibrium_is_stationary_on_the_loop():
    """The statics' equilibrium, against the four-bar written here from its geometry: the
    coordinates close the loop, and the potential energy along the loop (three uniform links
    under gravity) is stationary at the equilibrium's crank angle."""
    four_bar = model("four_bar")
    p = four_bar.parameters
    equilibrium = four_bar.statics(independent={"crank_angle": "-1.5 rad"})
    assert equilibrium["force_residual"] < 1e-9 and equilibrium["constraint_residual"] < 1e-12
    crank, coupler, rocker = equilibrium["q"]
    tip = four_bar.evaluate_outputs(equilibrium["q"], np.zeros(3))
    P, R, T = four_bar_tip(p, crank, near=np.zeros(2))
    # The model's coupler angle is relative to the crank; its rocker angle absolute.
    T_model = R + p["rocker_length"] * np.array([math.cos(rocker), math.sin(rocker)])
    np.testing.assert_allclose(
        P + p["coupler_length"] * np.array([math.cos(crank + coupler), math.sin(crank + coupler)]),
        T_model,
        atol=1e-12,
    )
    near = T_model

    def energy(angle):
        P, R, T = four_bar_tip(p, angle, near)
        heights = [P[1] / 2, (P[1] + T[1]) / 2, (R[1] + T[1]) / 2]
        return p["m"] * p["g"] * sum(heights)

    assert energy(crank) == pytest.approx(tip[four_bar.outputs.index("pe")], rel=1e-12)
    h = 1e-5
    slope = (energy(crank + h) - energy(crank - h)) / (2 * h)
    curvature = (energy(crank + h) - 2 * energy(crank) + energy(crank - h)) / h**2
    assert abs(slope) < 1e-7 * p["m"] * p["g"] * p["crank_length"]
    assert curvature > 0  # a minimum: the linearization's mode is a real oscillation
    # The linearized frequency, ω² = V''(θ) / I(θ), with the effective inertia I(θ) of the
    # kinetic energy ½ I θ̇² summed over the links (centre velocities and spins along the loop).
    def configuration(angle):
        P, R, T = four_bar_tip(p, angle, near)
        centres = [P / 2, (P + T) / 2, (R + T) / 2]
        spins = [angle, math.atan2(*(T - P)[::-1]), math.atan2(*(T - R)[::-1])]
        return np.concatenate(centres), np.array(spins)

    (c_plus, s_plus), (c_minus, s_minus) = configuration(crank + h), configuration(crank - h)
    lengths = np.array([p["crank_length"], p["coupler_length"], p["rocker_length"]])
    inertia = p["m"] * np.sum(((c_plus - c_minus) / (2 * h)) ** 2) + np.sum(
        p["m"] * lengths**2 / 12 * ((s_plus - s_minus) / (2 * h)) ** 2
    )
    frequency = math.sqrt(curvature / inertia) / (2 * math.pi)
    linear = four_bar.linearize(independent={"crank_angle": "-1.5 rad"})
    assert linear["frequency_hz"][0] == pytest.approx(frequency, rel=1e-4)
    state = four_bar.assemble(independent=["crank_angle"])
    assert state["dof"] == 1 and state["rank"] == 2 and state["independent"] == ["crank_angle"]


def test_simulations_run_in_parallel_threads():
    """Two Python threads may call one model at once (each analysis runs on its own copy of
    the session): each gets the same result as a call alone. (It checks thread safety, not
    that the calls overlap in time.)"""
    four_bar = model("four_bar")
    alone = four_bar.simulate(t_end=0.5)
    results = [None, None]

    def run(k):
        results[k] = four_bar.simulate(t_end=0.5)

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for result in results:
        np.testing.assert_array_equal(result["q"], alone["q"])


# ---------------------------------------------------------------------------- errors


def test_contact_implicit_method_ends_rolling_and_balances_energy():
    """`method="rosenbrock-w"` (implicit in the contact's damping) on the ball thrown sliding:
    it ends rolling at 5/7 of its speed (the angular momentum about the contact line is kept),
    and the energy lost is the contact's `dissipated` output, integrated with the motion."""
    ball = model("contact_ball")
    run = ball.simulate(t_end=0.4, method="rosenbrock-w", rtol=1e-8, atol=1e-12)
    v0 = run["u"][0, 0]
    assert run["u"][-1, 0] == pytest.approx(5 / 7 * v0, rel=1e-6)
    names = ball.outputs
    energy = run["outputs"][:, names.index("ke")] + run["outputs"][:, names.index("pe")]
    lost = energy[0] - energy
    dissipated = run["outputs"][:, names.index("ground.dissipated")]
    assert lost[-1] > 1e-4
    assert np.max(np.abs(lost - dissipated)) < 1e-6 * lost[-1]


def test_errors_say_where_and_what(tmp_path):
    with pytest.raises(mech.MechError, match="nope.mech"):
        mech.load(tmp_path / "nope.mech")
    bad = tmp_path / "bad.mech"
    bad.write_text("model bad;\nparam m = 1 kgg;\n")
    with pytest.raises(mech.MechError, match=r"bad\.mech:2:"):
        mech.load(bad)
    with pytest.raises(mech.MechError, match="unit"):
        model("pendulum", set={"l": "3 kg"})
    with pytest.raises(mech.MechError, match="its parameters: m, l, g, c"):
        model("pendulum", set={"length": 0.03})
    pendulum = model("pendulum")
    with pytest.raises(mech.MechError, match="has 2 values"):
        pendulum.mass_matrix(np.zeros(2))
    with pytest.raises(mech.MechError, match="unknown method `euler`"):
        pendulum.simulate(t_end=1.0, method="euler")
    with pytest.raises(mech.MechError, match="needs `step`"):
        pendulum.simulate(t_end=1.0, method="rk4")
    with pytest.raises(mech.MechError, match="positive"):
        pendulum.simulate(t_end=-1.0)


def test_settings_by_unit_and_by_number_agree():
    by_text = model("pendulum", set={"l": "30 mm", "m": "12 g"})
    by_number = model("pendulum", set={"l": 0.03, "m": 0.012})
    assert by_text.parameters == by_number.parameters
    by_text.set("l=45 mm")
    assert by_text.parameters["l"] == pytest.approx(0.045, rel=1e-15)
    assert "M[0,0]" in by_text.equations()


def test_physically_impossible_values_are_refused():
    """The model's physical rules (E05xx when written in the file) hold for `set`, `set_si`
    and `load(set=...)`; a refused value is not kept, and settings are checked together."""
    pendulum = model("pendulum")
    with pytest.raises(mech.MechError, match="body `bob` has a negative mass"):
        pendulum.set("m=-3 g")
    with pytest.raises(mech.MechError, match="negative mass"):
        pendulum.set_si("m", -0.003)
    assert pendulum.parameters["m"] == pytest.approx(0.01, rel=1e-15)
    pendulum.set_si("m", 0.0)  # a massless bob is legal
    # The rig's pendulum has I_p − m L_cm² about its centre of mass.
    with pytest.raises(mech.MechError, match="negative principal moment"):
        model("flexure_rig", set={"L_cm": "30 mm"})
    rig = model("flexure_rig", set={"L_cm": "30 mm", "I_p": "1e-6 kg*m^2"})
    assert rig.parameters["L_cm"] == pytest.approx(0.03, rel=1e-15)


# ---------------------------------------------------------------- check: mobility by hand


def test_check_counts_the_freedom_kutzbach_and_the_rolling_disc_give():
    # A planar four-bar: Grübler–Kutzbach 3(n − 1) − 2j with n = 4 links, j = 4 pins: 1.
    four_bar = model("four_bar").check()
    assert (four_bar["loops"], four_bar["rows"], four_bar["rank"]) == (1, 2, 2)
    assert four_bar["dof"] == four_bar["speed_dof"] == 1
    assert len(four_bar["bodies"]) == 3 and len(four_bar["singular_values"]) == 2
    # Two sliders in a chain, no loops: one freedom each.
    chain = model("two_mass_chain").check()
    assert (chain["dof"], chain["speed_dof"], chain["loops"]) == (2, 2, 0)
    # A disc rolling without slip: five coordinates free in configuration (position on the
    # plane and three angles), three in motion (the two no-slip rows remove two speeds).
    disc = model("rolling_disc").check()
    assert disc["velocity_constraints"] >= 1
    assert (disc["dof"], disc["speed_dof"]) == (5, 3)
