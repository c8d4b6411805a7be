#!/usr/bin/env bash
# Regenerates the clipping_chain rows of docs/chain.md: docs/chain/clipping_chain.toml at n N per
# class (default 5000), seeds 1 and 2, with the chain given right under the scene's tolerance
# (the kernel's default), given right and known exactly (tolerance 0), and drawn within the
# tolerance for every stream (--chain-drawn).
# Usage: bash docs/clipping-chain-table.sh [N]   (from the repository root; needs python3)
set -euo pipefail
# shellcheck source=docs/chain-scenes.sh
source docs/chain-scenes.sh
n=${1:-5000}
cargo build --release -q -p host-sim
bin=${CARGO_TARGET_DIR:-target}/release/host-sim
scene=docs/chain/clipping_chain.toml
exact=$(mktemp -d)
trap 'rm -rf "$exact"' EXIT
with_sensor_lines "$scene" "$EXACT_TOLERANCE" > "$exact/clipping_chain.toml"
row() { # label, scene file, seed, flags...
    local label=$1 file=$2 seed=$3
    shift 3
    "$bin" evaluate --scene "$file" --n "$n" --seed "$seed" "$@" --json | python3 -c '
import json, sys
sys.path.insert(0, "docs")
from targets import worst_bin  # noqa: E402
d = json.load(sys.stdin)
rel = d["reliability"]
worst = worst_bin(d)
p = lambda v: "%.2f" % (100 * v)
print("| %s | %s | %s | %s | %s | %s / %s | %d | %s | %.3f / %.3f (%d) |" % (sys.argv[1],
    p(d["forced_choice_accuracy"]), p(d["forced_choice_accuracy"] - d["reference"]["accuracy"]),
    p(d["coverage"]), "%.3f" % (100 * d["confident_error_rate"]), p(d["rejected_share"]),
    p(d["missed_share"]), d["spurious_reports"], p(rel["calibration_error_max"]),
    worst["stated"], worst["observed"], worst["verdicts"]))
' "$label"
}
echo "| seed, chain | forced choice (%) | kernel - reference (pp) | coverage (%) | confident errors (%) | rejected / missed (%) | spurious reports | calibration error max (pp) | worst bin: stated / observed (verdicts) |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for seed in 1 2; do
    row "$seed, right, tolerance" "$scene" "$seed"
    row "$seed, right, known exactly" "$exact/clipping_chain.toml" "$seed"
    row "$seed, drawn" "$scene" "$seed" --chain-drawn
done
