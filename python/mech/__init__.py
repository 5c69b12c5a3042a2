"""mech from Python: load a `.mech` model, then assemble, simulate, solve statics and
linearize it, with NumPy arrays in and out; run an experiment file (:func:`experiment`) or a
diagnosis of measured data (:func:`diagnose`) and get their results as dicts.

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
"""

from __future__ import annotations

from os import PathLike
from typing import Mapping, Union

from ._mech import MechError, Model, diagnose, experiment

__all__ = ["load", "experiment", "diagnose", "Model", "MechError"]

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
