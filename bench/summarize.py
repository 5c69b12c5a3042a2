#!/usr/bin/env python3
"""Writes docs/benchmarks.md from the JSON lines of one bench/run.sh run.

Usage (from the repository root; bench/run.sh calls it):
    bench/.venv/bin/python bench/summarize.py --results bench/results --out docs/benchmarks.md

Inputs in --results: mech.jsonl (mech-bench), sympy_chain.jsonl (peers/sympy_chain.py),
pinocchio_cpp.jsonl (peers/native/pinocchio_bench.cpp), pinocchio_py.jsonl
(peers/pinocchio_chain.py), sympy_fourbar.jsonl (peers/sympy_fourbar.py), sympy_fivebar.jsonl
(bench/sympy_fivebar.py), the paired rounds (paired_*.jsonl), load.jsonl and commands.txt
(bench/run.sh). Every number on the
page comes from these files; nothing is typed in by hand. Standard library only.
"""
import argparse
import datetime
import json
import math
import os
import platform
import re
import statistics
import subprocess
from collections import defaultdict

SIZES = [1, 2, 4, 8, 16, 32]


def read_jsonl(path):
    rows = []
    if not os.path.exists(path):
        return rows
    with open(path) as f:
        for line in f:
            line = line.strip()
            if line.startswith('{'):
                try:
                    rows.append(json.loads(line))
                except json.JSONDecodeError:
                    pass
    return rows


def by_n(rows):
    out = defaultdict(list)
    for r in rows:
        if 'N' in r:
            out[r['N']].append(r)
    return out


def med(values):
    values = [v for v in values if isinstance(v, (int, float))]
    return statistics.median(values) if values else None


def fmt(x, digits=3):
    """Number with `digits` significant digits, thousands separators for large values."""
    if x is None:
        return '-'
    if isinstance(x, str):
        return x
    if x == 0:
        return '0'
    if abs(x) >= 10 ** digits:
        return f'{x:,.0f}'
    decimals = max(0, digits - 1 - int(math.floor(math.log10(abs(x)))))
    return f'{x:,.{decimals}f}'


def fmt_int(x):
    return '-' if x is None else f'{int(x):,}'


def ratio(a, b):
    if a is None or b is None or b == 0:
        return None
    return a / b


def sh(cmd):
    try:
        return subprocess.run(cmd, shell=True, capture_output=True, text=True, timeout=30).stdout.strip()
    except Exception:  # noqa: BLE001
        return ''


def machine():
    cpu = ''
    flags = ''
    family = model = ''
    with open('/proc/cpuinfo') as f:
        for line in f:
            key, _, value = line.partition(':')
            key, value = key.strip(), value.strip()
            if key == 'model name' and not cpu:
                cpu = value
            elif key == 'cpu family' and not family:
                family = value
            elif key == 'model' and not model:
                model = value
            elif key == 'flags' and not flags:
                flags = value
    if family:
        cpu = f'{cpu} (family {family}, model {model})'
    if 'hypervisor' in flags.split():
        cpu += ', virtual machine guest'
    mem = ''
    with open('/proc/meminfo') as f:
        for line in f:
            if line.startswith('MemTotal'):
                mem = f"{int(line.split()[1]) / 1024 / 1024:.0f} GiB"
    return dict(
        cpu=cpu,
        avx512='avx512f' in flags.split(),
        nproc=sh('nproc'),
        mem=mem,
        kernel=platform.release(),
        os=sh(". /etc/os-release 2>/dev/null && echo $PRETTY_NAME"),
        rustc=sh('rustc --version'),
        gcc=sh('g++ --version | head -1'),
        python=platform.python_version(),
        commit=sh('git rev-parse --short HEAD'),
        dirty=bool(sh('git status --porcelain --untracked-files=no')),
    )


def recorded_machine(results):
    """The machine and date of the run that wrote `results` (`machine.json`, recorded by
    `bench/run.sh` before it measures), else this machine now: the header then describes the
    run the numbers come from even when summarize.py runs again later (a hand section added)."""
    path = os.path.join(results, 'machine.json')
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    return dict(machine(), date=datetime.date.today().isoformat())


