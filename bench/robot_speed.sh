#!/bin/sh
# The whole robot's speed (docs/benchmarks.md §16, measured with this script): 1 s of the 10 Hz
# trot of docs/import.md by `mech simulate` with DOPRI5 and with the contact-implicit W-method
# (`--method rosenbrock-w`), and the Fig. 9 sweep of issue 16's target, 5 payloads × 4 gait
# frequencies × 2 s each, by `mech experiment` with experiments/hamr_vi_locomotion.toml's
# settings (one file per frequency: `cycles` makes 2 s of each walk). Prints Markdown rows:
# user CPU and wall seconds. From the repository root:
#
#     bench/robot_speed.sh
set -eu
cargo build --release --quiet
mech=target/release/mech
work=$(mktemp -d "${TMPDIR:-/tmp}/robot_speed.XXXXXX")
trap 'rm -rf "$work"' EXIT

timed() {
    /usr/bin/time -f "%U %e" -o "$work/time" "$@" > "$work/log" 2>&1 || {
        cat "$work/log" >&2
        exit 1
    }
    cat "$work/time"
}

sine() {
    echo "$1=sine(amplitude=100 V, frequency=10 Hz, phase=$2 deg)"
}

echo "| command | simulated | CPU (user) s | wall s |"
echo "|---|---|---|---|"
for setting in "dopri5 1e-6 1e-9" "rosenbrock-w 1e-3 1e-6" "rosenbrock-w 1e-4 1e-7"; do
    set -- $setting
    row=$(timed "$mech" simulate models/robots/hamr_vi_robot.mech --t-end 1s \
        --method "$1" --rtol "$2" --atol "$3" --out "$work/trot.csv" \
        --input "$(sine FL_v_swing 0)" --input "$(sine FR_v_swing 0)" \
        --input "$(sine RL_v_swing 0)" --input "$(sine RR_v_swing 0)" \
        --input "$(sine FL_v_lift 270)" --input "$(sine FR_v_lift 270)" \
        --input "$(sine RL_v_lift 90)" --input "$(sine RR_v_lift 90)")
    set -- $setting $row
    echo "| \`mech simulate\`, 10 Hz trot, \`--method $1 --rtol $2 --atol $3\` | 1 s | $4 | $5 |"
done

cpu=0
wall=0
for hz in 2 5 10 20; do
    sed -e '/^compare = /d' \
        -e "s|\"models/|\"$PWD/models/|" \
        -e "s|^frequencies = .*|frequencies = [\"$hz Hz\"]|" \
        -e "s|^cycles = .*|cycles = $((2 * hz - 1))|" \
        experiments/hamr_vi_locomotion.toml > "$work/sweep_${hz}hz.toml"
    set -- $(timed "$mech" experiment "$work/sweep_${hz}hz.toml" --out-dir "$work/out")
    cpu=$(echo "$cpu + $1" | bc)
    wall=$(echo "$wall + $2" | bc)
done
method=$(sed -n 's/^method = "\(.*\)"/\1/p' experiments/hamr_vi_locomotion.toml)
rtol=$(sed -n 's/^rtol = //p' experiments/hamr_vi_locomotion.toml)
echo "| \`mech experiment\`, Fig. 9 sweep: 5 payloads × 2, 5, 10, 20 Hz × 2 s (\`$method\`, rtol $rtol) | 40 s | $cpu | $wall |"
