#!/usr/bin/env bash
# Regenerates the table "The noise each pulse is weighed on" of docs/chain.md: for every
# shipped scene, and for the chain scenes also known exactly (tolerance 0), drawn within their
# tolerance for every stream (--chain-drawn), and drawn within the tolerance `host-sim
# identify` prints for a stream of 60 impacts (docs/chain-tables.sh, third table), the check of
# the noise the classifier weighs each pulse on against the impacts' true radius and speed
# (`noise.stated_noise_check` of `host-sim evaluate --json`), n N per class, seed 1.
# Usage: bash docs/noise-table.sh [N]   (from the repository root; needs python3)
set -euo pipefail
# shellcheck source=docs/chain-scenes.sh
source docs/chain-scenes.sh
n=${1:-5000}
cargo build --release -q -p host-sim
bin=${CARGO_TARGET_DIR:-target}/release/host-sim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
row() { # label, scene file, flags...
    local label=$1 file=$2
    shift 2
    "$bin" evaluate --scene "$file" --n "$n" --seed 1 --reference-draws 2000 --bayes-draws 1000 \
        "$@" --json 2>/dev/null | python3 -c '
import json, sys
d = json.load(sys.stdin)
c = d["noise"]["stated_noise_check"]
z = lambda s: "%.2f / %.1f / %.2f / %.2f" % (s["rms"], *(100 * v for v in s["beyond"]))
print("| %s | %d | %s | %s | %.1f |" % (sys.argv[1], c["pulses"], z(c["ln_radius"]), z(c["ln_speed"]),
    100 * d["reliability"]["calibration_error_max"]))
' "$label"
}
echo "| scene, chain | pulses | ln R: rms z / abs(z) > 1, 2, 3 (%) | ln u: rms z / abs(z) > 1, 2, 3 (%) | calibration error max (pp) |"
echo "| --- | --- | --- | --- | --- |"
echo "| standard normal | | 1.00 / 31.7 / 4.55 / 0.27 | 1.00 / 31.7 / 4.55 / 0.27 | |"
for s in scenes/*.toml; do
    row "$(basename "$s" .toml)" "$s"
done
for scene in tail_beam mems_chain piezo_chain; do
    with_sensor_lines "scenes/$scene.toml" "$EXACT_TOLERANCE" > "$work/${scene}_exact.toml"
    row "$scene, known exactly" "$work/${scene}_exact.toml"
    row "$scene --chain-drawn" "scenes/$scene.toml" --chain-drawn
    tol=$(identified_tolerance "$bin" "$work" "$scene")
    with_sensor_lines "scenes/$scene.toml" "$tol" > "$work/${scene}_identified.toml"
    row "$scene, identified tolerance, given right" "$work/${scene}_identified.toml"
    row "$scene, identified tolerance, --chain-drawn" "$work/${scene}_identified.toml" --chain-drawn
done
