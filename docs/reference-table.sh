#!/usr/bin/env bash
# Regenerates the table "Every shipped scene" of docs/reference.md: every scene file, seeds 1
# and 2, n 5000 per class (the fixed-c_max Adams scene last).
# Usage: bash docs/reference-table.sh [N]   (from the repository root; needs python3)
set -euo pipefail
n=${1:-5000}
cargo build --release -q -p host-sim
bin=${CARGO_TARGET_DIR:-target}/release/host-sim
row() { # label, scene file, seed
    "$bin" evaluate --scene "$2" --n "$n" --seed "$3" --json 2>/dev/null | python3 -c '
import json, sys
d = json.load(sys.stdin)
r, g, rel, k = d["reference"], d["kernel_vs_reference"], d["reliability"], d["noise"]["measured_vs_hertz"]
p = lambda v: 100 * v
print("| %s | %s | %.2f ± %.2f | %.2f | %.2f ± %.2f | %+.2f ± %.2f | %.1f | %.2f | %.2f / %.2f | %.4f / %.4f | %.4f / %.4f |" % (
    sys.argv[1], sys.argv[2], p(r["accuracy"]), p(r["std_error"]), p(r["noiseless_accuracy"]),
    p(d["forced_choice_accuracy"]), p(d["forced_choice_std_error"]), p(g["difference"]),
    p(g["std_error"]), p(d["coverage"]), p(d["confident_error_rate"]),
    p(rel["calibration_error_max"]), p(rel["calibration_error_mean"]),
    r["mean_sigma_ln_force"], r["mean_sigma_ln_duration"], k["sigma_ln_force"],
    k["sigma_ln_duration"]))
' "$1" "$3"
}
echo "| scene | seed | reference limit (%) | noiseless (%) | kernel forced choice (%) | kernel - reference (pp) | coverage (%) | confident errors (%) | calibration error max / mean (pp) | CRB sigma ln F / ln t_c | kernel sigma ln F / ln t_c |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for s in scenes/*.toml; do
    name=$(basename "$s" .toml)
    [ "$name" = paper_adams_fixed ] && continue
    for seed in 1 2; do row "$name" "$s" "$seed"; done
done
for seed in 1 2; do row 'paper_adams_fixed (ratio tables)' scenes/paper_adams_fixed.toml "$seed"; done