def status_of(row):
    s = row.get('status', 'ok')
    return s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--results', default='bench/results')
    ap.add_argument('--out', default='docs/benchmarks.md')
    ap.add_argument('--record-machine', metavar='FILE',
                    help='write this machine, commit and date as JSON to FILE and stop')
    a = ap.parse_args()
    R = a.results
    if a.record_machine:
        with open(a.record_machine, 'w') as f:
            json.dump(dict(machine(), date=datetime.date.today().isoformat()), f, indent=1)
            f.write('\n')
        return

    mech_rows = read_jsonl(os.path.join(R, 'mech.jsonl'))
    mech = {r['N']: r for r in mech_rows if r.get('record') == 'chain'}
    mech_meta = next((r for r in mech_rows if r.get('record') == 'meta'), {})
    mech_end = next((r for r in mech_rows if r.get('record') == 'end'), {})
    sympy = by_n(read_jsonl(os.path.join(R, 'sympy_chain.jsonl')))
    pin_cpp = by_n(read_jsonl(os.path.join(R, 'pinocchio_cpp.jsonl')))
    pin_py = by_n(read_jsonl(os.path.join(R, 'pinocchio_py.jsonl')))
    loads = read_jsonl(os.path.join(R, 'load.jsonl'))
    paired_pin = [r['crba_nle_chol_us'] * 1e3 for r in read_jsonl(os.path.join(R, 'paired_pinocchio_cpp.jsonl'))
                  if isinstance(r.get('crba_nle_chol_us'), (int, float))]
    paired_mech = [r['generated']['udot_ns']['median'] for r in read_jsonl(os.path.join(R, 'paired_mech.jsonl'))
                   if r.get('record') == 'eval']
    loops = {r['model']: r for r in mech_rows if r.get('record') == 'loop'}
    paired_loops = [r for r in read_jsonl(os.path.join(R, 'paired_mech_loops.jsonl'))
                    if r.get('record') == 'loop']
    sympy_loops = {
        'four_bar': [r for r in read_jsonl(os.path.join(R, 'sympy_fourbar.jsonl')) if 'x0' in r],
        'spherical_five_bar': [r for r in read_jsonl(os.path.join(R, 'sympy_fivebar.jsonl')) if 'x0' in r],
    }
    paired_sympy_fourbar = [r for r in read_jsonl(os.path.join(R, 'paired_sympy_fourbar.jsonl')) if 'x0' in r]
    commands = []
    if os.path.exists(os.path.join(R, 'commands.txt')):
        with open(os.path.join(R, 'commands.txt')) as f:
            commands = [line.rstrip('\n') for line in f if line.strip()]

    # ---- per-N aggregates ----
    def sympy_ok(n):
        return [r for r in sympy.get(n, []) if r.get('status') == 'ok'
                and isinstance(r.get('kanes_equations_s'), (int, float))]

    def sympy_derive(n):
        return med([r['kanes_equations_s'] for r in sympy_ok(n)])

    def sympy_total(n):  # setup (frames, points, bodies) + kanes_equations
        return med([r['setup_s'] + r['kanes_equations_s'] for r in sympy_ok(n)])

    def sympy_ops(n, key):
        return med([r.get(key) for r in sympy_ok(n)])

    def sympy_status(n):
        rows = sympy.get(n, [])
        if not rows:
            return None
        bad = [status_of(r) for r in rows if status_of(r) != 'ok']
        return bad[0] if bad and not sympy_ok(n) else 'ok'

    def pin(n, key, src):
        return med([r.get(key) for r in src.get(n, [])])

    def mech_eval(n):
        r = mech.get(n)
        if not r:
            return None
        return r['generated'] or r['tape']

    def ms(summary):
        return None if summary is None else summary['median'] * 1e3

    m = recorded_machine(R)
    today = m['date']
    L = []
    w = L.append
    w('# Benchmarks: mech vs SymPy and Pinocchio on the N-link 3D chain, and vs SymPy/PyDy + SciPy on two closed loops')
    w('')
    load_rows = read_jsonl(os.path.join(R, 'load.jsonl'))
    floating_only = [r for r in load_rows if r.get('section', '').startswith('floating_')]
    if floating_only:
        # `ONLY_FLOATING=1 bench/run.sh` appended section 17 to an earlier full run; the
        # machine is the one its rows recorded (older rows did not record it).
        last = floating_only[-1]
        where = (f', on `{last["cpu"]}`, {last["nproc"]} cores' if 'cpu' in last
                 else ', machine not recorded')
        origin = (f'from one run of `bench/run.sh` on {today} (commit `{m["commit"]}`'
                  f'{", with uncommitted changes" if m["dirty"] else ""}; sections 1 to 16, and '
                  'the machine table) and `ONLY_FLOATING=1 bench/run.sh` on '
                  f'{last["date"][:10]} (section 17{where})')
    else:
        origin = (f'from one run of `bench/run.sh` on {today} (commit `{m["commit"]}`'
                  f'{", with uncommitted changes" if m["dirty"] else ""})')
    w(f'Generated by `bench/summarize.py` {origin}. '
      'Every number below comes from the JSON lines in `bench/results/`; none is '
      'typed in by hand. The model is the N-link 3D chain of `../shared/peers/chain_model.py` '
      '(revolute joints alternating about the parent\'s x and y, links hanging along -z, '
      'full inertia tensors, gravity); mech compiles it from `.mech` text made by '
      '`mech_bench::chain_source(N)`, which for N = 4 is `models/chain4.mech` byte for byte. '
      'The loop models are the bundled `models/four_bar.mech` and `models/spherical_five_bar.mech` '
      '(sections 6 and 7), against SymPy `KanesMethod` with dependent coordinates and speeds, '
      'integrated by SciPy.')
    w('')
    w('## The command')
    w('')
    w('```bash')
    w('bench/run.sh        # from the repository root; ../shared/peers beside it')
    w('```')
    w('')
    w('It runs, in this order (each command as logged in `bench/results/commands.txt`, '
      'repetitions folded):')
    w('')
    w('```bash')
    folded = {}  # command with N replaced -> (first command, [N, ...])
    for c in commands:
        key = re.sub(r'(chain\.py|_native) (\d+)', r'\1 N', c)
        match = re.search(r'(?:chain\.py|_native) (\d+)', c)
        first, ns = folded.setdefault(key, (c, []))
        if match:
            ns.append(int(match.group(1)))
    repeats = defaultdict(int)
    for c in commands:
        repeats[re.sub(r'(chain\.py|_native) (\d+)', r'\1 N', c)] += 1
    for key, (first, ns) in folded.items():
        if len(ns) > 1:
            counts = {n: ns.count(n) for n in dict.fromkeys(ns)}
            w(f'{first}   # N = ' + ', '.join(f'{n}' + (f' (x{k})' if k > 1 else '') for n, k in counts.items()))
        elif repeats[key] > 1:
            w(f'{first}   # x{repeats[key]}')
        else:
            w(first)
    w('```')
    w('')
    w('## Machine')
    w('')
    w('| item | value |')
    w('|---|---|')
    w(f'| CPU | `{m["cpu"]}`{", AVX-512" if m["avx512"] else ""} |')
    w(f'| cores (`nproc`) | {m["nproc"]} |')
    w(f'| memory | {m["mem"]} |')
    w(f'| OS, kernel | {m["os"]}, {m["kernel"]} |')
    w(f'| Rust | `{m["rustc"]}`, `--release` (opt-level 3, no `-C target-cpu`) |')
    w(f'| C++ (Pinocchio native) | `{m["gcc"]}`, `-O3 -march=native` |')
    w(f'| Python (peers) | {m["python"]}, venv `bench/.venv` from `../shared/peers/requirements.txt` |')
    w('')
    w('**Load caveat.** The machine has 2 cores and is shared with other agents that build and '
      'test while the benchmark runs, so timings are noisy (noise only ever adds time). Every '
      'timing is a median: mech evaluation over 21 batches of about 20 ms each, mech '
      'derivation over at least 5 runs, Pinocchio over 7 batches of 200,000 calls, SymPy over '
      'separate processes. Load averages (1, 5, 15 min) when each section started:')
    w('')
    w('| section | UTC | load average |')
    w('|---|---|---|')
    for l in loads:
        w(f'| {l["section"]} | {l["date"]} | {" ".join(l["loadavg"].split()[:3])} |')
    if mech_meta or mech_end:
        w(f'| (mech-bench start / end) | | {" ".join(mech_meta.get("loadavg_start", "").split()[:3])} / '
          f'{" ".join(mech_end.get("loadavg_end", "").split()[:3])} |')
    w('')

    # ---- targets ----
    n8 = 8
    sd8, md8 = sympy_derive(n8), ms(mech[n8]['derive_s']) if n8 in mech else None
    speed8 = ratio(sd8, md8 / 1e3) if sd8 and md8 else None
    d32 = mech[32]['derive_s']['median'] if 32 in mech else None
    d32_max = mech[32]['derive_s']['max'] if 32 in mech else None
    so8 = sympy_ops(n8, 'ops_after_cse')
    mo8 = mech[n8]['ops_mass_forcing_joint'] if n8 in mech else None
    mo8_pl = mech[n8]['per_link_ops_mass_forcing_joint'] if n8 in mech else None
    op_ratio = ratio(mo8, so8)
    op_ratio_pl = ratio(mo8_pl, so8)
    e4 = mech_eval(4)
    u4 = e4['udot_ns']['median'] if e4 else None
    p4 = pin(4, 'crba_nle_chol_us', pin_cpp)
    p4_ns = p4 * 1e3 if p4 is not None else None
    u_ratio = ratio(u4, p4_ns)

    def verdict(ok):
        return '**MET**' if ok else '**MISSED**'

    w('## Targets')
    w('')
    w('| target | measured | verdict |')
    w('|---|---|---|')
    if speed8 is not None:
        w(f'| derivation ≥ 1000× faster than SymPy at N = 8 | SymPy `kanes_equations` {fmt(sd8)} s '
          f'vs mech parse + lower + Kane {fmt(md8)} ms: **{fmt(speed8)}×** | {verdict(speed8 >= 1000)} |')
    else:
        w('| derivation ≥ 1000× faster than SymPy at N = 8 | SymPy or mech missing | **NOT MEASURED** |')
    if d32 is not None:
        w(f'| N = 32 derived in under 1 s | {fmt(d32 * 1e3)} ms median (slowest run {fmt(d32_max * 1e3)} ms) '
          f'| {verdict(d32 < 1.0)} |')
    if op_ratio is not None:
        w(f'| generated op count ≤ ½ of SymPy\'s after cse, N = 8 | mech M and F together '
          f'{fmt_int(mo8)} ops vs SymPy {fmt_int(so8)}: **{fmt(op_ratio)}×** (per-link parameters as in '
          f'SymPy: {fmt_int(mo8_pl)}, {fmt(op_ratio_pl)}×) | {verdict(op_ratio <= 0.5 and op_ratio_pl <= 0.5)} |')
    else:
        w('| generated op count ≤ ½ of SymPy\'s after cse, N = 8 | SymPy or mech missing | **NOT MEASURED** |')
    pp, pm = med(paired_pin), med(paired_mech)
    paired_ratio = ratio(pm, pp)
    if u_ratio is not None:
        paired = ''
        if paired_ratio is not None:
            paired = (f'; paired rounds (alternating, {len(paired_pin)} + {len(paired_mech)}): mech {fmt(pm)} ns vs '
                      f'Pinocchio {fmt(pp)} ns, **{fmt(paired_ratio)}×**')
        ok = u_ratio < 1.0 and (paired_ratio is None or paired_ratio < 1.0)
        w(f'| u̇ at N = 4 faster than Pinocchio CRBA + NLE + Cholesky (same run) | mech {fmt(u4)} ns '
          f'({e4["path"]}) vs Pinocchio C++ {fmt(p4_ns)} ns: **{fmt(u_ratio)}×** the time '
          f'({fmt(1 / u_ratio)}× faster){paired} | {verdict(ok)} |')
    else:
        w('| u̇ at N = 4 faster than Pinocchio CRBA + NLE + Cholesky | Pinocchio C++ missing | **NOT MEASURED** |')
    loop_targets = loop_target_rows(loops, paired_loops, sympy_loops, paired_sympy_fourbar, verdict)
    L.extend(loop_targets['rows'])
    w('')
    w('Ratios are of medians. The paired rounds run Pinocchio\'s C++ benchmark and `mech-bench '
      '--eval-only --sizes 4` alternately after the main run, so that both loops see the same '
      'machine load; the ratio is of the medians over rounds. The four-bar\'s paired rounds do the '
      'same with `peers/sympy_fourbar.py --no-pydy` and `mech-bench --loops-only`.')
    w('')
    w('"mech M and F together" is one tape program over the roots of '
      'both `M` and `F`, so subexpressions shared between them count once; the generated Rust '
      'has separate `mass_matrix` and `forcing` functions, whose counts are in the next table.')
    w('')

    # ---- derivation ----
    w('## 1. Derivation time')
    w('')
    w('mech: `Compiled::from_source` (parse + lower + Kane\'s method, from `.mech` text to the '
      'equations `M(q)`, `F(t, q, u)`), median of ≥ 5 runs in one process; "Kane only" is '
      '`kane::derive` on the lowered model; "emit Rust" is `Compiled::rust` (formatted source); '
      '"tape" builds the interpreter programs. SymPy: `KanesMethod.kanes_equations()` '
      '(`kanes_equations_s` of `peers/sympy_chain.py`; "+ setup" adds building the frames, '
      'points and bodies), median over fresh processes.')
    w('')
    w('| N | mech derive ms (min–max, runs) | Kane only ms | emit Rust ms (lines) | tape ms | '
      'mech per-link params derive ms | SymPy kanes_equations s (runs) | SymPy + setup s | SymPy / mech |')
    w('|---|---|---|---|---|---|---|---|---|')
    for n in sorted(set(SIZES) | set(sympy.keys())):
        r = mech.get(n)
        sd = sympy_derive(n)
        st = sympy_status(n)
        if r:
            d = r['derive_s']
            mech_cells = (f'{fmt(d["median"] * 1e3)} ({fmt(d["min"] * 1e3)}–{fmt(d["max"] * 1e3)}, '
                          f'{d["samples"]}) | {fmt(ms(r["kane_only_s"]))} | {fmt(ms(r["emit_rust_s"]))} '
                          f'({fmt_int(r["emit_rust_lines"])}) | {fmt(ms(r["tape_build_s"]))} | '
                          f'{fmt(ms(r["per_link_derive_s"]))}')
        else:
            mech_cells = '- | - | - | - | -'
        if sd is not None:
            sympy_cells = f'{fmt(sd)} ({len(sympy_ok(n))}) | {fmt(sympy_total(n))} | ' + \
                (f'{fmt(ratio(sd, r["derive_s"]["median"]))}×' if r else '-')
        elif st:
            sympy_cells = f'did not finish: `{st}` | - | -'
        else:
            sympy_cells = 'not run | - | -'
        w(f'| {n} | {mech_cells} | {sympy_cells} |')
    w('')
    notes = []
    for n in sorted(sympy.keys()):
        if sympy_status(n) not in (None, 'ok'):
            notes.append(n)
    if notes:
        w(f'SymPy did not finish N = {", ".join(map(str, notes))} within its cap (`--timeout`, '
          'seconds per stage); larger N were not attempted, since its time grows about 2.2× per '
          'link (`../shared/peers/RESULTS.md`).')
        w('')

    # ---- op counts ----
    w('## 2. Generated operation count')
    w('')
    w('mech: arithmetic instructions of the tape programs (`Program::operation_count`: '
      'add, sub, mul, div, neg, powi, sqrt, sin/cos calls; loads and constants are free), '
      'which is the arithmetic of the generated Rust (both back ends share one lowering). '
      '"M+F" is one program over both root sets. "per-link" is the same chain with its own '
      'nine parameters per link, as the SymPy peer keeps them (shared parameters let '
      'identical terms of different links merge). SymPy: `count_ops` of the `cse` output over '
      '`list(M) + list(f)` (`ops_after_cse`), and before cse (`ops_before_cse`).')
    w('')
    w('| N | mech M | mech F | mech outputs | mech M+F | mech M+F per-link | SymPy before cse | '
      'SymPy after cse | mech / SymPy (per-link) |')
    w('|---|---|---|---|---|---|---|---|---|')
    for n in SIZES:
        r = mech.get(n)
        if not r:
            continue
        sa = sympy_ops(n, 'ops_after_cse')
        sb = sympy_ops(n, 'ops_before_cse')
        rr = ratio(r['ops_mass_forcing_joint'], sa)
        rp = ratio(r['per_link_ops_mass_forcing_joint'], sa)
        cell = f'{fmt(rr)}× ({fmt(rp)}×)' if rr is not None else '-'
        w(f'| {n} | {fmt_int(r["ops_mass_matrix"])} | {fmt_int(r["ops_forcing"])} | '
          f'{fmt_int(r["ops_outputs"])} | {fmt_int(r["ops_mass_forcing_joint"])} | '
          f'{fmt_int(r["per_link_ops_mass_forcing_joint"])} | {fmt_int(sb)} | {fmt_int(sa)} | {cell} |')
    w('')
    growth = []
    for a_, b_ in [(8, 16), (16, 32)]:
        if a_ in mech and b_ in mech:
            g = math.log(mech[b_]['ops_mass_forcing_joint'] / mech[a_]['ops_mass_forcing_joint']) / math.log(2)
            gm = math.log(mech[b_]['ops_mass_matrix'] / mech[a_]['ops_mass_matrix']) / math.log(2)
            gf = math.log(mech[b_]['ops_forcing'] / mech[a_]['ops_forcing']) / math.log(2)
            growth.append(f'N = {a_} → {b_}: M+F ∝ N^{gm if False else g:.2f} (M ∝ N^{gm:.2f}, F ∝ N^{gf:.2f})')
    if growth:
        w('Growth of the mech counts: ' + '; '.join(growth) + '.')
        w('')

    # ---- evaluation ----
    w('## 3. Evaluation time')
    w('')
    w('At q = 0.5 rad, u = the non-zero v of the Pinocchio C++ peer '
      '(u_i = 0.3((i mod 3) − 1) + 0.1 i), time 0. mech: the Rust generated by `build.rs` '
      '(`Chain{N}::mass_matrix`, `::forcing`, fixed-size nalgebra types), called in a tight loop '
      'with `std::hint::black_box` on inputs and results; "u̇" is M, F, then an in-place '
      'allocation-free Cholesky solve (`mech_bench::cholesky_solve_fixed`), and "M then F" and '
      '"solve alone" are its two parts timed on their own; "u̇ nalgebra" uses '
      '`SMatrix::cholesky().solve()` instead; "tape u̇" is the same through the interpreter. '
      'Pinocchio C++: `peers/native/pinocchio_bench.cpp` built `-O3 -march=native`; '
      '"CRBA+NLE+Chol" is `crba`, `nonLinearEffects`, `cholesky::decompose` and '
      '`cholesky::solve`. Pinocchio Python: `peers/pinocchio_chain.py` (`crba + nle + numpy '
      'solve`, through the bindings). All times in ns per call, medians.')
    w('')
    w('| N | mech M | mech F | mech M then F | mech solve alone | **mech u̇** | mech u̇ nalgebra | mech tape u̇ | '
      'Pinocchio CRBA | Pinocchio NLE | **Pinocchio CRBA+NLE+Chol** | Pinocchio ABA (v≠0) | '
      'Pinocchio Py crba+nle+solve | mech u̇ / Pinocchio CRBA+NLE+Chol |')
    w('|---|---|---|---|---|---|---|---|---|---|---|---|---|---|')

    def ns_cell(summary):
        return '-' if summary is None else fmt(summary['median'])

    def us_to_ns(x):
        return None if x is None else x * 1e3

    for n in SIZES:
        r = mech.get(n)
        e = mech_eval(n)
        if not r or not e:
            continue
        chol = us_to_ns(pin(n, 'crba_nle_chol_us', pin_cpp))
        rr = ratio(e['udot_ns']['median'], chol)
        path = '' if e['path'] == 'generated' else ' (tape)'
        w(f'| {n} | {ns_cell(e["mass_matrix_ns"])}{path} | {ns_cell(e["forcing_ns"])}{path} | '
          f'{ns_cell(e.get("mass_forcing_ns"))} | {ns_cell(e.get("solve_ns"))} | '
          f'**{ns_cell(e["udot_ns"])}**{path} | {ns_cell(e.get("udot_nalgebra_ns"))} | '
          f'{ns_cell(r["tape"]["udot_ns"])} | {fmt(us_to_ns(pin(n, "crba_us", pin_cpp)))} | '
          f'{fmt(us_to_ns(pin(n, "nle_us", pin_cpp)))} | **{fmt(chol)}** | '
          f'{fmt(us_to_ns(pin(n, "aba_v_us", pin_cpp)))} | '
          f'{fmt(us_to_ns(pin(n, "crba_nle_solve_us", pin_py)))} | {fmt(rr)}{"×" if rr else ""} |')
    w('')

    # ---- agreement ----
    w('## 4. Cross-check: the same dynamics')
    w('')
    w('Largest |u̇ − q̈| at q = 0.5, u = 0 between mech\'s generated code and the peers\' own '
      'accelerations from the same run (Pinocchio `aba`, SymPy `lambdify` + `numpy.linalg.solve`), '
      'and between mech\'s generated code and its tape at the timed state.')
    w('')
    w('| N | vs Pinocchio (Python `qdd0`) | vs SymPy (`udot0`) | generated vs tape |')
    w('|---|---|---|---|')
    for n in SIZES:
        e = mech_eval(n)
        if not e:
            continue
        ours = e['udot_rest']

        def diff(rows, key):
            vals = [r.get(key) for r in rows if isinstance(r.get(key), list)]
            if not vals or len(vals[0]) != len(ours):
                return None
            return max(abs(x - y) for x, y in zip(ours, vals[0]))
        dp = diff(pin_py.get(n, []), 'qdd0')
        ds = diff(sympy_ok(n), 'udot0')
        gt = mech[n].get('generated_vs_tape_maxabs')
        w(f'| {n} | {"-" if dp is None else f"{dp:.1e}"} | {"-" if ds is None else f"{ds:.1e}"} | '
          f'{"-" if gt is None else f"{gt:.1e}"} |')
    w('')

    # ---- analysis (filled from numbers) ----
    w('## 5. Where the targets stand, and why')
    w('')
    analysis = analyse(mech, sympy_ops, sympy_derive, pin, pin_cpp, mech_eval)
    L.extend(analysis)
    w('')
    L.extend(loop_sections(loops, paired_loops, sympy_loops, paired_sympy_fourbar, loop_targets))
    L.extend(hamr_section(R))
    L.extend(statics_section(R))
    L.extend(diagnose_section())
    L.extend(resources_section())
    L.extend(jit_section(R))
    L.extend(hand_section(
        '## 14. `mech sweep`: 10,000 Monte-Carlo samples of the HAMR-VI leg', 'analysis_sweep'))
    # Section 15: the Python call overhead (bench/python_overhead.py).
    L.extend(printed_section(
        R,
        '## 15. Python call overhead (issue 19): `model.rhs(t, q, u)` against Rust',
        'python.md',
        '`python bench/python_overhead.py` (run by `bench/run.sh` after the JIT tables, in '
        '`bench/.venv` with the package installed by `pip install ./python`), its table as printed.',
        'analysis_python',
    ))
    L.extend(hand_section(
        '## 16. The whole robot (issue 16): one second of trotting, and the Fig. 9 grid',
        'analysis_robot'))
    L.extend(hand_section('### The same robot in MuJoCo', 'analysis_robot_mujoco'))
    L.extend(floating_section(R))
    with open(a.out, 'w') as f:
        f.write('\n'.join(L).rstrip('\n') + '\n')
    print(f'wrote {a.out}')


