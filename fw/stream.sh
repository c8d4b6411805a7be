#!/usr/bin/env bash
# The replayed streams of the node firmware (fw/), made by host-sim:
#   fw/data/paper_stream.bin and .truth.csv from the paper scene (scenes/paper.toml), 40 impacts;
#   fw/data/chain_stream.bin and .truth.csv from the chain scene (scenes/piezo_chain.toml: the
#   same classes on a tail beam with 3 modes under a piezo accelerometer), 20 impacts;
#   fw/data/yield_stream.bin and .truth.csv from the yielding scene (scenes/paper_yield.toml:
#   the paper scene with Thornton's elastic-plastic contact), 20 impacts (the node replays it
#   when built with the feature `plasticity`);
# (little-endian i16 ADC codes, and the truth of every impact and fault, host-sim/FORMATS.md).
# Both with injected faults (pile-ups, saturated impacts, dropped samples inside and between
# pulses, EMI spikes, a stuck run, and a stream that ends inside the last pulse), so the node
# shows rejections as well as verdicts. Same arguments, same bytes: every random draw comes
# from the seed.
# Also the node's scenes, fw/replay/src/scenes/paper.rs, piezo_chain.rs and paper_yield.rs: Rust source written
# by `host-sim export` from the same scene files (the kernel scene host-sim builds from each).
#
# Usage: fw/stream.sh           regenerates the shipped pairs in fw/data/ and the scenes
#        fw/stream.sh --check   regenerates them in a temporary directory and fails (status 1)
#                               unless every file equals the shipped one byte for byte
#
# The debug build of host-sim is used (it shares its build with the host replay of fw/ci.sh);
# `cargo run --release -p host-sim -- stream ...` with the same arguments writes the same bytes.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

faults=(--pileup-share 0.08 --saturate-share 0.05 --drop-share 0.05 --drop-quiet-share 0.05
        --spike-share 0.1 --stuck-share 0.05 --end-mid-pulse)
names=(paper_stream chain_stream yield_stream)
args_paper_stream=(stream --scene scenes/paper.toml --n 40 --seed 4 "${faults[@]}")
args_chain_stream=(stream --scene scenes/piezo_chain.toml --n 20 --seed 4 "${faults[@]}")
args_yield_stream=(stream --scene scenes/paper_yield.toml --n 20 --seed 4 "${faults[@]}")
# Exported scenes: fw/replay/src/scenes/<name>.rs from scenes/<name>.toml.
scenes=(paper piezo_chain paper_yield)

case "${1:-}" in
    "")
        for name in "${names[@]}"; do
            declare -n args="args_$name"
            cargo run --quiet -p host-sim -- "${args[@]}" --out "fw/data/$name"
        done
        for scene in "${scenes[@]}"; do
            cargo run --quiet -p host-sim -- export --scene "scenes/$scene.toml" \
                --out "fw/replay/src/scenes/$scene.rs"
        done
        ;;
    --check)
        tmp=$(mktemp -d)
        trap 'rm -rf "$tmp"' EXIT
        status=0
        for name in "${names[@]}"; do
            declare -n args="args_$name"
            cargo run --quiet -p host-sim -- "${args[@]}" --out "$tmp/$name" > /dev/null
            stem=fw/data/$name
            for ext in bin truth.csv; do
                if cmp -s "$tmp/$name.$ext" "$stem.$ext"; then
                    echo "$stem.$ext: reproduced byte for byte by host-sim"
                else
                    echo "$stem.$ext DIFFERS from what host-sim makes now (fw/stream.sh regenerates it):" >&2
                    cmp "$tmp/$name.$ext" "$stem.$ext" >&2 || true
                    status=1
                fi
            done
        done
        for scene in "${scenes[@]}"; do
            shipped=fw/replay/src/scenes/$scene.rs
            cargo run --quiet -p host-sim -- export --scene "scenes/$scene.toml" \
                --out "$tmp/$scene.rs"
            if cmp -s "$tmp/$scene.rs" "$shipped"; then
                echo "$shipped: reproduced byte for byte by host-sim export"
            else
                echo "$shipped DIFFERS from what host-sim export makes now (fw/stream.sh regenerates it):" >&2
                diff -u "$shipped" "$tmp/$scene.rs" >&2 || true
                status=1
            fi
        done
        exit "$status"
        ;;
    *)
        echo "usage: fw/stream.sh [--check]" >&2
        exit 2
        ;;
esac
