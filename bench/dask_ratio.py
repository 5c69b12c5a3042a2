"""Issue 19's Dask target: the 10,000-sample tolerance study of the HAMR-VI leg run locally
(the Rust sweep on all cores) and on a 2-worker dask.distributed LocalCluster (one process and
one thread per worker), in one run; the ratio of their wall times, and that both give the same
columns.

Usage (repository root, the package and dask installed, e.g. the venv `.ci/run` makes):
    target/py-venv/bin/python bench/dask_ratio.py [--samples 10000] [--rounds 3]
"""
import argparse
import statistics
import time

import numpy as np
from dask import distributed

import mech

STUDY = "experiments/studies/hamr_vi_tolerance.toml"


def timed(run):
    start = time.perf_counter()
    result = run()
    return time.perf_counter() - start, result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=10_000)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    local_times, dask_times = [], []
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1) as cluster:
        with distributed.Client(cluster) as client:
            # Warm the workers (import, first model compile) outside the timed rounds.
            mech.sweep(STUDY, samples=20, seed=1, client=client)
            for _ in range(args.rounds):
                t_local, local = timed(lambda: mech.sweep(STUDY, samples=args.samples, seed=1))
                t_dask, remote = timed(
                    lambda: mech.sweep(STUDY, samples=args.samples, seed=1, client=client)
                )
                for name, column in local["columns"].items():
                    np.testing.assert_array_equal(remote["columns"][name], column, err_msg=name)
                local_times.append(t_local)
                dask_times.append(t_dask)
    local_median, dask_median = statistics.median(local_times), statistics.median(dask_times)
    print(f"samples: {args.samples}, rounds: {args.rounds} (alternating), columns identical")
    print(f"local (Rust threads): {', '.join(f'{t:.2f}' for t in local_times)} s, median {local_median:.2f} s")
    print(f"Dask LocalCluster, 2 workers: {', '.join(f'{t:.2f}' for t in dask_times)} s, median {dask_median:.2f} s")
    print(f"Dask / local: {dask_median / local_median:.2f}")


if __name__ == "__main__":
    main()