def analysis_path(name):
    """The hand-written interpretation bench/NAME.md, kept next to this script."""
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), f'{name}.md')


def analysis_text(path):
    """The text of `path` without its HTML comments (notes to whoever edits it)."""
    with open(path) as f:
        return re.sub(r'<!--.*?-->\s*', '', f.read(), flags=re.S)


class Missing(dict):
    """Placeholder values: a placeholder with no measurement reads '-'."""
    def __missing__(self, key):
        return '-'


def analyse(mech, sympy_ops, sympy_derive, pin, pin_cpp, mech_eval):
    """Prose derived from the measured numbers (see ANALYSIS.md-style notes in run output)."""
    L = []
    w = L.append
    path = analysis_path('analysis')
    # Hand-written interpretation kept in bench/analysis.md, with {placeholders} filled from
    # the measurements, so that the explanation stays next to the numbers it explains.
    if os.path.exists(path):
        values = {}
        for n, r in mech.items():
            values[f'ops_mf_{n}'] = fmt_int(r['ops_mass_forcing_joint'])
            values[f'ops_mf_pl_{n}'] = fmt_int(r['per_link_ops_mass_forcing_joint'])
            values[f'ops_m_{n}'] = fmt_int(r['ops_mass_matrix'])
            values[f'ops_f_{n}'] = fmt_int(r['ops_forcing'])
            values[f'derive_ms_{n}'] = fmt(r['derive_s']['median'] * 1e3)
            values[f'kane_ms_{n}'] = fmt(r['kane_only_s']['median'] * 1e3)
            values[f'emit_ms_{n}'] = fmt(r['emit_rust_s']['median'] * 1e3)
            e = mech_eval(n)
            values[f'udot_ns_{n}'] = fmt(e['udot_ns']['median'])
            values[f'm_ns_{n}'] = fmt(e['mass_matrix_ns']['median'])
            values[f'f_ns_{n}'] = fmt(e['forcing_ns']['median'])
            for key in ('mass_forcing_ns', 'solve_ns'):
                if e.get(key):
                    values[f'{key}_{n}'] = fmt(e[key]['median'])
            chol = pin(n, 'crba_nle_chol_us', pin_cpp)
            values[f'pin_chol_ns_{n}'] = fmt(chol * 1e3) if chol else '-'
            sa = sympy_ops(n, 'ops_after_cse')
            values[f'sympy_ops_{n}'] = fmt_int(sa)
            values[f'ops_ratio_{n}'] = fmt(ratio(r['ops_mass_forcing_joint'], sa))
            values[f'ops_ratio_pl_{n}'] = fmt(ratio(r['per_link_ops_mass_forcing_joint'], sa))
            sd = sympy_derive(n)
            values[f'sympy_s_{n}'] = fmt(sd)
            values[f'speedup_{n}'] = fmt(ratio(sd, r['derive_s']['median']))
            # The idle-machine SymPy time quoted in ../shared/peers/RESULTS.md (13.4 s at N = 8),
            # for a load-independent second ratio.
            if n == 8:
                values['speedup_ref_8'] = fmt(ratio(13.4, r['derive_s']['median']))
            values[f'udot_ratio_{n}'] = fmt(ratio(e['udot_ns']['median'], chol * 1e3 if chol else None))
        L.append(analysis_text(path).format_map(Missing(values)).rstrip('\n'))
    return L


