#!/usr/bin/env bash
# Regenerates the README's table "End to end against the reference limit": every shipped scene
# at n 5000 per class, seed 1, default confident-error rate.
# Usage: bash docs/accuracy-table.sh [N] [SEED]   (from the repository root; needs python3)
set -euo pipefail
n=${1:-5000}
seed=${2:-1}
cargo build --release -q -p host-sim
bin=${CARGO_TARGET_DIR:-target}/release/host-sim
row() { # scene, label
    "$bin" evaluate --scene "scenes/$1.toml" --n "$n" --seed "$seed" --json 2>/dev/null |
        python3 -c '
import json, sys
d = json.load(sys.stdin)
ref, gap, rel = d["reference"], d["kernel_vs_reference"], d["reliability"]
pct = lambda v: 100 * v
share = lambda k: "%.4g" % round(pct(d[k]), 2)
print("| %s | %.2f ± %.2f | %.2f ± %.2f | %+.2f ± %.2f | %.2f | %.1f | %.2f | %.1f / %.1f | %s / %s / %s / %s |" % (
    sys.argv[1],
    pct(d["forced_choice_accuracy"]), pct(d["forced_choice_std_error"]),
    pct(ref["accuracy"]), pct(ref["std_error"]),
    pct(gap["difference"]), pct(gap["std_error"]),
    pct(d["oracle_accuracy"]), pct(d["coverage"]), pct(d["confident_error_rate"]),
    pct(rel["calibration_error_max"]), pct(rel["calibration_error_mean"]),
    share("ambiguous_share"), share("out_of_envelope_share"), share("rejected_share"),
    share("missed_share")))
' "$2"
}
echo "| scene | forced choice (%) | reference limit (%) | kernel - reference (pp) | oracle (%) | coverage (%) | confident errors (%) | calibration error max / mean (pp) | ambiguous / out / rejected / missed (%) |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
row paper '`paper`'
row paper_narrow '`paper_narrow` (u 2.5-3.5 m/s)'
row roof_rock '`roof_rock` (coal, roof sandstone, sandy mudstone; drop heights)'
row mems_26k '`mems_26k` (26.7 kS/s, 3-12 samples per pulse)'
row noisy '`noisy` (40 counts RMS)'
row paper_damped '`paper_damped` (Flores, e = 0.5, calibrated)'
row paper_adams '`paper_adams` (the paper'"'"'s Adams IMPACT, e = 0.5, d = 0.01 mm, ratio tables)'
row paper_adams_fixed '`paper_adams_fixed` (Adams IMPACT, one `c_max` 687.16 N s/m, d = 0.01 mm, ratio tables)'
row tail_beam '`tail_beam` (3 beam modes 180 Hz - 2.1 kHz, 100 kS/s)'
row mems_chain '`mems_chain` (the same beam, a 6.3 kHz MEMS band, 26.7 kS/s)'
row piezo_chain '`piezo_chain` (the same beam, a 35 kHz piezo, 100 kS/s)'
row paper_yield '`paper_yield` (contacts that yield: Thornton)'
row yield_tail_beam '`yield_tail_beam` (yielding contacts behind the tail beam'"'"'s chain)'
row tsuji_25k '`tsuji_25k` (Tsuji, e = 0.4, 25 kS/s)'
row flores_25k '`flores_25k` (Flores, e = 0.5, 25 kS/s)'
