"""Type stubs of the native module `mech._mech` (python/src/lib.rs)."""

from os import PathLike
from typing import Any, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

Independent = Optional[Union[Sequence[str], Mapping[str, Union[str, float, None]]]]
Array = npt.NDArray[np.float64]

class MechError(Exception): ...

class Model:
    def __init__(self, path: Union[str, PathLike], set: Sequence[str] = ..., inputs: Sequence[str] = ...) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def coordinates(self) -> list[str]: ...
    @property
    def speeds(self) -> list[str]: ...
    @property
    def inputs(self) -> list[str]: ...
    @property
    def outputs(self) -> list[str]: ...
    @property
    def constraints(self) -> list[str]: ...
    @property
    def parameters(self) -> dict[str, float]: ...
    def set(self, assignment: str) -> None: ...
    def set_si(self, name: str, value: float) -> None: ...
    def input(self, assignment: str) -> None: ...
    def equations(self) -> str: ...
    def check(self) -> dict[str, Any]: ...
    def assemble(self, independent: Independent = None) -> dict[str, Any]: ...
    def simulate(
        self,
        t_end: float,
        dt_out: Optional[float] = None,
        method: str = "dopri5",
        rtol: float = 1e-9,
        atol: float = 1e-12,
        step: Optional[float] = None,
        independent: Independent = None,
        max_steps: int = 1_000_000,
        as_frame: bool = False,
    ) -> Any:
        """A dict of arrays `t`, `q`, `u`, `outputs`, `inputs` and `steps`; with `as_frame`, a
        pandas DataFrame indexed by `t` (`q_NAME`, `u_NAME`, outputs, inputs)."""
    def statics(self, independent: Independent = None, inputs: Optional[Array] = None) -> dict[str, Any]: ...
    def linearize(self, independent: Independent = None, inputs: Optional[Array] = None) -> dict[str, Any]: ...
    def linearize_steady(
        self, independent: Independent = None, inputs: Optional[Array] = None
    ) -> dict[str, Any]:
        """`δẋ = A δx` about the steady motion through the initial state: `states`, `cyclic`,
        `A`, complex `eigenvalues`, `unsteadiness`, `cyclic_change`, and `coordinates`, `M`,
        `C`, `K` when the second-order form exists."""
    def bode(
        self,
        input: str,
        output: str,
        frequencies_hz: Array,
        damping: str = "hysteretic",
        independent: Independent = None,
        as_frame: bool = False,
    ) -> Any:
        """Complex gains at `frequencies_hz`; with `as_frame`, a pandas DataFrame indexed by
        `frequency_hz` with `gain`, `magnitude` and `phase_deg`."""
    def mass_matrix(self, q: Array, inputs: Optional[Array] = None, t: float = 0.0) -> Array: ...
    def forcing(self, q: Array, u: Array, inputs: Optional[Array] = None, t: float = 0.0) -> Array: ...
    def evaluate_outputs(self, q: Array, u: Array, inputs: Optional[Array] = None, t: float = 0.0) -> Array: ...
    def rhs(self, t: float, q: Array, u: Array, inputs: Optional[Array] = None) -> Array:
        """The accelerations u̇ at `(t, q, u)` (loop reactions included), `inputs` defaulting to
        the input signals at `t`; about 0.3 µs above the Rust evaluation."""

def rhs_seconds(
    model: Model, t: float, q: Array, u: Array, inputs: Optional[Array] = None, calls: int = 1000
) -> float:
    """Seconds per call of `model.rhs`'s Rust part (no Python call), the mean of `calls` calls:
    the reference of `bench/python_overhead.py`."""

def experiment(path: Union[str, PathLike[str]], out_dir: Optional[Union[str, PathLike[str]]] = None) -> dict[str, Any]:
    """Runs an experiment file as `mech experiment` does: `name`, `title`, `method`, `tables`
    (each `title`, `header`, `rows` of text cells), `notes`, `values` (SI units) and the `files`
    written (only with `out_dir`)."""

def diagnose(
    experiment: Union[str, PathLike[str]],
    data: Union[str, PathLike[str]],
    model: Optional[Union[str, PathLike[str]]] = None,
    fit: list[str] = ...,
    holdout: str = "every:3",
    causes: list[str] = ...,
) -> dict[str, Any]:
    """Diagnoses measured data as `mech diagnose` does and returns what `diagnosis.json` holds
    (`verdict`, `summary`, `base`, `ranked`, `combined`, `features`, ...); writes nothing."""

def fit(
    experiment: Union[str, PathLike[str]],
    data: Union[str, PathLike[str]],
    fit: list[str],
    model: Optional[Union[str, PathLike[str]]] = None,
) -> dict[str, Any]:
    """Fits parameters to measured data as `mech fit` does: what `fit.json` holds
    (`parameters`, `converged`, `reason`, `cost`, `degrees_of_freedom`, `residual_rms`,
    `flags`, `screening`) and `points` (`series`, `abscissa`, `row`, `measured`, `before`,
    `after`); writes nothing."""

def report(
    out_dir: Optional[Union[str, PathLike[str]]] = None,
    experiments: Optional[Union[str, PathLike[str]]] = None,
) -> dict[str, Any]:
    """Runs every experiment file in `experiments` and writes the report (`mech report`) into
    `out_dir`: `html`, `markdown`, `seconds` and each experiment's result (`experiments`)."""

def sweep_size(
    study: Union[str, PathLike[str]],
    samples: Optional[int] = None,
    seed: Optional[int] = None,
    cwd: Optional[Union[str, PathLike[str]]] = None,
) -> int:
    """The number of samples of a study (its grid's points, or `samples` draws)."""

def sweep_run(
    study: Union[str, PathLike[str]],
    samples: Optional[int] = None,
    seed: Optional[int] = None,
    indices: Optional[list[int]] = None,
    cwd: Optional[Union[str, PathLike[str]]] = None,
) -> dict[str, Any]:
    """Runs the samples `indices` (default all) of a study: `columns` (name -> array),
    `parameters`, `outputs`, `units`, `failures`; model paths relative to `cwd`."""

def sweep_ranking(
    parameters: list[tuple[str, Any]], outputs: list[tuple[str, Any]]
) -> list[tuple[str, str, float]]:
    """`(output, parameter, rho)` by output, largest |Spearman rho| first."""