# ---- loop models ----

LOOP_NAMES = {'four_bar': 'four-bar', 'spherical_five_bar': 'spherical five-bar'}


def sympy_coords(model, q, u):
    """mech's (q, u) in the SymPy peer's coordinates (the four-bar peer uses absolute angles)."""
    if model == 'four_bar':
        return [q[0], q[0] + q[1], q[2]], [u[0], u[0] + u[1], u[2]]
    return list(q), list(u)


def loop_numbers(loops, paired_loops, sympy_loops, paired_sympy_fourbar):
    """Medians used by the targets and the prose, per model."""
    out = {}
    for model, r in loops.items():
        sy = sympy_loops.get(model, [])
        n = dict(
            udot=r['udot_ns']['median'],
            sim=r['sim1s']['wall_s']['median'],
            sympy_dop=med([x['sim1s_DOP853']['wall_s_median'] for x in sy if 'sim1s_DOP853' in x]),
            sympy_rk=med([x['sim1s_RK45']['wall_s_median'] for x in sy if 'sim1s_RK45' in x]),
            sympy_rhs=med([x.get('rhs_eval_us_median') for x in sy]),
            sympy_nfev_dop=med([x['sim1s_DOP853']['nfev'] for x in sy if 'sim1s_DOP853' in x]),
            sympy_nfev_rk=med([x['sim1s_RK45']['nfev'] for x in sy if 'sim1s_RK45' in x]),
        )
        pm = [x for x in paired_loops if x['model'] == model]
        n['paired_udot'] = med([x['udot_ns']['median'] for x in pm])
        n['paired_sim'] = med([x['sim1s']['wall_s']['median'] for x in pm])
        n['paired_rounds_mech'] = len(pm)
        if model == 'four_bar':
            n['paired_sympy_dop'] = med([x['sim1s_DOP853']['wall_s_median'] for x in paired_sympy_fourbar])
            n['paired_sympy_rhs'] = med([x.get('rhs_eval_us_median') for x in paired_sympy_fourbar])
            n['paired_rounds_sympy'] = len(paired_sympy_fourbar)
        out[model] = n
    return out


