"""Python call overhead of one evaluation: `model.rhs(t, q, u, inputs)` against the same
evaluation in Rust, in one run (docs/benchmarks.md, "Python call overhead").

Consumes: the bundled N = 4 chain (`models/chain4.mech`) and HAMR-VI leg
(`models/hamr_vi.mech`), and the installed package `mech` (`pip install ./python`).
Produces: a Markdown table on stdout, per model: the Rust evaluation (`mech._mech.rhs_seconds`:
the same solver call on the same scratch, in a Rust loop), the Python call (a Python loop of
`model.rhs`), their difference (the overhead: argument conversion, locking, the result array,
the interpreter's loop) and ratio; then where the overhead goes on the chain: the same call
without `inputs`, and pieces of it alone (a loop iteration, a method call that returns a
string, a 4-element NumPy array).

    target/py-venv/bin/python bench/python_overhead.py      # from the repository root

States as in `examples/jit_performance.rs`: the chain at q = 0.5, u_i = 0.3((i mod 3) − 1) +
0.1 i; HAMR-VI at its static equilibrium under 225 V on both drives, u = 0. Rounds alternate
Rust and Python so both see the same machine load; medians over rounds.
"""

from __future__ import annotations

import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

import mech
from mech._mech import rhs_seconds

ROOT = Path(__file__).resolve().parents[1]
ROUNDS = 41


def chain_state(model):
    n = len(model.coordinates)
    q = np.full(n, 0.5)
    u = np.array([0.3 * ((i % 3) - 1) + 0.1 * i for i in range(n)])
    return q, u, np.zeros(len(model.inputs))


def leg_state(model):
    inputs = np.array([225.0 if name in ("v_lift", "v_swing") else 0.0 for name in model.inputs])
    q = model.statics(independent=["qsact", "qlact"], inputs=inputs)["q"]
    return q, np.zeros(len(q)), inputs


def python_seconds(model, t, q, u, inputs, calls):
    rhs = model.rhs
    started = time.perf_counter()
    for _ in range(calls):
        rhs(t, q, u, inputs)
    return (time.perf_counter() - started) / calls


def format_time(seconds):
    return f"{seconds * 1e6:.2f} µs" if seconds >= 1e-6 else f"{seconds * 1e9:.0f} ns"


def measure(name, state):
    model = mech.load(ROOT / "models" / f"{name}.mech")
    q, u, inputs = state(model)
    for _ in range(10):  # past the JIT's three interpreted calls
        model.rhs(0.0, q, u, inputs)
    # Calls per batch: about 20 ms of Python calls.
    calls = max(100, int(0.02 / python_seconds(model, 0.0, q, u, inputs, 1000)))
    rust, python = [], []
    for _ in range(ROUNDS):
        rust.append(rhs_seconds(model, 0.0, q, u, inputs, calls))
        python.append(python_seconds(model, 0.0, q, u, inputs, calls))
    return statistics.median(rust), statistics.median(python)


def main():
    print(
        f"Python {platform.python_version()}, NumPy {np.__version__}, "
        f"load average {os.getloadavg()[0]:.1f}, {ROUNDS} rounds"
    )
    print()
    print("| model | Rust u̇ | Python `model.rhs` | overhead (Python − Rust) | Python / Rust |")
    print("|---|---|---|---|---|")
    worst = 0.0
    for name, state in [("chain4", chain_state), ("hamr_vi", leg_state)]:
        rust, python = measure(name, state)
        worst = max(worst, python - rust)
        print(
            f"| {name} | {format_time(rust)} | {format_time(python)} | "
            f"**{format_time(python - rust)}** | {python / rust:.2f}× |"
        )
    print()
    breakdown()
    # The target: under 5 µs of overhead per evaluation.
    return 0 if worst < 5e-6 else 1


def breakdown():
    """Per-call times of the chain's `rhs` call and of pieces of any Python call, each the
    median of ROUNDS batches of `timeit` (which loops in C: no Python loop included)."""
    import timeit

    model = mech.load(ROOT / "models" / "chain4.mech")
    q, u, inputs = chain_state(model)
    cases = [
        ("`model.rhs(t, q, u, inputs)`", lambda: model.rhs(0.0, q, u, inputs)),
        ("`model.rhs(t, q, u)` (inputs from the signals)", lambda: model.rhs(0.0, q, u)),
        ("`rhs_seconds(model, t, q, u, inputs, 1)` (one Rust call from Python)", lambda: rhs_seconds(model, 0.0, q, u, inputs, 1)),
        ("`model.name` (a method returning a string)", lambda: model.name),
        ("`numpy.empty(4)` (a result array)", lambda: np.empty(4)),
        ("`(lambda: None)()` (the timing's own call)", lambda: None),
    ]
    for _, call in cases:
        call()
    print("| chain4, one call of | time |")
    print("|---|---|")
    for label, call in cases:
        times = [timeit.timeit(call, number=20000) / 20000 for _ in range(ROUNDS)]
        print(f"| {label} | {format_time(statistics.median(times))} |")


if __name__ == "__main__":
    sys.exit(main())
