#!/usr/bin/env bash
# The replayed stream of the node firmware (fw/), made by host-sim from the paper scene:
# fw/data/paper_stream.bin (little-endian i16 ADC codes) and
# fw/data/paper_stream.truth.csv (the truth of every impact and fault, host-sim/FORMATS.md).
# 40 impacts with injected faults (pile-ups, saturated impacts, dropped samples inside and
# between pulses, EMI spikes, a stuck run, and a stream that ends inside the last pulse), so
# the node shows rejections as well as verdicts. Same arguments, same bytes: every random draw
# comes from the seed.
#
# Usage: fw/stream.sh           regenerates the shipped pair in fw/data/
#        fw/stream.sh --check   regenerates it in a temporary directory and fails (status 1)
#                               unless both files equal the shipped ones byte for byte
#
# The debug build of host-sim is used (it shares its build with the host replay of fw/ci.sh);
# `cargo run --release -p host-sim -- stream ...` with the same arguments writes the same bytes.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

stem=fw/data/paper_stream
args=(stream --scene scenes/paper.toml --n 40 --seed 4
      --pileup-share 0.08 --saturate-share 0.05 --drop-share 0.05 --drop-quiet-share 0.05
      --spike-share 0.1 --stuck-share 0.05 --end-mid-pulse)

case "${1:-}" in
    "")
        cargo run --quiet -p host-sim -- "${args[@]}" --out "$stem"
        ;;
    --check)
        tmp=$(mktemp -d)
        trap 'rm -rf "$tmp"' EXIT
        cargo run --quiet -p host-sim -- "${args[@]}" --out "$tmp/paper_stream" > /dev/null
        status=0
        for ext in bin truth.csv; do
            if cmp -s "$tmp/paper_stream.$ext" "$stem.$ext"; then
                echo "$stem.$ext: reproduced byte for byte by host-sim"
            else
                echo "$stem.$ext DIFFERS from what host-sim makes now (fw/stream.sh regenerates it):" >&2
                cmp "$tmp/paper_stream.$ext" "$stem.$ext" >&2 || true
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
