#!/usr/bin/env python3
"""Time and peak memory of the `mech` command line on N-link chains (docs/benchmarks.md §12).

    nice -n 10 python3 bench/chain_resources.py [--mech target/release/mech] [--sizes 8,16,32,64,128]

Writes chainN.mech (the text of `mech_bench::chain_source(N)`; N = 4 is checked against
models/chain4.mech byte for byte) into a temporary folder and runs, for each N, `mech check`
and `mech derive --emit equations|tape|rust` under `/usr/bin/time -v`, stdout counted and
discarded, each run capped at --timeout seconds and --memory-gb of address space (so a run
that would exhaust the shared machine fails instead). Prints one Markdown table.
"""
import argparse
import os
import re
import resource
import subprocess
import tempfile


def chain_source(n):
    """The N-link chain of bench/src/source.rs (`chain_text(n, false)`)."""
    s = (f'/// The N-link 3D chain of ../shared/peers/chain_model.py with N = {n}: identical links\n'
         '/// hanging along -z, joint k about the parent\'s x (k odd) or y (k even), full inertia tensors.\n'
         f'model chain{n};\n\n')
    params = ['m', 'l', 'd', 'Ixx', 'Iyy', 'Izz', 'Ixy', 'Iyz', 'Izx']
    units = ['kg', 'm', 'm'] + ['kg*m^2'] * 6
    values = ['1.0', '1.0', '0.5', '0.0845', '0.0855', '0.0125', '0.001', '0.002', '0.003']
    for p, u, v in zip(params, units, values):
        s += f'param {p} = {v} {u};\n'
    s += 'param g = 9.81 m/s^2;\n\ngravity = [0, 0, -g];\n'
    for k in range(1, n + 1):
        s += (f'\nbody link{k} {{\n    mass = m;\n    com = [0, 0, -d];\n'
              '    inertia = [Ixx, Iyy, Izz, Ixy, Iyz, Izx];\n}\n')
    for k in range(1, n + 1):
        parent = 'newtonian' if k == 1 else f'link{k - 1}'
        axis = 'x' if k % 2 == 1 else 'y'
        s += f'\njoint q{k} = pin({parent}, link{k}) {{\n    axis = {axis};\n'
        if k > 1:
            s += '    parent_point = [0, 0, -l];\n'
        s += '    q0 = 0.5 rad;\n}\n'
    s += '\noutput ke = kinetic_energy;\noutput pe = potential_energy;\n'
    return s


def measure(command, timeout, memory):
    """(seconds, peak RSS MB, stdout bytes, status) of one run."""
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    timed = ['/usr/bin/time', '-v'] + command
    try:
        run = subprocess.run(timed, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             timeout=timeout, preexec_fn=limit)
    except subprocess.TimeoutExpired:
        return None, None, None, f'killed after {timeout} s'
    err = run.stderr.decode(errors='replace')
    wall = re.search(r'Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)', err)
    seconds = None
    if wall:
        h, m, s = wall.groups()
        seconds = int(h or 0) * 3600 + int(m) * 60 + float(s)
    rss = re.search(r'Maximum resident set size \(kbytes\): (\d+)', err)
    peak = int(rss.group(1)) / 1024 if rss else None
    status = 'ok'
    if run.returncode != 0:
        # The first line mech printed on stderr (before time's report).
        first = next((line for line in err.splitlines() if line.strip()
                      and not line.startswith('\t') and 'Command' not in line), '')
        status = f'exit {run.returncode}: {first.strip()[:90]}'
    return seconds, peak, len(run.stdout), status


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--mech', default='target/release/mech')
    ap.add_argument('--sizes', default='8,16,32,64,128')
    ap.add_argument('--emit', default='check,equations,tape,rust')
    ap.add_argument('--timeout', type=float, default=300)
    ap.add_argument('--memory-gb', type=float, default=8)
    a = ap.parse_args()
    with open('models/chain4.mech') as f:
        assert f.read() == chain_source(4), 'chain_source(4) differs from models/chain4.mech'
    memory = int(a.memory_gb * 2**30)
    print('| N | command | wall s | peak RSS MB | stdout bytes | result |')
    print('|---|---|---|---|---|---|')
    with tempfile.TemporaryDirectory() as folder:
        for n in (int(x) for x in a.sizes.split(',')):
            path = os.path.join(folder, f'chain{n}.mech')
            with open(path, 'w') as f:
                f.write(chain_source(n))
            for what in a.emit.split(','):
                command = [a.mech, 'check', path] if what == 'check' else \
                    [a.mech, 'derive', path, '--emit', what]
                shown = 'check' if what == 'check' else f'derive --emit {what}'
                seconds, peak, size, status = measure(command, a.timeout, memory)
                cell = lambda x, fmt: '-' if x is None else format(x, fmt)
                print(f'| {n} | `{shown}` | {cell(seconds, ".2f")} | {cell(peak, ",.0f")} | '
                      f'{cell(size, ",")} | {status} |', flush=True)


if __name__ == '__main__':
    main()