def loop_target_rows(loops, paired_loops, sympy_loops, paired_sympy_fourbar, verdict):
    nums = loop_numbers(loops, paired_loops, sympy_loops, paired_sympy_fourbar)
    rows = []
    fb = nums.get('four_bar')
    result = dict(rows=rows, nums=nums, udot_met=None, sim_met=None)
    if not fb:
        rows.append('| constrained u̇ under 0.5 µs (four-bar) | mech loop measurements missing | **NOT MEASURED** |')
        rows.append('| 1 s of four-bar motion ≥ 50× faster than SymPy + SciPy, same tolerance | '
                    'mech loop measurements missing | **NOT MEASURED** |')
        return result
    five = nums.get('spherical_five_bar', {})
    ok = fb['udot'] < 500 and (fb['paired_udot'] is None or fb['paired_udot'] < 500)
    result['udot_met'] = ok
    paired = ''
    if fb['paired_udot'] is not None:
        paired = f'; paired rounds ({fb["paired_rounds_mech"]}): {fmt(fb["paired_udot"])} ns'
    rows.append(f'| constrained u̇ under 0.5 µs (four-bar) | `ConstrainedSolver::accelerations` on the generated '
                f'code: **{fmt(fb["udot"])} ns**{paired} (spherical five-bar, 4 coordinates and 5 rows: '
                f'{fmt(five.get("udot"))} ns); SymPy/NumPy right-hand side {fmt(fb["sympy_rhs"])} µs | {verdict(ok)} |')
    r_main = ratio(fb['sympy_dop'], fb['sim'])
    r_paired = ratio(fb.get('paired_sympy_dop'), fb['paired_sim'])
    result['sim_ratio'], result['sim_ratio_paired'] = r_main, r_paired
    if r_main is None:
        rows.append('| 1 s of four-bar motion ≥ 50× faster than SymPy + SciPy, same tolerance | SymPy peer missing '
                    '| **NOT MEASURED** |')
        return result
    ok = r_main >= 50 and (r_paired is None or r_paired >= 50)
    result['sim_met'] = ok
    paired = ''
    if r_paired is not None:
        paired = (f'; paired rounds ({fb["paired_rounds_sympy"]} + {fb["paired_rounds_mech"]}): SymPy '
                  f'{fmt(fb["paired_sympy_dop"] * 1e3)} ms vs mech {fmt(fb["paired_sim"] * 1e6)} µs, '
                  f'**{fmt(r_paired)}×**')
    rows.append(f'| 1 s of four-bar motion ≥ 50× faster than SymPy + SciPy, same tolerance (rtol = atol = 1e-9) '
                f'| SymPy + SciPy DOP853 {fmt(fb["sympy_dop"] * 1e3)} ms vs mech DOP853 with projection '
                f'{fmt(fb["sim"] * 1e6)} µs: **{fmt(r_main)}×**{paired} | {verdict(ok)} |')
    return result


