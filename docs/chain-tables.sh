#!/usr/bin/env bash
# Regenerates the tables of docs/chain.md: every chain scene at n 5000 per class, seeds 1 and
# 2, with the chain given right and at each mismatch corner (one parameter off at a time).
# Usage: bash docs/chain-tables.sh [N]   (from the repository root; needs python3)
set -euo pipefail
n=${1:-5000}
cargo build --release -q -p host-sim
bin=target/release/host-sim
row() { # scene, seed, mismatch flags...
    local scene=$1 seed=$2
    shift 2
    "$bin" evaluate --scene "scenes/$scene.toml" --n "$n" --seed "$seed" "$@" --json |
        python3 -c '
import json, sys
d = json.load(sys.stdin)
label, seed = sys.argv[1], sys.argv[2]
pct = lambda k: "%.2f" % (100 * d[k])
print("| %s | %s | %s | %s | %s | %s | %s | %s | %d |" % (label, seed,
    "%.2f" % (100 * d["forced_choice_accuracy"]), "%.2f" % (100 * d["reference"]["accuracy"]), pct("coverage"),
    pct("confident_error_rate"), pct("rejected_share"), pct("missed_share"),
    d["spurious_reports"]))
' "$scene ${*:-(chain right)}" "$seed"
}
echo "| scene, chain given | seed | forced choice (%) | reference limit (%) | coverage (%) | confident errors (%) | rejected (%) | missed (%) | spurious reports |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for scene in tail_beam mems_chain piezo_chain; do
    for m in "" "--chain-frequency-error 0.02" "--chain-frequency-error -0.02" \
        "--chain-damping-error 0.3" "--chain-damping-error -0.3" \
        "--chain-gain-error 0.2" "--chain-gain-error -0.2"; do
        for seed in 1 2; do
            # shellcheck disable=SC2086
            row "$scene" "$seed" $m
        done
    done
done
