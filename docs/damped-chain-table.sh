#!/usr/bin/env bash
# Regenerates the table "Damped contact behind a chain" of docs/chain.md: each chain scene
# (tail_beam, mems_chain, piezo_chain) with its [contact] set to each damped law at e 0.3,
# 0.5 and 0.9 (and Hertz, as shipped), told the tolerance `host-sim identify` prints for a
# stream of 60 of its impacts (docs/chain-scenes.sh), evaluated with the chain given right and
# with every stream's chain drawn within that tolerance (--chain-drawn): n N per class, seed 1.
# Usage: bash docs/damped-chain-table.sh [N]   (from the repository root; needs python3)
set -euo pipefail
# shellcheck source=docs/chain-scenes.sh
source docs/chain-scenes.sh
n=${1:-5000}
cargo build --release -q -p host-sim
bin=${CARGO_TARGET_DIR:-target}/release/host-sim
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# evaluate FILE FLAGS...: the figures of one run, as JSON on one line.
evaluate() {
    local file=$1
    shift
    "$bin" evaluate --scene "$file" --n "$n" --seed 1 --bayes-draws 1000 "$@" --json 2>/dev/null
}
echo "| scene | law, e | kernel - reference (pp) | confident errors (%) | calibration error max (pp) | rms z, ln R / ln u | drawn: kernel - reference (pp) | drawn: confident errors (%) |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for scene in tail_beam mems_chain piezo_chain; do
    tol=$(identified_tolerance "$bin" "$work" "$scene")
    for contact in hertz hunt_crossley:0.3 hunt_crossley:0.5 hunt_crossley:0.9 \
        lankarani_nikravesh:0.3 lankarani_nikravesh:0.5 lankarani_nikravesh:0.9 \
        flores:0.3 flores:0.5 flores:0.9 gonthier:0.3 gonthier:0.5 gonthier:0.9 \
        tsuji:0.3 tsuji:0.5 tsuji:0.9; do
        law=${contact%%:*}
        lines="law = \"$law\""
        [ "$law" != hertz ] && lines="$lines
restitution = ${contact#*:}"
        file="$work/${scene}_${contact/:/_}.toml"
        with_sensor_lines "scenes/$scene.toml" "$tol" |
            awk -v lines="$lines" '/^law = / { print lines; next } 1' > "$file"
        right=$(evaluate "$file")
        drawn=$(evaluate "$file" --chain-drawn)
        python3 -c '
import json, sys
r, d = json.loads(sys.argv[3]), json.loads(sys.argv[4])
gap = lambda x: 100 * (x["forced_choice_accuracy"] - x["reference"]["accuracy"])
c = r["noise"]["stated_noise_check"]
print("| %s | %s | %+.2f | %.2f | %.1f | %.2f / %.2f | %+.2f | %.2f |" % (sys.argv[1], sys.argv[2],
    gap(r), 100 * r["confident_error_rate"], 100 * r["reliability"]["calibration_error_max"],
    c["ln_radius"]["rms"], c["ln_speed"]["rms"], gap(d), 100 * d["confident_error_rate"]))
' "$scene" "${contact/:/ e }" "$right" "$drawn"
    done
done
