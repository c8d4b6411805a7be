#!/usr/bin/env bash
# Everything CI does for the firmware, in one script:
#   1. fw/install.sh (targets, llvm-tools, qemu-system-arm, defmt-print; skips what is present);
#   2. fw/stream.sh --check: host-sim regenerates the replayed streams (fw/data/
#      paper_stream.* from the paper scene, chain_stream.* from scenes/piezo_chain.toml,
#      yield_stream.* from scenes/paper_yield.toml) and
#      `host-sim export` the node's scenes (fw/replay/src/scenes/), and they must equal the
#      shipped files byte for byte;
#   3. fw/measure.sh: builds the firmware, runs it in QEMU (Cortex-M4F), measures flash, RAM,
#      stack and instructions, checks for kernel panic paths and enforces fw/budgets.txt;
#      runs the front-end binary (fw/src/bin/front_end.rs) in QEMU; also builds for Cortex-M0
#      and M33 and runs the M0 build (report only); builds the reference node (report and
#      budget of its sizes); builds the node and the reference node once more with the yield
#      feature (`plasticity`) and runs that node (the yielding scene's stream too);
#   4. host replay: `cargo run -p host-sim --example node_replay`, where host-sim reads the
#      same stream files and replays them through the kernel and prints the verdict lines
#      (those of the chain stream after the prefix `chain `, the yielding stream's after
#      `yield `);
#   5. compares the node's pulse/stuck/classified/rejected/counters lines with the host's, for
#      each stream: they must be identical, pulse by pulse (same f32 arithmetic on both; the
#      yielding stream's lines come from the node built with `plasticity`);
#   6. the front-end check on the host (`cargo run -p host-sim --example front_end`): same
#      output as in QEMU.
# Exit status 0 only when all of it passes. Outputs: <cargo target dir>/fw (or $FW_OUT).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
start=$SECONDS
section() { printf '\n==== %s (%ds)\n' "$*" "$((SECONDS - start))"; }

section "install"
fw/install.sh

target_dir=$(cargo metadata --format-version 1 --no-deps \
    | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
out=${FW_OUT:-$target_dir/fw}
export FW_OUT=$out
mkdir -p "$out"

for stream in fw/data/paper_stream.bin fw/data/chain_stream.bin fw/data/yield_stream.bin; do
    if [ ! -s "$stream" ] || [ $(( $(stat -c %s "$stream") % 2 )) != 0 ]; then
        echo "$stream missing or not a whole number of i16 samples" >&2
        exit 1
    fi
done

status=0
section "streams and scenes: regenerate with host-sim and compare with the shipped ones (fw/stream.sh --check)"
fw/stream.sh --check || status=1

section "firmware: build, run, measure, budgets (fw/measure.sh)"
fw/measure.sh || status=$?

section "host replay (cargo run -p host-sim --example node_replay)"
rm -f "$out/host.txt"
if cargo run --quiet -p host-sim --example node_replay > "$out/host.txt"; then
    echo "$(grep -c '^pulse ' "$out/host.txt") pulse lines on the host"
else
    echo "host replay FAILED"
    status=1
fi

section "compare node with host (paper stream, chain stream, yielding stream)"
if [ ! -s "$out/node.txt" ] || [ ! -s "$out/node-plasticity.txt" ] || [ ! -s "$out/host.txt" ]; then
    echo "nothing to compare (node or host output missing)"
    status=1
else
    : > "$out/compare.diff"
    for prefix in "" "chain " "yield "; do
        name=${prefix:-paper }
        # The yielding stream is replayed by the node built with `plasticity`.
        node=$out/node.txt
        [ "$prefix" = "yield " ] && node=$out/node-plasticity.txt
        lines="^${prefix}(pulse|stuck|classified|rejected|counters) "
        if ! grep -qE "^${prefix}pulse " "$out/host.txt"; then
            echo "${name% }: nothing to compare (no pulse line on the host)"
            status=1
        elif diff -u <(grep -E "$lines" "$out/host.txt") <(grep -E "$lines" "$node") \
                >> "$out/compare.diff"; then
            echo "${name% } stream: node and host agree on all $(grep -cE "$lines" "$out/host.txt") lines" \
                "($(grep -cE "^${prefix}pulse " "$out/host.txt") pulse verdicts)"
            grep -E "^${prefix}(truth|feed_check) " "$out/host.txt" || true
        else
            echo "${name% } stream: node and host DIFFER:"
            head -40 "$out/compare.diff"
            status=1
        fi
    done
fi

section "front end on the host (cargo run -p host-sim --example front_end)"
rm -f "$out/front_end-host.txt"
if cargo run --quiet -p host-sim --example front_end > "$out/front_end-host.txt"; then
    cat "$out/front_end-host.txt"
else
    echo "front-end check FAILED on the host:"
    cat "$out/front_end-host.txt"
    status=1
fi
if [ -s "$out/front_end.txt" ] && diff -u "$out/front_end-host.txt" "$out/front_end.txt" \
        > "$out/front_end.diff"; then
    echo "front end: host and node print the same lines"
else
    echo "front end: host and node DIFFER (or the node output is missing):"
    head -20 "$out/front_end.diff" 2> /dev/null || true
    status=1
fi

section "done: status $status"
exit "$status"
