#!/usr/bin/env bash
# The one command behind docs/benchmarks.md. From the repository root:
#
#     bench/run.sh
#
# Measures mech, SymPy and Pinocchio on the N-link 3D chain, and mech and SymPy/PyDy + SciPy
# on the two loop models (four-bar, spherical five-bar), in one run and writes
# docs/benchmarks.md from the results. Steps:
#   1. a venv for the peers in bench/.venv (pip install -r ../shared/peers/requirements.txt),
#      and the native Pinocchio benchmark built from ../shared/peers/native (optional);
#   2. `cargo build --release -p mech-bench`, before any timing;
#   3. SymPy (`peers/sympy_chain.py`), N = 1, 2, 4, 8 (and one N = 12 attempt);
#   4. Pinocchio, C++ (`peers/native/pinocchio_bench.cpp`) and Python (`peers/pinocchio_chain.py`),
#      N = 1, 2, 4, 8, 16, 32;
#   4b. SymPy/PyDy + SciPy on the loop models: `peers/sympy_fourbar.py` and
#      `bench/sympy_fivebar.py` (KanesMethod with dependent speeds, solve_ivp at 1e-9);
#   5. mech (`cargo run --release -p mech-bench`), N = 1, 2, 4, 8, 16, 32 and the loop models;
#      then paired rounds at N = 4, Pinocchio C++ and mech alternating, for the u̇ target, and
#      paired rounds on the four-bar, SymPy + SciPy and `mech-bench --loops-only` alternating,
#      for the loop targets;
#   5d. the HAMR leg: `cargo run --release --example hamr_performance` (a Markdown table);
#   5e. the HAMR leg's statics: `cargo run --release --example statics_timing` (Markdown tables);
#   5f. tapes as native code: `cargo run --release --example jit_performance` (Markdown tables);
#   5g. the Python call overhead: the package installed into bench/.venv (`pip install
#      ./python`), then `bench/python_overhead.py` (`model.rhs` against the same evaluation in
#      Rust, a Markdown table);
#   5h. the whole HAMR-VI robot in MuJoCo beside mech (`bench/mujoco_robot.py --mech ...`:
#      the same URDF and trot; time per simulated second and forward speed; a Markdown
#      table in bench/results/mujoco_robot.md for bench/analysis_robot_mujoco.md);
#   6. bench/summarize.py: docs/benchmarks.md.
# ../shared/peers is only read: every result goes to bench/results/ (JSON lines), and every
# command run is logged in bench/results/commands.txt.
#
# Environment: PEERS (default ../shared/peers), SYMPY_REPS (default 3), SYMPY_N12 (1: try
# N = 12 once with a 180 s cap, the default; 0: skip), PIN_REPS (default 7), PAIRED_ROUNDS
# (default 5), LOOP_REPS (SymPy loop-model processes, default 3), LOOP_ROUNDS (paired
# four-bar rounds, default 5), SKIP_CHAIN_PEERS=1 (reuse the chain peers' results of an
# earlier run: steps 3 and 4 skipped), SKIP_MUJOCO_ROBOT=1 (step 5h skipped), MUJOCO_ROBOT_HZ
# (its gait frequencies, default "10 5 2"), SKIP_SUMMARY=1.
set -uo pipefail
cd "$(dirname "$0")/.."
PEERS=${PEERS:-../shared/peers}
SYMPY_REPS=${SYMPY_REPS:-3}
SYMPY_N12=${SYMPY_N12:-1}
PIN_REPS=${PIN_REPS:-7}
R=bench/results
VENV=bench/.venv
PY=$VENV/bin/python
SIZES="1 2 4 8 16 32"

mkdir -p $R/bin
SKIP_CHAIN_PEERS=${SKIP_CHAIN_PEERS:-0}
LOOP_REPS=${LOOP_REPS:-3}
if [ "$SKIP_CHAIN_PEERS" != 1 ]; then
  rm -f $R/sympy_chain.jsonl $R/pinocchio_py.jsonl $R/pinocchio_cpp.jsonl
fi
rm -f $R/mech.jsonl $R/load.jsonl $R/commands.txt $R/sympy_fourbar.jsonl $R/sympy_fivebar.jsonl
: > $R/commands.txt
# The machine, commit and date of this run, for the header of docs/benchmarks.md.
python3 bench/summarize.py --record-machine $R/machine.json

