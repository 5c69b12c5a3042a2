"""`as_frame=True`: the tables as pandas DataFrames hold the same numbers as the dicts, under
the names `mech simulate`'s CSV and the sweep use; without pandas, a clear ImportError.

Run from the repository root after `pip install ./python pytest pandas`.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

import mech

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"

pd = pytest.importorskip("pandas", reason="pandas is not installed (pip install pandas)")


def chain():
    return mech.load(
        MODELS / "two_mass_chain.mech", inputs={"push": "sine(amplitude=2 N, frequency=1.5 Hz)"}
    )


def test_simulation_frame_is_the_runs_arrays_by_name():
    model = chain()
    run = model.simulate(t_end=2.0, dt_out=0.01)
    frame = model.simulate(t_end=2.0, dt_out=0.01, as_frame=True)
    assert frame.index.name == "t"
    np.testing.assert_array_equal(frame.index.to_numpy(), run["t"])
    assert list(frame.columns) == ["q_x1", "q_x21", "u_x1", "u_x21", *model.outputs, "push"]
    np.testing.assert_array_equal(frame["q_x21"], run["q"][:, 1])
    np.testing.assert_array_equal(frame["u_x1"], run["u"][:, 0])
    np.testing.assert_array_equal(frame["x2.x"], run["outputs"][:, model.outputs.index("x2.x")])
    np.testing.assert_array_equal(frame["push"], run["inputs"][:, 0])
    assert frame.attrs["steps"] == run["steps"]


def test_bode_frame_has_magnitude_and_unwrapped_phase():
    model = chain()
    frequencies = np.geomspace(0.1, 30.0, 40)
    gains = model.bode("push", "x2.x", frequencies)
    frame = model.bode("push", "x2.x", frequencies, as_frame=True)
    np.testing.assert_array_equal(frame.index.to_numpy(), frequencies)
    np.testing.assert_array_equal(frame["gain"], gains)
    np.testing.assert_allclose(frame["magnitude"], np.abs(gains), rtol=1e-15)
    # Stiffness-dominated at 0.1 Hz (phase near 0), mass-dominated at 30 Hz (near −180°: x2
    # has a zero between the two modes), no jump of a full turn between neighbours.
    phase = frame["phase_deg"].to_numpy()
    assert abs(phase[0]) < 1.0 and abs(phase[-1] + 180.0) < 1.0
    assert np.all(np.abs(np.diff(phase)) < 180.0)
    np.testing.assert_allclose(np.cos(np.radians(phase)), np.cos(np.angle(gains)), atol=1e-12)


def test_sweep_frame_is_the_columns_by_sample(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    study = ROOT / "experiments" / "studies" / "hamr_vi_tolerance.toml"
    plain = mech.sweep(study, samples=12, seed=4)
    framed = mech.sweep(study, samples=12, seed=4, as_frame=True)
    frame = framed["columns"]
    assert frame.index.name == "sample" and list(frame.index) == list(range(12))
    assert list(frame.columns) == [*plain["parameters"], *plain["outputs"], "failed"]
    for name in frame.columns:
        np.testing.assert_array_equal(frame[name], plain["columns"][name], err_msg=name)
    assert frame.attrs["units"]["free_stroke.lift"] == "m"
    ranking = framed["ranking"]
    assert list(ranking.columns) == ["output", "parameter", "rho"]
    assert list(ranking.itertuples(index=False, name=None)) == plain["ranking"]
    assert list(framed["failures"].columns) == ["sample", "robot", "message"]
    assert len(framed["failures"]) == len(plain["failures"])


def test_experiment_tables_as_frames_are_numeric_where_the_cells_are():
    result = mech.experiment(ROOT / "experiments" / "hamr_vi_force.toml", as_frame=True)
    first = result["tables"][0]
    frame = first["frame"]
    assert list(frame.columns) == first["header"] and len(frame) == len(first["rows"])
    assert frame["DOF"].iloc[0] == "lift"
    force = frame["F_b foot [mN]"]
    assert force.dtype == np.float64
    assert force.iloc[0] == float(first["rows"][0][2])


def test_without_pandas_as_frame_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # `import pandas` now raises ImportError
    model = chain()
    with pytest.raises(ImportError, match="pip install pandas"):
        model.simulate(t_end=0.1, as_frame=True)
    assert model.simulate(t_end=0.1)["t"].shape == (1001,)  # without a frame, no pandas needed
