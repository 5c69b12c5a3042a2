"""`mech.sweep`: tolerance studies from Python, locally and on a Dask cluster.

Run from the repository root after `pip install ./python pytest "dask[distributed]"`.
"""

import math
from pathlib import Path

import numpy as np
import pytest

import mech

ROOT = Path(__file__).resolve().parents[2]

STUDY = """
model = "models/two_mass_chain.mech"
seed = 21
samples = 40
outputs = ["natural_frequency.1", "natural_frequency.2"]

[[parameter]]
name = "k1"
distribution = "normal"
mean = "300 N/m"
sd = "30 N/m"

[[parameter]]
name = "m2"
relative = true
distribution = "truncated_normal"
mean = 1.0
sd = 0.3
low = 0.5
high = 1.5
"""


@pytest.fixture
def study(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)  # the study's model path is relative to the repository
    path = tmp_path / "chain.toml"
    path.write_text(STUDY)
    return path


def test_sweep_columns_match_the_closed_form(study):
    """Each sample's natural frequencies are the roots of the two-mass chain's
    m1 m2 w^4 - (m1 k2 + m2 (k1 + k2)) w^2 + k1 k2 = 0 at its drawn k1 and m2."""
    result = mech.sweep(study)
    columns = result["columns"]
    assert list(columns["sample"]) == list(range(40))
    assert not columns["failed"].any()
    assert result["units"]["k1"] == "N/m" and result["units"]["m2"] == ""
    k1, m2 = columns["k1"], 0.5 * columns["m2"]
    a, b, c = 2.0 * m2, 2.0 * 120.0 + m2 * (k1 + 120.0), k1 * 120.0
    root = np.sqrt(b * b - 4 * a * c)
    expected = np.sqrt((b - root) / (2 * a)) / (2 * math.pi)
    np.testing.assert_allclose(columns["natural_frequency.1"], expected, rtol=1e-9)
    assert ((columns["m2"] >= 0.5) & (columns["m2"] <= 1.5)).all()


def test_sweep_ranking_is_spearman(study):
    """The ranking's rho is Spearman's: the Pearson correlation of the ranks (NumPy)."""
    result = mech.sweep(study, samples=30, seed=3)
    columns = result["columns"]
    assert len(columns["sample"]) == 30

    def ranks(x):
        return np.argsort(np.argsort(x)).astype(float)

    for output, parameter, rho in result["ranking"]:
        expected = np.corrcoef(ranks(columns[parameter]), ranks(columns[output]))[0, 1]
        assert rho == pytest.approx(expected, abs=1e-12)
    first = [r for r in result["ranking"] if r[0] == "natural_frequency.2"]
    assert abs(first[0][2]) >= abs(first[1][2])


def test_sweep_errors_name_the_key(tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    path = tmp_path / "bad.toml"
    path.write_text(STUDY.replace('mean = "300 N/m"', 'mean = "300 mm"'))
    with pytest.raises(mech.MechError, match=r"line 10: key `parameter\[1\].mean`"):
        mech.sweep(path)
    with pytest.raises(mech.MechError, match="more than 1000000 samples"):
        mech.sweep(_write(tmp_path), samples=10**7)


def _write(tmp_path):
    path = tmp_path / "good.toml"
    path.write_text(STUDY)
    return path


def test_dask_local_cluster_gives_the_local_result(study):
    """Two worker processes, the samples split into chunks: the same columns, bit for bit,
    as the local run for the same seed."""
    distributed = pytest.importorskip(
        "dask.distributed", reason="dask[distributed] is not installed (pip install 'dask[distributed]')"
    )
    local = mech.sweep(study, samples=24, seed=5)
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1) as cluster:
        with distributed.Client(cluster) as client:
            remote = mech.sweep(study, samples=24, seed=5, client=client, chunk=5)
    assert remote["parameters"] == local["parameters"]
    for name, column in local["columns"].items():
        np.testing.assert_array_equal(remote["columns"][name], column, err_msg=name)
    assert remote["ranking"] == local["ranking"]
