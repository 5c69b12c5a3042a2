"""mech from Python: load a `.mech` model, then assemble, simulate, solve statics and
linearize it, with NumPy arrays in and out; run an experiment file (:func:`experiment`), a fit
(:func:`fit`) or a diagnosis (:func:`diagnose`) of measured data, a tolerance study
(:func:`sweep`, locally or on a Dask cluster) or the paper's whole report (:func:`report`) and
get their results as dicts.

    >>> import mech
    >>> pendulum = mech.load("models/pendulum.mech", set={"l": "30 mm"})
    >>> run = pendulum.simulate(t_end=1.0)
    >>> run["t"].shape, run["q"].shape
    ((1001,), (1001, 1))

Settings take units as on the command line (``"30 mm"``, checked against the parameter's
dimension) or plain numbers in SI units. Every value returned is in SI units. Errors raise
:class:`MechError` with the message `mech` prints (a model text error names its file, line
and column).

The model is compiled once when loaded; changing a parameter does not recompile it.

Results that are tables come as pandas DataFrames with ``as_frame=True`` (``simulate``,
``bode``, :func:`sweep`, :func:`experiment`, :func:`fit`); pandas is needed only then.
"""

from __future__ import annotations

from os import PathLike
from typing import Mapping, Sequence, Union

import os

from . import _frames, _mech
from ._mech import MechError, Model, diagnose, sweep_ranking, sweep_run, sweep_size

__all__ = ["load", "experiment", "fit", "diagnose", "sweep", "report", "Model", "MechError"]

Value = Union[str, float, int]


def _assignments(values: Mapping[str, Value] | None) -> list[str]:
    return [f"{name}={value}" for name, value in (values or {}).items() if isinstance(value, str)]


def load(
    path: str | PathLike,
    set: Mapping[str, Value] | None = None,
    inputs: Mapping[str, str] | None = None,
) -> Model:
    """Compiles the `.mech` file at `path`.

    `set` gives parameter values by name: a string with a unit (``"40 uN*m/rad"``, checked
    against the parameter's dimension) or a number in SI units. `inputs` gives input signals by
    name, as ``--input`` does: ``{"drive": "sine(amplitude=1 mN, frequency=10 Hz)"}``.
    """
    model = Model(str(path), _assignments(set), [f"{k}={v}" for k, v in (inputs or {}).items()])
    for name, value in (set or {}).items():
        if not isinstance(value, str):
            model.set_si(name, float(value))
    return model


def experiment(path: str | PathLike, out_dir: str | PathLike | None = None, as_frame: bool = False) -> dict:
    """Runs the experiment file at `path` as ``mech experiment`` does: a dict of its ``name``,
    ``title``, ``method``, ``tables`` (each ``title``, ``header``, ``rows`` of text cells as
    printed), ``notes``, key ``values`` (SI units) and the ``files`` written (only with
    `out_dir`, where its CSV files and plots are written, all or none).

    With `as_frame` each table also has a ``frame``: a pandas DataFrame of its rows, columns
    numeric where every cell is a number.
    """
    result = _mech.experiment(path, out_dir)
    return _frames.experiment(result) if as_frame else result


def report(out_dir: str | PathLike = "out/report", experiments: str | PathLike = "experiments") -> dict:
    """Runs every experiment file (``*.toml``) in the folder `experiments` on all cores and
    writes the report as ``mech report`` does: ``report.html`` (self-contained),
    ``report.md`` and each experiment's CSV files and plots under `out_dir`, all or none
    (about 2 min on two cores for the bundled ``experiments/``).

    Returns ``html`` and ``markdown`` (the pages' paths), ``seconds`` and ``experiments``: each
    experiment's result as :func:`experiment` returns it, in the report's order.
    """
    return _mech.report(out_dir, experiments)


def fit(
    experiment: str | PathLike,
    data: str | PathLike,
    fit: Sequence[str],
    model: str | PathLike | None = None,
    as_frame: bool = False,
) -> dict:
    """Fits model parameters to measured data as ``mech fit`` does (Levenberg–Marquardt).

    `experiment` is a diagnosis experiment file (TOML, ``docs/diagnose.md``), `data` its
    measured CSV, `fit` the parameters: ``"NAME"`` (bounds a factor of ten either side of a
    positive value) or ``"NAME=LO..HI UNIT"`` (``"eta=0.01..0.5"``, ``"k_s3=10..100
    uN*m/rad"``). `model` replaces the experiment's model. Returns what ``fit.json`` holds:
    ``parameters`` (``name``, ``value``, ``standard_error``, ``status``), ``converged``,
    ``reason``, ``cost``, ``degrees_of_freedom``, ``residual_rms`` per series (``before``,
    ``after``), ``flags`` and ``screening``; and ``points``: per measured value its
    ``series``, ``abscissa``, data ``row``, ``measured`` value and the model ``before`` and
    ``after`` the fit (NumPy arrays). Writes nothing.

    With `as_frame`, ``parameters``, ``residual_rms`` and ``points`` are pandas DataFrames.
    """
    result = _mech.fit(experiment, data, list(fit), model)
    return _frames.fit(result) if as_frame else result


def sweep(
    study_path: str | PathLike,
    samples: int | None = None,
    seed: int | None = None,
    client=None,
    chunk: int | None = None,
    as_frame: bool = False,
) -> dict:
    """Runs a parameter grid or Monte-Carlo tolerance study (``mech sweep``).

    Returns a dict: ``columns`` (name -> NumPy array: ``sample``, each parameter, each output
    in SI units, ``failed``), ``parameters`` and ``outputs`` (column names), ``units``,
    ``failures`` (``(sample, robot, message)`` of every failed sample) and ``ranking``
    (``(output, parameter, rho)``, Spearman's rank correlation, by output, largest ``|rho|``
    first). `samples` and `seed` replace the study's own.

    With `client` (a ``dask.distributed.Client``) the samples are split into chunks of
    `chunk` indices (default: about four per worker) run on the workers, each through the same
    Rust function; a sample's values depend only on the seed and its index, so the result is
    the local run's. Each worker needs this package installed and the study and its models at
    the same paths (relative model paths are taken from the client's current directory).

    With `as_frame`, ``columns`` is a pandas DataFrame indexed by ``sample`` (units in its
    ``attrs["units"]``), and ``ranking`` and ``failures`` are DataFrames too.
    """
    import numpy as np

    study = os.path.abspath(os.fspath(study_path))
    cwd = os.getcwd()
    if client is None:
        result = sweep_run(study, samples, seed, None, cwd)
    else:
        total = sweep_size(study, samples, seed, cwd)
        workers = max(1, len(client.scheduler_info().get("workers", {})))
        size = chunk or max(1, -(-total // (4 * workers)))
        chunks = [list(range(start, min(start + size, total))) for start in range(0, total, size)]
        futures = client.map(
            sweep_run,
            [study] * len(chunks),
            [samples] * len(chunks),
            [seed] * len(chunks),
            chunks,
            [cwd] * len(chunks),
            pure=False,
        )
        parts = client.gather(futures)
        result = parts[0]
        result["columns"] = {
            name: np.concatenate([part["columns"][name] for part in parts])
            for name in result["columns"]
        }
        result["failures"] = [f for part in parts for f in part["failures"]]
    columns = result["columns"]
    result["ranking"] = sweep_ranking(
        [(name, columns[name]) for name in result["parameters"]],
        [(name, columns[name]) for name in result["outputs"]],
    )
    return _frames.sweep(result) if as_frame else result