def loop_sections(loops, paired_loops, sympy_loops, paired_sympy_fourbar, targets):
    L = []
    w = L.append
    if not loops:
        return L
    nums = targets['nums']
    w('## 6. Loop models: assembly and one constrained u̇')
    w('')
    w('The bundled `models/four_bar.mech` (the crank-rocker of `../shared/peers/sympy_fourbar.py`: 3 '
      'coordinates, 2 closure rows, 1 degree of freedom) and `models/spherical_five_bar.mech` (4 '
      'coordinates, 5 closure rows of rank 2, 2 degrees of freedom), compiled to Rust by '
      '`bench/build.rs` with the public build API (the same generated code as `mech::models`), called '
      'through the `Model` trait. Assembly: `mech_runtime::assemble` from the model\'s `q0` with the '
      'first coordinate(s) held (crank; `ground_a`, `a_b`), then `assemble_speeds` (held speeds kept, the '
      'others from `J u = 0`). "u̇" is `ConstrainedSolver::accelerations` at the assembled state: `M`, '
      '`F`, `J`, `J̇u`, the Cholesky factor `M = L Lᵀ`, `Z = L⁻¹Jᵀ`, the pivoted Cholesky of `ZᵀZ = '
      'J M⁻¹ Jᵀ` (which drops the five-bar\'s 3 redundant rows) and `u̇ = L⁻ᵀ(L⁻¹F + Zλ)`. "project" is '
      '`ConstrainedSolver::project` from that state with `q` and `u` nudged by 1e-9 (one Newton step '
      'back to `φ = 0` and the velocity projection: what `simulate` does after every step). The model '
      'functions alone are timed too. SymPy: `rhs` of the peer (`lambdify(cse=True)` of `KanesMethod`\'s '
      '`mass_matrix_full`, `forcing_full`, and `numpy.linalg.solve` of that 2n system, which holds the '
      'velocity-constraint rows), median over its processes. Times in ns per call unless marked.')
    w('')
    w('| model | assembly µs (Newton steps) | assemble_speeds µs | M | F | J | J̇u | φ | **constrained u̇** | '
      'project | SymPy rhs µs | SymPy rhs / mech u̇ |')
    w('|---|---|---|---|---|---|---|---|---|---|---|---|')
    for model, r in loops.items():
        n = nums[model]
        w(f'| {LOOP_NAMES.get(model, model)} | {fmt(r["assemble_ns"]["median"] / 1e3)} ({r["assemble_iterations"]}) | '
          f'{fmt(r["assemble_speeds_ns"]["median"] / 1e3)} | {fmt(r["mass_matrix_ns"]["median"])} | '
          f'{fmt(r["forcing_ns"]["median"])} | {fmt(r["jacobian_ns"]["median"])} | {fmt(r["bias_ns"]["median"])} | '
          f'{fmt(r["constraints_ns"]["median"])} | **{fmt(r["udot_ns"]["median"])}** | {fmt(r["project_ns"]["median"])} | '
          f'{fmt(n["sympy_rhs"])} | {fmt(ratio(n["sympy_rhs"], n["udot"] / 1e3))}× |')
    w('')
    w('## 7. Loop models: 1 s of motion at rtol = atol = 1e-9')
    w('')
    w('From the assembled state to t = 1 s, all at the SymPy peers\' tolerance, rtol = atol = 1e-9. '
      'mech: `mech_runtime::simulate` with `Method::Dop853 { rtol: 1e-9, atol: 1e-9, h_max: ∞ }` '
      '(Dormand–Prince 8(5,3), a transcription of Hairer\'s `DOP853`, the method of the peers\' '
      '`solve_ivp`; `Method::Dopri5` for comparison) and the default `constraint_tolerance` 1e-12: '
      'after every accepted step the state is projected back to `max |φ| ≤ 1e-12` and `max |J u| ≤ 1e-12` '
      '(and the derivative re-evaluated there, one extra right-hand side per projected step). The '
      'headline row samples only t = 0 and 1 s, as `solve_ivp` without `t_eval` does; "1 kHz output" '
      'adds the default output grid (dense output, a projection and the outputs at each of 1,001 '
      'samples); "no projection" steps `Dop853` on `ModelOde` directly, as the SymPy peers integrate. '
      'SymPy + SciPy: `solve_ivp(rhs, (0, 1), x0, method=..., rtol=1e-9, atol=1e-9)` on the full '
      'state (no projection; the constraints drift), medians over 5 repetitions per process and over '
      'processes. PyDy: `System.integrate` (`odeint`, rtol = atol = 1e-9, 101 output times). Wall '
      'times are medians; "vs mech" is that row\'s time over the headline mech row\'s.')
    w('')
    w('| model | integrator | wall time | steps (rejected) | rhs evaluations | q1(1 s) | max \\|φ\\| at 1 s | '
      'energy drift | vs mech |')
    w('|---|---|---|---|---|---|---|---|---|')
    for model, r in loops.items():
        name = LOOP_NAMES.get(model, model)
        base = r['sim1s']['wall_s']['median']

        def time_cell(seconds):
            return f'{fmt(seconds * 1e3)} ms' if seconds >= 1e-3 else f'{fmt(seconds * 1e6)} µs'
        for label, key in [('**mech DOP853 + projection**', 'sim1s'), ('mech DOPRI5 + projection', 'sim1s_dopri5'),
                           ('mech DOP853, 1 kHz output', 'sim1s_1khz'),
                           ('mech DOP853, no projection', 'sim1s_unprojected')]:
            if key not in r:
                continue
            m = r[key]
            wall = m['wall_s']['median']
            w(f'| {name} | {label} | {time_cell(wall)} | {m["accepted_steps"]} ({m["rejected_steps"]}) | '
              f'{m["rhs_evaluations"]} | {m["q_final"][0]:.10f} | {m["phi_final"]:.1e} | {m["energy_drift"]:.1e} | '
              f'{fmt(ratio(wall, base))}× |')
        sy = sympy_loops.get(model, [])
        for method in ['DOP853', 'RK45']:
            runs = [x[f'sim1s_{method}'] for x in sy if f'sim1s_{method}' in x]
            if not runs:
                continue
            wall = med([x['wall_s_median'] for x in runs])
            residual = runs[0].get('mech_rows_residual', runs[0].get('constraint_residual'))
            w(f'| {name} | SymPy + SciPy {method} ({len(runs)} processes) | {time_cell(wall)} | - | '
              f'{fmt_int(med([x["nfev"] for x in runs]))} | {runs[0]["q1_final"]:.10f} | {residual:.1e} | '
              f'{runs[0]["energy_drift"]:.1e} | {fmt(ratio(wall, base))}× |')
        for gen in ['lambdify', 'cython']:
            runs = [x[f'pydy_system_{gen}'] for x in sy if f'pydy_system_{gen}' in x]
            if not runs:
                continue
            wall = med([x['integrate_odeint_s_median'] for x in runs])
            w(f'| {name} | PyDy odeint ({gen}; generation {fmt(med([x["generate_s"] for x in runs]))} s) | '
              f'{time_cell(wall)} | - | - | {runs[0]["q1_final"]:.10f} | - | - | {fmt(ratio(wall, base))}× |')
    w('')
    w('q1 is the crank angle (four-bar) and `ground_a` (five-bar), the same coordinate in both programs. '
      'Cross-check of the initial states and of the dynamics (mech\'s coordinates mapped to the '
      'peer\'s: the four-bar peer uses the coupler\'s absolute angle, mech the angle relative to the '
      'crank):')
    w('')
    w('| model | max \\|x0 mech − x0 SymPy\\| | max \\|u̇ mech − u̇ SymPy\\| at x0 | max \\|q(1 s) mech − SymPy DOP853\\| | '
      'mech no projection vs SymPy DOP853 |')
    w('|---|---|---|---|---|')
    for model, r in loops.items():
        sy = sympy_loops.get(model, [])
        if not sy:
            continue
        s0 = sy[0]
        q, u = sympy_coords(model, r['q'], r['u'])
        x0_diff = max(abs(a - b) for a, b in zip(q + u, s0['x0']))
        ud = '-'
        if isinstance(s0.get('udot0'), list):
            mu = sympy_coords(model, r['udot'], r['udot'])[1]
            ud = f'{max(abs(a - b) for a, b in zip(mu, s0["udot0"])):.1e}'
        xf = s0.get('sim1s_DOP853', {}).get('x_final')
        nq = len(r['q'])

        def q_diff(key):
            if not xf:
                return '-'
            qf = sympy_coords(model, r[key]['q_final'], r[key]['u_final'])[0]
            return f'{max(abs(a - b) for a, b in zip(qf, xf[:nq])):.1e}'
        w(f'| {LOOP_NAMES.get(model, model)} | {x0_diff:.1e} | {ud} | {q_diff("sim1s")} | {q_diff("sim1s_unprojected")} |')
    w('')
    w('## 8. Where the loop targets stand, and why')
    w('')
    path = analysis_path('analysis_loops')
    if os.path.exists(path):
        fb = loops.get('four_bar')
        n = nums.get('four_bar', {})
        values = {}
        if fb:
            model_ns = sum(fb[k]['median'] for k in ('mass_matrix_ns', 'forcing_ns', 'jacobian_ns', 'bias_ns'))
            sim = fb['sim1s']
            rhs = sim['rhs_evaluations']
            values.update(
                udot_ns=fmt(fb['udot_ns']['median']), model_ns=fmt(model_ns),
                model_share=fmt(100 * model_ns / fb['udot_ns']['median'], 2),
                solve_ns=fmt(fb['udot_ns']['median'] - model_ns),
                m_ns=fmt(fb['mass_matrix_ns']['median']), f_ns=fmt(fb['forcing_ns']['median']),
                j_ns=fmt(fb['jacobian_ns']['median']), b_ns=fmt(fb['bias_ns']['median']),
                project_ns=fmt(fb['project_ns']['median']),
                sim_us=fmt(sim['wall_s']['median'] * 1e6), steps=sim['accepted_steps'], rhs=rhs,
                per_rhs_ns=fmt(sim['wall_s']['median'] * 1e9 / rhs),
                rhs_udot_us=fmt(rhs * fb['udot_ns']['median'] / 1e3),
                proj_us=fmt(sim['accepted_steps'] * fb['project_ns']['median'] / 1e3),
                unproj_us=fmt(fb['sim1s_unprojected']['wall_s']['median'] * 1e6),
                dopri5_us=fmt(fb.get('sim1s_dopri5', {}).get('wall_s', {}).get('median', 0) * 1e6),
                dopri5_rhs=fb.get('sim1s_dopri5', {}).get('rhs_evaluations', '-'),
                rejected=sim['rejected_steps'],
                unproj_rhs=fb['sim1s_unprojected']['rhs_evaluations'],
                khz_us=fmt(fb['sim1s_1khz']['wall_s']['median'] * 1e6),
                sympy_dop_ms=fmt((n.get('sympy_dop') or 0) * 1e3), sympy_nfev=fmt_int(n.get('sympy_nfev_dop')),
                sympy_rk_ms=fmt((n.get('sympy_rk') or 0) * 1e3), sympy_nfev_rk=fmt_int(n.get('sympy_nfev_rk')),
                sympy_rhs_us=fmt(n.get('sympy_rhs')),
                ratio=fmt(targets.get('sim_ratio')), ratio_paired=fmt(targets.get('sim_ratio_paired')),
                ratio_ref=fmt(ratio(3.85e-3, sim['wall_s']['median'])),
                ratio_unproj=fmt(ratio(n.get('sympy_dop'), fb['sim1s_unprojected']['wall_s']['median'])),
                needed_us=fmt((n.get('sympy_dop') or 0) / 50 * 1e6),
                verdict_sim='met' if targets.get('sim_met') else 'missed',
                verdict_udot='met' if targets.get('udot_met') else 'missed',
            )
            worst = min(x for x in (targets.get('sim_ratio'), targets.get('sim_ratio_paired')) if x is not None) \
                if targets.get('sim_ratio') is not None else None
            if worst is None:
                values['verdict_sim_detail'] = 'The SymPy peer did not run, so the ratio is not measured.'
            elif targets.get('sim_met'):
                values['verdict_sim_detail'] = (f'So the target is met, with the smaller of the two ratios at '
                                                f'{fmt(worst)}× against the 50× asked for.')
            else:
                values['verdict_sim_detail'] = (
                    f'So the target is missed: the smaller of the two ratios is {fmt(worst)}×, a factor '
                    f'{fmt(50 / worst)} short of 50×. The u̇ itself is fast; what remains is the number of '
                    'right-hand sides at 1e-9, the extra evaluation after each projection, and the '
                    'projection itself.')
        five = loops.get('spherical_five_bar')
        if five:
            n5 = nums.get('spherical_five_bar', {})
            values.update(
                five_udot_ns=fmt(five['udot_ns']['median']), five_sim_ms=fmt(five['sim1s']['wall_s']['median'] * 1e3),
                five_steps=five['sim1s']['accepted_steps'], five_rhs=five['sim1s']['rhs_evaluations'],
                five_sympy_dop_ms=fmt((n5.get('sympy_dop') or 0) * 1e3),
                five_sympy_rhs_us=fmt(n5.get('sympy_rhs')),
                five_ratio=fmt(ratio(n5.get('sympy_dop'), five['sim1s']['wall_s']['median'])),
                five_nfev=fmt_int(n5.get('sympy_nfev_dop')))

        L.append(analysis_text(path).format_map(Missing(values)).rstrip('\n'))
        w('')
    return L


