"""`mech.fit`: parameters fitted to measured data, as `mech fit` does.

The data (`docs/examples/diagnose/hamr_vi_lift_bode.csv`) were made by mech with the loss
factor η = 0.12 instead of the model's 0.08, plus 2 % gain and 1° phase noise
(docs/diagnose.md). Run from the repository root after `pip install ./python pytest`.
"""

from pathlib import Path

import numpy as np
import pytest

import mech

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "docs" / "examples" / "diagnose"


@pytest.fixture
def lift_bode(monkeypatch):
    monkeypatch.chdir(ROOT)  # the experiment's model path is relative to the repository
    return EXAMPLES / "hamr_vi_lift_bode.toml", EXAMPLES / "hamr_vi_lift_bode.csv"


def test_fit_recovers_the_hidden_loss_factor(lift_bode):
    result = mech.fit(*lift_bode, fit=["eta=0.01..0.5"])
    assert result["converged"]
    (eta,) = result["parameters"]
    assert eta["name"] == "eta" and eta["status"] == "free"
    assert abs(eta["value"] - 0.12) < max(3 * eta["standard_error"], 0.01)
    # The residual RMS per series is that of the points, before and after.
    points = result["points"]
    series = np.array(points["series"])
    assert len(series) == len(points["measured"]) == len(points["after"]) == 80
    for rms in result["residual_rms"]:
        chosen = series == rms["series"]
        for when in ("before", "after"):
            difference = points[when][chosen] - points["measured"][chosen]
            assert np.sqrt(np.mean(difference**2)) == pytest.approx(rms[when], rel=1e-9)
        assert rms["after"] < 0.5 * rms["before"]


def test_fit_tables_as_frames(lift_bode):
    pd = pytest.importorskip("pandas", reason="pandas is not installed (pip install pandas)")
    result = mech.fit(*lift_bode, fit=["eta=0.01..0.5"], as_frame=True)
    assert isinstance(result["parameters"], pd.DataFrame)
    assert list(result["parameters"].columns) == ["name", "value", "standard_error", "status"]
    assert result["parameters"].loc[0, "name"] == "eta"
    points = result["points"]
    assert list(points.columns) == ["series", "abscissa", "row", "measured", "before", "after"]
    assert set(points["series"]) == set(result["residual_rms"]["series"])


def test_fit_errors_are_raised(lift_bode):
    with pytest.raises(mech.MechError, match="stiffness_of_nothing"):
        mech.fit(*lift_bode, fit=["stiffness_of_nothing"])
    with pytest.raises(mech.MechError, match="names no parameter"):
        mech.fit(*lift_bode, fit=[])
    with pytest.raises(mech.MechError, match="missing.csv"):
        mech.fit(lift_bode[0], EXAMPLES / "missing.csv", fit=["eta"])
