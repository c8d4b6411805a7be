#!/usr/bin/env bash
# Regenerates the tables of docs/chain.md: every chain scene at n 5000 per class, seeds 1 and
# 2, with the chain given right and at each mismatch corner (one parameter off at a time);
# then the posteriors' calibration at n 20000 per class (CAL_N), seeds 1 and 2, with the
# chain given right under the scene's tolerance, known exactly (tolerance 0), and drawn
# within the tolerance for every stream (--chain-drawn); then, at n N, every stream's chain
# drawn within the tolerance that `host-sim identify` reaches.
# Usage: bash docs/chain-tables.sh [N]   (from the repository root; needs python3)
set -euo pipefail
# shellcheck source=docs/chain-scenes.sh
source docs/chain-scenes.sh
n=${1:-5000}
cargo build --release -q -p host-sim
bin=${CARGO_TARGET_DIR:-target}/release/host-sim
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

cal_n=${CAL_N:-20000}
exact=$(mktemp -d)
trap 'rm -rf "$exact"' EXIT
cal_row() { # label, scene file, seed, flags...
    local label=$1 file=$2 seed=$3
    shift 3
    "$bin" evaluate --scene "$file" --n "$cal_n" --seed "$seed" --reference-draws 20000 "$@" \
        --json | python3 -c '
import json, sys
sys.path.insert(0, "docs")
from targets import worst_bin  # noqa: E402
d = json.load(sys.stdin)
rel = d["reliability"]
worst = worst_bin(d)
print("| %s | %s | %.2f | %.2f | %.2f / %.2f | %.3f / %.3f (%d) |" % (sys.argv[1], sys.argv[2],
    100 * d["forced_choice_accuracy"], 100 * d["coverage"],
    100 * rel["calibration_error_max"], 100 * rel["calibration_error_mean"],
    worst["stated"], worst["observed"], worst["verdicts"]))
' "$label" "$seed"
}
echo
echo "| scene, chain | seed | forced choice (%) | coverage (%) | calibration error max / mean (pp) | worst bin: stated / observed (verdicts) |"
echo "| --- | --- | --- | --- | --- | --- |"
for scene in tail_beam mems_chain piezo_chain; do
    with_sensor_lines "scenes/$scene.toml" "$EXACT_TOLERANCE" > "$exact/$scene.toml"
    for seed in 1 2; do cal_row "$scene (given right, tolerance)" "scenes/$scene.toml" "$seed"; done
    for seed in 1 2; do cal_row "$scene (known exactly)" "$exact/$scene.toml" "$seed"; done
    for seed in 1 2; do cal_row "$scene --chain-drawn" "scenes/$scene.toml" "$seed" --chain-drawn; done
done

# Third table: every stream's chain drawn within the `chain_tolerance` (and
# `accelerometer_tolerance`) that `host-sim identify` prints for a stream of 60 impacts of the
# scene (seed 1), with `--accelerometer` where the scene has one and `--hertz-pulses` for the
# MEMS band, which does not ring long enough to be identified from its ring, n N.
id_row() { # label, scene file, seed
    "$bin" evaluate --scene "$2" --n "$n" --seed "$3" --chain-drawn --json | python3 -c '
import json, sys
d = json.load(sys.stdin)
p = lambda v: 100 * v
print("| %s | %s | %.2f | %.2f | %+.2f | %.2f | %.2f | %.2f / %.2f | %.2f |" % (sys.argv[1], sys.argv[2],
    p(d["forced_choice_accuracy"]), p(d["reference"]["accuracy"]),
    p(d["kernel_vs_reference"]["difference"]), p(d["coverage"]), p(d["confident_error_rate"]),
    p(d["rejected_share"]), p(d["missed_share"]), p(d["reliability"]["calibration_error_max"])))
' "$1" "$3"
}
echo
echo "| scene, chain drawn within | seed | forced choice (%) | reference limit (%) | kernel - reference (pp) | coverage (%) | confident errors (%) | rejected / missed (%) | calibration error max (pp) |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for scene in tail_beam mems_chain piezo_chain; do
    tol=$(identified_tolerance "$bin" "$exact" "$scene")
    label=$(python3 -c '
import re, sys
lines = sys.argv[1].splitlines()
f, z, g = (100 * float(v) for v in re.findall(r"= ([0-9.e-]+)", lines[0]))
label = "%g %% / %g %% / %g %%" % (f, z, g)
if len(lines) > 1:
    af, az = (100 * float(v) for v in re.findall(r"= ([0-9.e-]+)", lines[1]))
    label += "; band %g %% / %g %%" % (af, az)
print(label)' "$tol")
    with_sensor_lines "scenes/$scene.toml" "$tol" > "$exact/${scene}_identified.toml"
    for seed in 1 2; do
        id_row "$scene ($label)" "$exact/${scene}_identified.toml" "$seed"
    done
done
