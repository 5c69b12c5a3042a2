"""pandas DataFrames of the results that are tables (``as_frame=True``).

Consumes: the dicts and arrays the native module returns (a simulation, a frequency
response, a sweep, an experiment's tables, a fit) and the model's names. Produces: DataFrames with
named columns in SI units, what does not fit a column (integrator steps, units) in
``DataFrame.attrs``. pandas is optional: it is imported here, on the first call that asks
for a frame, and its absence raises an ImportError saying how to install it.
"""

from __future__ import annotations

from typing import Any, Sequence


def pandas():
    """The pandas module, or an ImportError that says what asked for it and how to install it."""
    try:
        import pandas
    except ImportError as missing:
        raise ImportError(
            "as_frame=True returns a pandas DataFrame, and pandas is not installed: "
            "pip install pandas"
        ) from missing
    return pandas


def simulation(
    run: dict,
    coordinates: Sequence[str],
    speeds: Sequence[str],
    outputs: Sequence[str],
    inputs: Sequence[str],
):
    """One row per sample, indexed by ``t``: ``q_NAME``, ``u_NAME`` and the outputs (the
    columns of ``mech simulate``'s CSV), then the inputs by name; ``attrs["steps"]``."""
    pd = pandas()
    blocks = [
        (run["q"], [f"q_{name}" for name in coordinates]),
        (run["u"], [f"u_{name}" for name in speeds]),
        (run["outputs"], list(outputs)),
        (run["inputs"], list(inputs)),
    ]
    data = {name: values[:, k] for values, names in blocks for k, name in enumerate(names)}
    frame = pd.DataFrame(data, index=pd.Index(run["t"], name="t"))
    frame.attrs["steps"] = run["steps"]
    return frame


def bode(frequencies_hz, gains):
    """One row per frequency (index ``frequency_hz``): the complex ``gain``, its
    ``magnitude`` and ``phase_deg`` (unwrapped)."""
    import numpy as np

    pd = pandas()
    return pd.DataFrame(
        {
            "gain": gains,
            "magnitude": np.abs(gains),
            "phase_deg": np.degrees(np.unwrap(np.angle(gains))),
        },
        index=pd.Index(np.asarray(frequencies_hz, dtype=float), name="frequency_hz"),
    )


def sweep(result: dict) -> dict:
    """A sweep's result with its tables as frames: ``columns`` indexed by ``sample``,
    ``ranking`` (``output``, ``parameter``, ``rho``) and ``failures`` (``sample``, ``robot``,
    ``message``); ``columns.attrs["units"]`` the SI units."""
    pd = pandas()
    columns = dict(result["columns"])
    sample = columns.pop("sample").astype(int)
    frame = pd.DataFrame(columns, index=pd.Index(sample, name="sample"))
    frame.attrs["units"] = dict(result["units"])
    framed = dict(result)
    framed["columns"] = frame
    framed["ranking"] = pd.DataFrame(result["ranking"], columns=["output", "parameter", "rho"])
    framed["failures"] = pd.DataFrame(result["failures"], columns=["sample", "robot", "message"])
    return framed


def table(header: Sequence[str], rows: Sequence[Sequence[str]]):
    """An experiment's table of text cells, each column numeric where every cell reads as a
    number (``+0.00``, ``24.57``), else text as printed."""
    pd = pandas()
    columns = []
    for k, name in enumerate(header):
        cells = pd.Series([row[k] for row in rows], name=name, dtype=object)
        try:
            cells = pd.to_numeric(cells)
        except (ValueError, TypeError):
            cells = pd.Series(cells.tolist(), name=name)  # pandas' own text dtype
        columns.append(cells)
    return pd.concat(columns, axis=1) if columns else pd.DataFrame()


def experiment(result: dict) -> dict:
    """An experiment's result with a ``frame`` beside each table's ``header`` and ``rows``."""
    framed = dict(result)
    framed["tables"] = [dict(t, frame=table(t["header"], t["rows"])) for t in result["tables"]]
    return framed



def fit(result: dict) -> dict:
    """A fit's result with its tables as frames: ``parameters`` (``name``, ``value``,
    ``standard_error``, ``status``), ``residual_rms`` (``series``, ``before``, ``after``) and
    ``points`` (one row per measured value)."""
    pd = pandas()
    framed = dict(result)
    framed["parameters"] = pd.DataFrame(
        result["parameters"], columns=["name", "value", "standard_error", "status"]
    )
    framed["residual_rms"] = pd.DataFrame(result["residual_rms"], columns=["series", "before", "after"])
    framed["points"] = pd.DataFrame(result["points"])
    return framed