def measured_section(R, heading, table, intro, analysis):
    """A section of Markdown tables an example printed (`R/<table>`, each table kept apart by a
    blank line) under `heading` and `intro`, then the hand-written interpretation in
    bench/<analysis>.md."""
    L = ['', heading, '']
    path = os.path.join(R, table)
    if not os.path.exists(path):
        L.append(f'Not measured in this run (`bench/results/{table}` missing).')
        return L
    L.append(intro)
    with open(path) as f:
        lines = [line.rstrip('\n') for line in f]
    previous = ''
    for line in lines:
        # A table starts where the example's previous line was not a row of one.
        if line.startswith('|'):
            if not previous.startswith('|'):
                L.append('')
            L.append(line)
        previous = line
    L.append('')
    path = analysis_path(analysis)
    if os.path.exists(path):
        L.append(analysis_text(path).rstrip('\n'))
    return L


def hamr_section(R):
    """Section 9: the HAMR leg (`examples/hamr_performance.rs`, its Markdown table as printed)
    and the hand-written interpretation in bench/analysis_hamr.md."""
    return measured_section(
        R, '## 9. The HAMR leg (issue 6): derivation, u̇, motion, chirp, Bode', 'hamr.md',
        '`cargo run --release --example hamr_performance` (run by `bench/run.sh` after the loop '
        'rounds), both bundled legs, generated Rust for the dynamics and the tape model only for '
        'the statics that pick the starting state. Medians of repeated runs within ~1.5 s per row.',
        'analysis_hamr')


def statics_section(R):
    """Section 10: static equilibria of the HAMR leg (`examples/statics_timing.rs`, its Markdown
    tables as printed) and the hand-written interpretation in bench/analysis_statics.md."""
    return measured_section(
        R, '## 10. Static equilibria of the HAMR leg', 'statics.md',
        '`cargo run --release --example statics_timing` (run by `bench/run.sh` after the HAMR '
        'leg): one static equilibrium of HAMR-VI from its rest position (`solve_statics`, '
        'tape model, as `mech diagnose` and the experiments use it), with one or both '
        'actuators at ±112.5 V, free, with the foot held along z or x, and held along z with '
        'a 30 % side load along y; then the force/deflection experiment\'s sensor sweep. '
        'Fastest of 5 runs per case.',
        'analysis_statics')


def diagnose_section():
    """Section 11: `mech diagnose` over the whole catalog (measured by hand with the commands
    it shows: bench/analysis_diagnose.md)."""
    L = ['', '## 11. `mech diagnose`: the whole catalog on the HAMR leg', '']
    path = analysis_path('analysis_diagnose')
    if os.path.exists(path):
        L.append(analysis_text(path).rstrip('\n'))
    return L


def resources_section():
    """Section 12: the command line's time and memory on long chains (measured by hand with
    bench/chain_resources.py: bench/analysis_resources.md)."""
    L = ['', '## 12. The command line on long chains: time and peak memory', '']
    path = analysis_path('analysis_resources')
    if os.path.exists(path):
        L.append(analysis_text(path).rstrip('\n'))
    return L


def jit_section(R):
    """Section 13: native code for tapes (`examples/jit_performance.rs`, its tables as printed
    in bench/results/jit.md) and the hand-written interpretation in bench/analysis_jit.md."""
    return printed_section(
        R,
        '## 13. Compiled speed without cargo (issue 19): tapes as native code',
        'jit.md',
        '`cargo run --release --example jit_performance` (run by `bench/run.sh` after the '
        'statics), its tables as printed.',
        'analysis_jit',
    )


def printed_section(R, heading, table_name, command, analysis):
    """A section of tables a benchmark printed as Markdown (bench/results/TABLE_NAME, its
    `###` headings one level down), the sentence saying which `command` printed them, then the
    hand-written interpretation bench/ANALYSIS.md."""
    L = ['', heading, '']
    table = os.path.join(R, table_name)
    if not os.path.exists(table):
        L.append(f'Not measured in this run (`bench/results/{table_name}` missing).')
    else:
        L.append(command)
        L.append('')
        with open(table) as f:
            L.extend(line.rstrip('\n').replace('### ', '#### ') for line in f)
        L.append('')
    path = analysis_path(analysis)
    if os.path.exists(path):
        L.append(analysis_text(path).rstrip('\n'))
    return L


FLOATING_SIZES = [4, 8, 16, 32]


