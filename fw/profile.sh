#!/usr/bin/env bash
# Instruction profile of the node firmware: runs the release ELF under QEMU with
# `-singlestep -d exec,nochain` (one trace line per executed instruction, tagged with its
# symbol) and prints how many instructions each function executed, most first. Exact and
# deterministic; an independent check of the SysTick figures of fw/measure.sh, and the place
# to look when a budget breaks. Not part of CI (a few tens of seconds for the whole run).
#
# Usage: fw/profile.sh [ELF] [TOP]   (default: the thumbv7em release node binary, top 40)
# Environment: FW_CPU (default cortex-m4), FW_MACHINE (default netduinoplus2).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$(pwd)
target_dir=$(cargo metadata --format-version 1 --no-deps \
    | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
elf=${1:-$target_dir/thumbv7em-none-eabihf/release/node}
top=${2:-40}
if [ $# -eq 0 ]; then
    # Built as fw/measure.sh builds it, through the fixed path, so that the functions lie
    # in the same order and the counts match its figures.
    . fw/fixed-path.sh
    fwcargo build --release --target thumbv7em-none-eabihf --bin node
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkfifo "$tmp/trace"
timeout "${FW_TIMEOUT:-600}" qemu-system-arm \
    -cpu "${FW_CPU:-cortex-m4}" -machine "${FW_MACHINE:-netduinoplus2}" \
    -nographic -monitor none -serial null \
    -semihosting-config enable=on,target=native -icount shift=0 \
    -singlestep -d exec,nochain -D "$tmp/trace" -kernel "$elf" > /dev/null &
qemu=$!
demangle() { if command -v c++filt > /dev/null; then c++filt; else cat; fi; }
awk '/^Trace/ { n[$NF]++; total++ }
     END { for (k in n) printf "%10d %6.2f%%  %s\n", n[k], 100 * n[k] / total, k;
           printf "%10d total\n", total > "/dev/stderr" }' "$tmp/trace" \
    | sort -rn | head -n "$top" | demangle
wait "$qemu"