# Logs and runs a command; a failure is recorded, not fatal.
run() {
  echo "$*" >> $R/commands.txt
  "$@"
}
load() { # section name
  printf '{"section":"%s","date":"%s","loadavg":"%s"}\n' "$1" "$(date -u +%FT%TZ)" "$(cat /proc/loadavg)" >> $R/load.jsonl
}
failed() { # script N rc
  printf '{"script":"%s","N":%s,"status":"process-failed rc=%s"}\n' "$1" "$2" "$3"
}

echo "== 1. peers: venv and native build" >&2
load setup
if [ ! -x $PY ] || ! $PY -c 'import sympy, pinocchio' 2>/dev/null; then
  run python3 -m venv $VENV
  run $VENV/bin/pip install -q -r $PEERS/requirements.txt
fi
NATIVE=$R/bin/pinocchio_bench_native
if [ ! -x $NATIVE ] || [ $PEERS/native/pinocchio_bench.cpp -nt $NATIVE ]; then
  # The "native" build of peers/native/build.sh (templates instantiated here, -O3 -march=native),
  # written to bench/results/bin instead of peers/native/bin.
  SP=$($PY -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
  CP=$SP/cmeel.prefix
  PDEF="-DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12"
  run g++ -O3 -march=native -DNDEBUG -std=c++17 $PDEF -o $NATIVE $PEERS/native/pinocchio_bench.cpp \
    -I"$CP/include" -I"$CP/include/eigen3" -L"$CP/lib" -lpinocchio_default -Wl,-rpath,"$CP/lib" \
    > $R/native_build.log 2>&1 || echo "native Pinocchio build failed: see $R/native_build.log" >&2
fi

echo "== 2. cargo build --release -p mech-bench" >&2
load build
run cargo build --release -p mech-bench || exit 1

if [ "$SKIP_CHAIN_PEERS" = 1 ]; then
  echo "== 3, 4. chain peers skipped (SKIP_CHAIN_PEERS=1): earlier results kept" >&2
  echo "# steps 3 and 4 skipped (SKIP_CHAIN_PEERS=1): chain peers' results from an earlier run" >> $R/commands.txt
else
echo "== 3. SymPy" >&2
load sympy
for N in 1 2 4 8; do
  for r in $(seq 1 "$SYMPY_REPS"); do
    echo "   sympy N=$N run $r" >&2
    run timeout 1200 $PY $PEERS/sympy_chain.py $N --timeout 200 >> $R/sympy_chain.jsonl \
      || failed sympy_chain $N $? >> $R/sympy_chain.jsonl
  done
done
if [ "$SYMPY_N12" = 1 ]; then
  echo "   sympy N=12 (180 s cap)" >&2
  run timeout 600 $PY $PEERS/sympy_chain.py 12 --timeout 180 >> $R/sympy_chain.jsonl \
    || failed sympy_chain 12 $? >> $R/sympy_chain.jsonl
fi

echo "== 4. Pinocchio" >&2
load pinocchio_cpp
if [ -x $NATIVE ]; then
  for N in $SIZES; do
    echo "   pinocchio C++ N=$N" >&2
    run $NATIVE $N "$PIN_REPS" >> $R/pinocchio_cpp.jsonl || failed pinocchio_bench_cpp $N $? >> $R/pinocchio_cpp.jsonl
  done
fi
load pinocchio_py
for N in $SIZES; do
  echo "   pinocchio Python N=$N" >&2
  run timeout 900 $PY $PEERS/pinocchio_chain.py $N --reps "$PIN_REPS" >> $R/pinocchio_py.jsonl \
    || failed pinocchio_chain $N $? >> $R/pinocchio_py.jsonl
done
fi

echo "== 4b. SymPy/PyDy + SciPy on the loop models" >&2
load sympy_loops
for r in $(seq 1 "$LOOP_REPS"); do
  echo "   sympy four-bar run $r" >&2
  run timeout 600 $PY $PEERS/sympy_fourbar.py --reps 5 >> $R/sympy_fourbar.jsonl \
    || failed sympy_fourbar 0 $? >> $R/sympy_fourbar.jsonl
  echo "   sympy five-bar run $r" >&2
  run timeout 900 $PY bench/sympy_fivebar.py --reps 5 >> $R/sympy_fivebar.jsonl \
    || failed sympy_fivebar 0 $? >> $R/sympy_fivebar.jsonl
done

echo "== 5. mech" >&2
load mech
run cargo run --release -q -p mech-bench -- --out $R/mech.jsonl || exit 1

# The u̇ target compares two tight loops on a shared machine: alternate them at N = 4, a few
# rounds, so that both see the same load; the page reports the medians of these rounds too.
echo "== 5b. paired rounds at N = 4: Pinocchio C++, mech" >&2
load paired
rm -f $R/paired_pinocchio_cpp.jsonl $R/paired_mech.jsonl
if [ -x $NATIVE ]; then
  for r in $(seq 1 "${PAIRED_ROUNDS:-5}"); do
    run $NATIVE 4 "$PIN_REPS" >> $R/paired_pinocchio_cpp.jsonl || failed pinocchio_bench_cpp 4 $? >> $R/paired_pinocchio_cpp.jsonl
    run target/release/mech-bench --eval-only --sizes 4 --out $R/paired_mech_round.jsonl > /dev/null \
      && grep '"record":"eval"' $R/paired_mech_round.jsonl >> $R/paired_mech.jsonl
  done
  rm -f $R/paired_mech_round.jsonl
fi

# The loop targets compare 1 s of four-bar motion (and one u̇) with SymPy + SciPy: alternate
# the SymPy peer (numeric part only, no PyDy) and `mech-bench --loops-only`.
echo "== 5c. paired rounds on the four-bar: SymPy + SciPy, mech" >&2
load paired_loops
rm -f $R/paired_sympy_fourbar.jsonl $R/paired_mech_loops.jsonl
for r in $(seq 1 "${LOOP_ROUNDS:-5}"); do
  run timeout 600 $PY $PEERS/sympy_fourbar.py --reps 5 --no-pydy >> $R/paired_sympy_fourbar.jsonl \
    || failed sympy_fourbar 0 $? >> $R/paired_sympy_fourbar.jsonl
  run target/release/mech-bench --loops-only --out $R/paired_mech_round.jsonl > /dev/null \
    && grep '"record":"loop"' $R/paired_mech_round.jsonl >> $R/paired_mech_loops.jsonl
done
rm -f $R/paired_mech_round.jsonl

# The HAMR leg (issue 6): derivation, u̇, 1 s at 1 Hz, chirp, Bode.
echo "== 5d. HAMR leg" >&2
load hamr
run cargo run --release -q --example hamr_performance > $R/hamr.md || failed hamr_performance 0 $? >> $R/hamr.md

# Static equilibria of the HAMR leg: one or both actuators, free, foot held, side load.
echo "== 5e. HAMR statics" >&2
load statics
run cargo run --release -q --example statics_timing > $R/statics.md || failed statics_timing 0 $? >> $R/statics.md

# Tapes as native code (issue 19): u̇ generated Rust / JIT / interpreter, JIT compile times.
echo "== 5f. JIT" >&2
load jit
run cargo run --release -q --example jit_performance > $R/jit.md || failed jit_performance 0 $? >> $R/jit.md

# The Python call overhead (issue 19): `model.rhs` against the same evaluation in Rust.
echo "== 5g. Python call overhead" >&2
load python
run $PY -m pip install -q ./python
run $PY bench/python_overhead.py > $R/python.md || failed python_overhead 0 $? >> $R/python.md

# The whole robot beside MuJoCo (issue 16): the same URDF, the same trot, in one run.
if [ "${SKIP_MUJOCO_ROBOT:-0}" != 1 ]; then
  echo "== 5h. the whole robot in MuJoCo and mech" >&2
  load mujoco_robot
  rm -f $R/mujoco_robot.jsonl
  if ! $PY -c 'import mujoco, numpy' 2>/dev/null; then
    run $VENV/bin/pip install -q -r $PEERS/requirements.txt
  fi
  run cargo build --release -q --bin mech \
    && run timeout 1800 $PY bench/mujoco_robot.py --mech "${CARGO_TARGET_DIR:-target}/release/mech" \
         --frequencies ${MUJOCO_ROBOT_HZ:-10 5 2} --json $R/mujoco_robot.jsonl --table $R/mujoco_robot.md \
         > /dev/null \
    || failed mujoco_robot 0 $? >> $R/mujoco_robot.jsonl
fi
load end

if [ "${SKIP_SUMMARY:-0}" != 1 ]; then
  echo "== 6. docs/benchmarks.md" >&2
  run $PY bench/summarize.py --results $R --out docs/benchmarks.md
fi
