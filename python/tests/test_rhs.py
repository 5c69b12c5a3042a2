"""`Model.rhs(t, q, u)`: one evaluation of u̇, against hand-written equations and against the
motion the integrators produce.

Run from the repository root after `pip install ./python pytest`: `pytest python/tests`.
"""

import math
from pathlib import Path

import numpy as np
import pytest

import mech

MODELS = Path(__file__).resolve().parents[2] / "models"


def test_two_mass_chain_rhs_is_the_hand_written_solve():
    """M = [[m1 + m2, m2], [m2, m2]], F = [push − k1 x1 − c1 u1, push − k2 x21 − c2 u21]; the
    push defaults to its signal at t (here a sine), and given inputs replace it."""
    chain = mech.load(MODELS / "two_mass_chain.mech", inputs={"push": "sine(amplitude=2 N, frequency=1.5 Hz)"})
    p = chain.parameters
    M = np.array([[p["m1"] + p["m2"], p["m2"]], [p["m2"], p["m2"]]])
    q, u = np.array([0.01, -0.02]), np.array([0.3, 0.1])

    def expected(push):
        F = np.array(
            [push - p["k1"] * q[0] - p["c1"] * u[0], push - p["k2"] * q[1] - p["c2"] * u[1]]
        )
        return np.linalg.solve(M, F)

    t = 0.1
    udot = chain.rhs(t, q, u)
    assert udot.shape == (2,) and udot.dtype == np.float64
    np.testing.assert_allclose(udot, expected(2.0 * math.sin(2 * math.pi * 1.5 * t)), rtol=1e-13)
    np.testing.assert_allclose(chain.rhs(t, q, u, np.array([-0.7])), expected(-0.7), rtol=1e-13)
    # A strided view (every other element) reads as its values.
    strided = np.array([q[0], 9.0, q[1], 9.0])[::2]
    np.testing.assert_array_equal(chain.rhs(t, strided, u), udot)


def test_four_bar_rhs_is_the_simulated_acceleration():
    """With loops, u̇ includes the loop reactions: the central difference of the simulated
    speeds (reduced dynamics in the crank angle, rtol 1e-12) matches rhs along the motion."""
    four_bar = mech.load(MODELS / "four_bar.mech")
    dt = 1e-4
    run = four_bar.simulate(t_end=0.02, dt_out=dt, rtol=1e-12, atol=1e-14)
    t, q, u = run["t"], run["q"], run["u"]
    scale = max(np.abs(four_bar.rhs(t[k], q[k], u[k])).max() for k in range(len(t)))
    assert scale > 1.0  # it moves
    for k in range(1, len(t) - 1, 20):
        difference = (u[k + 1] - u[k - 1]) / (2 * dt)
        np.testing.assert_allclose(four_bar.rhs(t[k], q[k], u[k]), difference, atol=1e-5 * scale)


def test_rhs_errors_name_the_argument():
    chain = mech.load(MODELS / "two_mass_chain.mech")
    two = np.zeros(2)
    with pytest.raises(mech.MechError, match=r"`q` has 3 values; `two_mass_chain` has 2 coordinates"):
        chain.rhs(0.0, np.zeros(3), two)
    with pytest.raises(mech.MechError, match=r"`u` has 1 values; `two_mass_chain` has 2 speeds"):
        chain.rhs(0.0, two, np.zeros(1))
    with pytest.raises(mech.MechError, match=r"`inputs` has 2 values; `two_mass_chain` has 1 inputs"):
        chain.rhs(0.0, two, two, two)
    with pytest.raises(mech.MechError, match="singular|finite"):
        chain.rhs(0.0, np.array([math.nan, 0.0]), two)
