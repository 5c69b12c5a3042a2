#!/bin/sh
# Fills fuzz/corpus/<target>/ with seeds from the repository: the bundled models and the UI test
# models, the experiment files, the example data and experiment files, and the signal specs
# quoted in the README, the docs and the signal-spec module documentation. The corpus is not
# committed (fuzz/corpus is git-ignored); run this before the first `cargo fuzz run`.
set -eu
cd "$(dirname "$0")/.."
out=fuzz/corpus
mkdir -p "$out/front_end" "$out/data_csv" "$out/experiment_toml" "$out/signal_spec"

# Seeds are named after their path, so models of the same name in two folders both stay.
seed() { # target file
    cp "$2" "$out/$1/$(printf '%s' "$2" | tr '/' '_')"
}

for f in models/*.mech codegen/tests/ui/*.mech; do
    [ -e "$f" ] && seed front_end "$f"
done
for f in experiments/*.toml experiments/studies/*.toml; do
    [ -e "$f" ] && seed experiment_toml "$f"
done
find docs/examples examples -name '*.toml' ! -name Cargo.toml | while read -r f; do
    seed experiment_toml "$f"
done
find docs/examples examples -name '*.csv' | while read -r f; do
    seed data_csv "$f"
done

# Signal specs: function calls in backticks, quotes or table cells, and `--input`/`--set`
# assignments (whose value is also a spec). One spec per file.
n=0
{
    grep -rhoE '\b(sine|sin|chirp|constant|const|csv)\([^()`"]*\)' \
        README.md docs/*.md src/signal_spec.rs experiments/*.toml || true
    grep -rhoE -- "--(input|set) '?[A-Za-z_.]+=[^'\` ]+" README.md docs/*.md |
        sed -E "s/^--(input|set) '?//" || true
} | sort -u | while IFS= read -r spec; do
    n=$((n + 1))
    printf '%s' "$spec" > "$out/signal_spec/spec_$n"
done

for t in front_end data_csv experiment_toml signal_spec; do
    echo "$t: $(ls "$out/$t" | wc -l) seeds"
done
