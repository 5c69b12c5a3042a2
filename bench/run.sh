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
#   5i. the floating base (issue 15): `bench/native/free_chain_pinocchio.cpp` and
#      `free_chain_mujoco.c` built against the wheels (the MJCF from
#      `tests/peers/pinocchio_free_chain.py --xml N`), then FLOAT_ROUNDS rounds of Pinocchio C++
#      and MuJoCo C at N = 4, 8, 16, 32, `target/release/floating` (mech's u̇, the quadruped's
#      derivation, 10 s of the rolling disc) and `bench/sympy_rolling_disc.py` (SymPy + SciPy);
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
# (its gait frequencies, default "10 5 2"), SKIP_SUMMARY=1, FLOAT_ROUNDS (step 5i's rounds,
# default 3), SKIP_FLOATING=1 (step 5i skipped, its earlier results kept), ONLY_FLOATING=1
# (steps 3 to 5h skipped: step 5i and the summary only).
set -uo pipefail
cd "$(dirname "$0")/.."
PEERS=${PEERS:-../shared/peers}
SYMPY_REPS=${SYMPY_REPS:-3}
SYMPY_N12=${SYMPY_N12:-1}
PIN_REPS=${PIN_REPS:-7}
R=bench/results
# the floating chains compiled to Rust up to N = 32 (bench/build.rs compiles 4 and 8 by default)
export MECH_BENCH_FLOATING_MAX=${MECH_BENCH_FLOATING_MAX:-32}
TARGET=${CARGO_TARGET_DIR:-target}
VENV=bench/.venv
PY=$VENV/bin/python
SIZES="1 2 4 8 16 32"

mkdir -p $R/bin
SKIP_CHAIN_PEERS=${SKIP_CHAIN_PEERS:-0}
ONLY_FLOATING=${ONLY_FLOATING:-0}
if [ "$ONLY_FLOATING" = 1 ]; then
  SKIP_CHAIN_PEERS=1
fi
LOOP_REPS=${LOOP_REPS:-3}
if [ "$SKIP_CHAIN_PEERS" != 1 ]; then
  rm -f $R/sympy_chain.jsonl $R/pinocchio_py.jsonl $R/pinocchio_cpp.jsonl
fi
LOAD_PREFIX=
if [ "$ONLY_FLOATING" = 1 ]; then
  # drop what an earlier ONLY_FLOATING run appended, keep the full run's lines
  sed -i '/^# ONLY_FLOATING=1/,$d' $R/commands.txt
  sed -i '/"section":"floating/d' $R/load.jsonl
  LOAD_PREFIX=floating_
  echo "# ONLY_FLOATING=1: steps 3 to 5h skipped, their earlier results kept" >> $R/commands.txt
else
  rm -f $R/mech.jsonl $R/load.jsonl $R/commands.txt $R/sympy_fourbar.jsonl $R/sympy_fivebar.jsonl
  : > $R/commands.txt
  # The machine, commit and date of this run, for the header of docs/benchmarks.md.
  python3 bench/summarize.py --record-machine $R/machine.json
fi

# Logs and runs a command; a failure is recorded, not fatal.
run() {
  echo "$*" >> $R/commands.txt
  "$@"
}
load() { # section name
  printf '{"section":"%s%s","date":"%s","loadavg":"%s","cpu":"%s","nproc":%s}\n' "$LOAD_PREFIX" "$1" "$(date -u +%FT%TZ)" "$(cat /proc/loadavg)" "$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1)" "$(nproc)" >> $R/load.jsonl
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
if [ "$ONLY_FLOATING" != 1 ] && { [ ! -x $NATIVE ] || [ $PEERS/native/pinocchio_bench.cpp -nt $NATIVE ]; }; then
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

# The floating base (issue 15): Pinocchio's ABA and MuJoCo's mj_forward (C and C++ against the
# wheels' libraries) and mech's generated u̇ on the floating chain, side by side in each round;
# the quadruped's derivation; the rolling disc's 10 s in mech and in SymPy + SciPy.
floating_step() {
  echo "== 5i. floating base: Pinocchio, MuJoCo, mech; quadruped; rolling disc" >&2
  LOAD_PREFIX= load floating
  local SP CP PDEF N r
  SP=$($PY -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
  CP=$SP/cmeel.prefix
  PDEF="-DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12"
  if [ ! -x $R/bin/free_chain_pinocchio ] || [ bench/native/free_chain_pinocchio.cpp -nt $R/bin/free_chain_pinocchio ]; then
    run g++ -O3 -march=native -DNDEBUG -std=c++17 $PDEF -o $R/bin/free_chain_pinocchio \
      bench/native/free_chain_pinocchio.cpp -I"$CP/include" -I"$CP/include/eigen3" \
      -L"$CP/lib" -lpinocchio_default -Wl,-rpath,"$CP/lib" > $R/native_build.log 2>&1 \
      || echo "free_chain_pinocchio build failed: see $R/native_build.log" >&2
  fi
  run gcc -O2 -o $R/bin/free_chain_mujoco bench/native/free_chain_mujoco.c \
    -I"$SP/mujoco/include" "$SP/mujoco/libmujoco.so.4.0.0" -Wl,-rpath,"$SP/mujoco" \
    || echo "free_chain_mujoco build failed" >&2
  rm -f $R/free_chain_pinocchio.jsonl $R/free_chain_mujoco.jsonl $R/floating.jsonl \
    $R/sympy_rolling_disc.jsonl
  for N in 4 8 16 32; do
    $PY tests/peers/pinocchio_free_chain.py --xml $N > $R/bin/free_chain$N.xml
  done
  for r in $(seq 1 "${FLOAT_ROUNDS:-3}"); do
    echo "   round $r" >&2
    for N in 4 8 16 32; do
      run $R/bin/free_chain_pinocchio $N 5 >> $R/free_chain_pinocchio.jsonl \
        || failed free_chain_pinocchio $N $? >> $R/free_chain_pinocchio.jsonl
      run $R/bin/free_chain_mujoco $R/bin/free_chain$N.xml $N 5 >> $R/free_chain_mujoco.jsonl \
        || failed free_chain_mujoco $N $? >> $R/free_chain_mujoco.jsonl
    done
    run $TARGET/release/floating --out $R/floating_round.jsonl > /dev/null \
      && cat $R/floating_round.jsonl >> $R/floating.jsonl
    run timeout 600 $PY bench/sympy_rolling_disc.py --reps 3 >> $R/sympy_rolling_disc.jsonl \
      || failed sympy_rolling_disc 0 $? >> $R/sympy_rolling_disc.jsonl
  done
  rm -f $R/floating_round.jsonl
}

if [ "$ONLY_FLOATING" = 1 ]; then
  floating_step
  if [ "${SKIP_SUMMARY:-0}" != 1 ]; then
    run $PY bench/summarize.py --results $R --out docs/benchmarks.md
  fi
  exit 0
fi

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
    run $TARGET/release/mech-bench --eval-only --sizes 4 --out $R/paired_mech_round.jsonl > /dev/null \
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
  run $TARGET/release/mech-bench --loops-only --out $R/paired_mech_round.jsonl > /dev/null \
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
if [ "${SKIP_FLOATING:-0}" != 1 ]; then
  floating_step
fi
load end

if [ "${SKIP_SUMMARY:-0}" != 1 ]; then
  echo "== 6. docs/benchmarks.md" >&2
  run $PY bench/summarize.py --results $R --out docs/benchmarks.md
fi