def floating_section(R):
    """Section 17 (issue 15): the floating chain's u̇ against Pinocchio's ABA and MuJoCo's
    mj_forward (medians over the rounds of bench/run.sh step 5h, each round all three
    side by side), the quadruped's derivation, and 10 s of the rolling disc against
    SymPy + SciPy; then the hand-written bench/analysis_floating.md, its {placeholders}
    filled from these numbers."""
    L = ['', '## 17. The floating base (issue 15): Pinocchio, MuJoCo, a quadruped, the rolling disc', '']
    rows = read_jsonl(os.path.join(R, 'floating.jsonl'))
    if not rows:
        L.append('Not measured in this run (`bench/results/floating.jsonl` missing).')
        return L
    pin = by_n(read_jsonl(os.path.join(R, 'free_chain_pinocchio.jsonl')))
    mj = by_n(read_jsonl(os.path.join(R, 'free_chain_mujoco.jsonl')))
    mech = by_n([r for r in rows if r.get('record') == 'free_chain'])
    rounds = len(mech.get(FLOATING_SIZES[0], []))
    loads = [r['loadavg'].split()[0] for r in read_jsonl(os.path.join(R, 'load.jsonl'))
             if r.get('section') == 'floating']
    values = dict(rounds=rounds, load=loads[-1] if loads else '-')
    L.append(f'`bench/run.sh` step 5i, {rounds} round(s), each round: '
             '`free_chain_pinocchio N 5` (Pinocchio C++, `aba`, built from '
             '`bench/native/free_chain_pinocchio.cpp` at -O3 -march=native), '
             '`free_chain_mujoco free_chainN.xml N 5` (MuJoCo C API, `mj_forward`, '
             '`bench/native/free_chain_mujoco.c`), N = 4, 8, 16, 32, then '
             '`target/release/floating` (mech: the generated Rust of `floating_chain_source(N)`, '
             '`M`, `F` and the Cholesky solve). Medians of the rounds\' medians, ns per u̇, in the '
             'CPU time of the timing thread (`CLOCK_THREAD_CPUTIME_ID`, `/proc/thread-self/schedstat`: '
             'the machine is shared, and wall time counts the time other processes hold the core; '
             'wall times beside); the '
             'state is the same for all three (base at the origin, unrotated and at rest, joints at '
             '0.5 rad, joint rates 0.3((i mod 3) − 1) + 0.1 i); "max |Δu̇|" compares the u̇ each '
             'printed there.')
    L.append('')
    L.append('| N | speeds | mech CPU ns | Pinocchio ABA CPU ns | MuJoCo mj_forward CPU ns | '
             'Pinocchio / mech | MuJoCo / mech | wall: mech, Pinocchio, MuJoCo ns | wall ratios | '
             'max \\|Δu̇\\| mech − Pinocchio | mech − MuJoCo |')
    L.append('|---|---|---|---|---|---|---|---|---|---|---|')
    crossover = {}
    for n in FLOATING_SIZES:
        def cpu(rows, key):
            return med([(r.get(key) or {}).get('median') if key == 'udot_cpu_ns' else r.get(key)
                        for r in rows.get(n, [])])
        m_ns, p_ns, j_ns = cpu(mech, 'udot_cpu_ns'), cpu(pin, 'aba_cpu_ns'), cpu(mj, 'forward_cpu_ns')
        m_wall = med([r['udot_ns']['median'] for r in mech.get(n, [])])
        p_wall, j_wall = cpu(pin, 'aba_ns'), cpu(mj, 'forward_ns')

        def gap(peer):
            if not mech.get(n) or not peer.get(n):
                return None
            a, b = mech[n][-1]['udot'], peer[n][-1].get('udot', [])
            return max(abs(x - y) for x, y in zip(a, b)) if len(a) == len(b) else None
        dp, dj = gap(pin), gap(mj)
        rp, rj = ratio(p_ns, m_ns), ratio(j_ns, m_ns)
        for who, r in (('pin', rp), ('mujoco', rj)):
            if r is not None and r < 1 and who not in crossover:
                crossover[who] = n
        values.update({f'mech_{n}': fmt(m_ns), f'pin_{n}': fmt(p_ns), f'mujoco_{n}': fmt(j_ns),
                       f'pin_ratio_{n}': fmt(rp), f'mujoco_ratio_{n}': fmt(rj),
                       f'verdict_{n}': ('**met**' if rp and rj and rp > 1 and rj > 1
                                        else '**missed**')})
        L.append(f'| {n} | {n + 6} | {fmt(m_ns)} | {fmt(p_ns)} | {fmt(j_ns)} | '
                 f'{fmt(rp)}× | {fmt(rj)}× | {fmt(m_wall)}, {fmt(p_wall)}, {fmt(j_wall)} | '
                 f'{fmt(ratio(p_wall, m_wall))}×, {fmt(ratio(j_wall, m_wall))}× | '
                 f'{"-" if dp is None else f"{dp:.1e}"} | {"-" if dj is None else f"{dj:.1e}"} |')
    for who in ('pin', 'mujoco'):
        values[f'{who}_crossover'] = (f'N = {crossover[who]}' if who in crossover
                                      else 'no N up to 32')
    # how each time grows from the second largest N to the largest
    for who, rows_of, key in (('mech', mech, None), ('pin', pin, 'aba_cpu_ns'),
                              ('mujoco', mj, 'forward_cpu_ns')):
        times = [med([(r.get('udot_cpu_ns') or {}).get('median') if key is None else r.get(key)
                      for r in rows_of.get(n, [])]) for n in FLOATING_SIZES[-2:]]
        values[f'{who}_growth'] = fmt(ratio(times[1], times[0]))
    L.append('')
    quad = [r for r in rows if r.get('record') == 'quadruped']
    if quad:
        derive = med([r['derive_s']['median'] for r in quad])
        kane = med([r['kane_only_s']['median'] for r in quad])
        values.update(quad_derive_ms=fmt(derive * 1e3), quad_kane_ms=fmt(kane * 1e3),
                      quad_nq=quad[0]['nq'], quad_nu=quad[0]['nu'])
        L.append(f'`models/quadruped.mech` ({quad[0]["nq"]} coordinates, {quad[0]["nu"]} speeds), '
                 'the same `floating` runs: `Compiled::from_source` (parse, Kane\'s method, '
                 f'simplification: `mech derive` before it prints) **{fmt(derive * 1e3)} ms**, '
                 f'Kane\'s method alone (`mech_codegen::kane::derive`) {fmt(kane * 1e3)} ms '
                 '(medians).')
        L.append('')
    disc = [r for r in rows if r.get('record') == 'rolling_disc']
    peer = [r for r in read_jsonl(os.path.join(R, 'sympy_rolling_disc.jsonl')) if 'DOP853' in r]
    if disc and peer:
        ours = disc[-1]
        mech_s = med([r['wall_s']['median'] for r in disc])
        names = ['x', 'y', 'yaw', 'lean', 'spin']
        L.append('The rolling disc (`models/rolling_disc.mech` from its `q0`, `u0`; the contact\'s '
                 'speeds solved from the no-slip rows), 10 s at rtol = atol = 1e-9: mech '
                 '(`mech_runtime::simulate`, DOP853, generated Rust) and SymPy\'s `KanesMethod` '
                 'disc + SciPy `solve_ivp` (`bench/sympy_rolling_disc.py`, lambdify with cse), '
                 'alternating in the same rounds. Times are medians.')
        L.append('')
        L.append('| | wall time | evaluations | × mech |')
        L.append('|---|---|---|---|')
        L.append(f'| mech DOP853 | {fmt(mech_s * 1e3)} ms | {ours["rhs_evaluations"]} | 1 |')
        for method in ('DOP853', 'RK45'):
            s_s = med([r[method]['wall_s'] for r in peer])
            values[f'sympy_{method}_ratio'] = fmt(ratio(s_s, mech_s))
            L.append(f'| SymPy + SciPy {method} | {fmt(s_s * 1e3)} ms | {peer[-1][method]["nfev"]} | '
                     f'{fmt(ratio(s_s, mech_s))}× |')
        L.append(f'| SymPy derivation + lambdify | {fmt(med([r["derive_s"] for r in peer]) * 1e3)} + '
                 f'{fmt(med([r["lambdify_s"] for r in peer]) * 1e3)} ms | | |')
        L.append('')
        L.append('| at 10 s | ' + ' | '.join(names) + ' | ' + ' | '.join(f"{n}'" for n in names) + ' |')
        L.append('|---' * 11 + '|')
        ref = peer[-1]['DOP853']
        L.append('| mech | ' + ' | '.join(f'{v:.10f}' for v in ours['q_final'] + ours['u_final']) + ' |')
        L.append('| SymPy DOP853 | ' + ' | '.join(f'{v:.10f}' for v in ref['q_final'] + ref['u_final']) + ' |')
        diffs = [abs(a - b) for a, b in zip(ours['q_final'] + ours['u_final'],
                                            ref['q_final'] + ref['u_final'])]
        L.append('| difference | ' + ' | '.join(f'{d:.1e}' for d in diffs) + ' |')
        values.update(disc_mech_ms=fmt(mech_s * 1e3), disc_max_diff=f'{max(diffs):.1e}')
        L.append('')
    path = analysis_path('analysis_floating')
    if os.path.exists(path):
        L.append(analysis_text(path).format_map(Missing(values)).rstrip('\n'))
    return L


def hand_section(heading, analysis):
    """A section measured by hand with the commands it shows (bench/ANALYSIS.md): section 14,
    `mech sweep`'s 10,000-sample tolerance study; section 16, the whole robot."""
    L = ['', heading, '']
    path = analysis_path(analysis)
    if os.path.exists(path):
        L.append(analysis_text(path).rstrip('\n'))
    return L


if __name__ == '__main__':
    main()
