#!/usr/bin/env bash
# Builds the node firmware (fw/src/bin/node.rs, package coalshock-fw), runs it in QEMU, measures it and checks the
# budgets of fw/budgets.txt. Exit status 0 only when the firmware ran to a successful exit and
# every budget holds.
#
# Measured (Cortex-M4F, thumbv7em-none-eabihf, QEMU netduinoplus2 with -icount shift=0):
#   - flash and static RAM of the release ELF (llvm-size), also without the replayed streams;
#   - what the firmware reports on its `measure` lines: kernel RAM (size_of), stack
#     high-water marks, instructions per quiet sample / per pulse / for building the scene;
#   - panic sites of the kernel left in the linked image (fw/nopanic.py).
# Also runs the front-end binary (fw/src/bin/front_end.rs: the IIS3DWB driver over a fake SPI
# sensor serving the same stream into Monitor::feed_slice) in QEMU; it must exit with success
# (`front_end_ok`), and its sizes are reported.
# Also builds the reference node (fw/src/bin/reference_node.rs, feature `board`, profile
# `board`) and budgets its flash and static RAM.
# Also builds the node without the kernel's `settle` (fw feature `settle`, a default one; build
# only): what the feature adds to the measuring node's flash (`settle_flash_added_bytes`, from
# `nosettle_flash_code_bytes`); its RAM per monitor is the node's `settle_bytes`. The same for
# the kernel's `noise_colour` (`noise_colour_flash_added_bytes`, from
# `nocolour_flash_code_bytes`), whose node is also run for the instructions the feature adds
# (`noise_colour_insns_*_added`).
# Also builds the node and the reference node with the yield feature (`plasticity`) and runs the
# node with the yielding scene: the feature's flash, RAM, stack and instructions are budgeted
# (`plasticity_*`, `yield_*`), and the non-yielding scenes must give the default node's lines.
# Also reported, not budgeted: the kernel built for thumbv6m-none-eabi (Cortex-M0/M0+) and
# thumbv8m.main-none-eabihf (Cortex-M33), and the same firmware's figures on a Cortex-M0 core
# (QEMU `-cpu cortex-m0` on the same machine: ARMv6-M instructions, no FPU).
#
# Outputs go to $FW_OUT (default: <cargo target dir>/fw): node.txt (decoded node output),
# measures.txt (every figure as `key value`), nopanic.txt, budget.md, front_end.txt, the
# same for M0, node-plasticity (ELF), node-plasticity.txt, nopanic-plasticity.txt and
# node-nocolour.txt.
# Environment: FW_SKIP_M0=1 skips the Cortex-M0 build and run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
root=$(pwd)
host=$(rustc -vV | sed -n 's/^host: //p')
tools="$(rustc --print sysroot)/lib/rustlib/$host/bin"
target_dir=$(cargo metadata --format-version 1 --no-deps \
    | python3 -c 'import json, sys; print(json.load(sys.stdin)["target_directory"])')
out=${FW_OUT:-$target_dir/fw}
mkdir -p "$out"
stream=fw/data/paper_stream.bin
chain_stream=fw/data/chain_stream.bin
# Bytes of the replayed streams in an image: the node carries both, the front end the paper one.
streams_node=$(( $(stat -c %s "$stream") + $(stat -c %s "$chain_stream") ))
streams_fe=$(stat -c %s "$stream")

section() { printf '\n== %s\n' "$*"; }

# Flash and static RAM of an ELF from its allocated sections (llvm-size -A): flash is
# everything loaded below 0x2000_0000 plus the .data initialisers, RAM is .data, .bss and
# .uninit. Appends `<prefix>flash_bytes`, `<prefix>static_ram_bytes` and (for the node)
# `<prefix>flash_code_bytes` (flash without the replayed streams, `$3` bytes of them) to
# measures.txt.
sizes() {
    local elf=$1 prefix=$2 streams=$3
    "$tools/llvm-size" -A "$elf" | python3 -c '
import sys
prefix, stream = sys.argv[1], int(sys.argv[2])
flash = ram = 0
for line in sys.stdin:
    p = line.split()
    if len(p) != 3 or not p[1].isdigit() or not p[2].isdigit():
        continue
    name, size, addr = p[0], int(p[1]), int(p[2])
    if addr == 0 or size == 0:
        continue  # debug info, .defmt (not loaded)
    if addr >= 0x20000000:
        ram += size
        if name == ".data":
            flash += size
    else:
        flash += size
print(f"{prefix}flash_bytes {flash}")
print(f"{prefix}flash_code_bytes {flash - stream}")
print(f"{prefix}static_ram_bytes {ram}")
' "$prefix" "$streams"
}

: > "$out/measures.txt"
status=0

section "build: node firmware, thumbv7em-none-eabihf (Cortex-M4F)"
# The firmware is built through a fixed path (fw/fixed-path.sh says why).
. fw/fixed-path.sh
fwcargo build --release --target thumbv7em-none-eabihf --bin node
elf="$target_dir/thumbv7em-none-eabihf/release/node"

section "run: QEMU netduinoplus2, -icount shift=0"
if fw/run.sh "$elf" > "$out/node.txt"; then
    echo "node exited with success ($(grep -c '^pulse ' "$out/node.txt") pulse lines)"
else
    rc=$?
    echo "node FAILED (status $rc); its output:"
    cat "$out/node.txt"
    status=1
fi
sed -n 's/^measure \([a-z0-9_]*\) \([0-9]*\)$/\1 \2/p' "$out/node.txt" >> "$out/measures.txt"

section "memory map: the image is linked with memory.x (fw/build.rs; the kernel has none)"
# The vector table at the start of FLASH and the initial stack pointer at the end of RAM, as
# the repository's memory.x gives them.
map=$(python3 - "$elf" "$tools/llvm-nm" memory.x <<'PY'
import re, subprocess, sys
elf, nm, memx = sys.argv[1:4]
text = open(memx).read()
def region(name):
    m = re.search(name + r"\s*:\s*ORIGIN\s*=\s*(0x[0-9A-Fa-f]+)\s*,\s*LENGTH\s*=\s*(\d+)K", text)
    return int(m.group(1), 16), int(m.group(2)) * 1024
flash, ram = region("FLASH"), region("RAM")
syms = {}
for line in subprocess.run([nm, elf], capture_output=True, text=True, check=True).stdout.splitlines():
    p = line.split()
    if len(p) == 3:
        syms[p[2]] = int(p[0], 16)
ok = syms.get("__vector_table", -1) == flash[0] and syms.get("_stack_start", -1) == ram[0] + ram[1]
print(f"memory_map_ok {int(ok)}  (FLASH {flash[0]:#x}+{flash[1]}, RAM {ram[0]:#x}+{ram[1]}, _stack_start {syms.get('_stack_start', 0):#x})")
PY
)
echo "$map"
echo "${map%%  *}" >> "$out/measures.txt"
case "$map" in memory_map_ok\ 1*) ;; *) status=1 ;; esac

section "size: llvm-size"
"$tools/llvm-size" -A "$elf" | awk '$3 != 0 && $2 != 0'
sizes "$elf" "" "$streams_node" | tee -a "$out/measures.txt"
echo "stream_bytes $(stat -c %s "$stream")" | tee -a "$out/measures.txt"
echo "chain_stream_bytes $(stat -c %s "$chain_stream")" | tee -a "$out/measures.txt"

section "panic paths: fw/nopanic.py"
set +e
python3 fw/nopanic.py --objdump "$tools/llvm-objdump" --package-src "$fw_src/src" "$elf" \
    > "$out/nopanic.txt"
set -e
cat "$out/nopanic.txt"
sed -n 's/^nopanic: \([0-9]*\) kernel panic site(s), \([0-9]*\) elsewhere$/nopanic_kernel_sites \1\nnopanic_other_sites \2/p' \
    "$out/nopanic.txt" >> "$out/measures.txt"

section "front end: fw/src/bin/front_end.rs in QEMU (IIS3DWB driver over a fake SPI sensor)"
fwcargo build --release --target thumbv7em-none-eabihf --bin front_end
elf_fe="$target_dir/thumbv7em-none-eabihf/release/front_end"
if fw/run.sh "$elf_fe" > "$out/front_end.txt"; then
    echo "front_end_ok 1" >> "$out/measures.txt"
    cat "$out/front_end.txt"
else
    rc=$?
    echo "front_end_ok 0" >> "$out/measures.txt"
    echo "front-end binary FAILED (status $rc); its output:"
    cat "$out/front_end.txt"
fi
sizes "$elf_fe" "front_end_" "$streams_fe" | tee -a "$out/measures.txt"

section "reference node: STM32F405 + IIS3DWB (build only; no IIS3DWB in QEMU)"
# Built with the size-optimised `board` profile (fw/Cargo.toml); its flash and static RAM are
# budgeted (reference_node_*).
fwcargo build --profile board --no-default-features --features board --bin reference_node
sizes "$target_dir/thumbv7em-none-eabihf/board/reference_node" "reference_node_" 0 \
    | grep -v '_flash_code_bytes ' | tee -a "$out/measures.txt"
# The same node with one more of the kernel's default features: what it adds to the
# size-optimised node with one backend (`reference_node_FEATURE_flash_added_bytes`).
reference_node_with() {
    fwcargo build --profile board --no-default-features --features "board,$1" --bin reference_node
    sizes "$target_dir/thumbv7em-none-eabihf/board/reference_node" "reference_node_$1_" 0 \
        | grep '_flash_bytes ' | tee -a "$out/measures.txt"
    python3 - "$out/measures.txt" "$1" <<'PY' | tee -a "$out/measures.txt"
import sys
m = dict(l.split()[:2] for l in open(sys.argv[1]) if len(l.split()) == 2)
f = sys.argv[2]
print(f"reference_node_{f}_flash_added_bytes "
      f"{int(m[f'reference_node_{f}_flash_bytes']) - int(m['reference_node_flash_bytes'])}")
PY
}
# `settle`: the equaliser's state re-estimation, as a node on a chain scene would carry it.
reference_node_with settle
# `second_order`: the measurement's second-order corrections, which the reference node leaves
# out to fit its 32 KiB part.
reference_node_with second_order

section "plasticity: the yield feature (fw feature plasticity; kernel feature plasticity)"
# Three more builds (the default ones above stay as they were and carry none of it):
#   - the node with the fw feature `plasticity`: the kernel's `plasticity` on, and the yielding
#     scene scenes/paper_yield.toml with its stream fw/data/yield_stream.* measured and logged
#     (prefix `yield `). Run in QEMU; its figures go to measures.txt with the prefix
#     `plasticity_`, except the yielding scene's own (`yield_*`); its paper and chain lines
#     must equal the default node's (`plasticity_verdicts_same`); its ELF is kept as
#     $out/node-plasticity and its log as $out/node-plasticity.txt;
#   - the node with only the kernel's `plasticity` (no yielding scene in the image):
#     `plasticity_flash_added_bytes`, the flash the kernel feature adds to the measuring node;
#   - the reference node with the kernel's `plasticity` (`board` profile):
#     `reference_node_plasticity_flash_added_bytes`, the same for a size-optimised node with
#     one backend.
streams_yield=$(( streams_node + $(stat -c %s fw/data/yield_stream.bin) ))
fwcargo build --release --target thumbv7em-none-eabihf --bin node --features plasticity
elf_p=$out/node-plasticity
cp "$elf" "$elf_p"
if fw/run.sh "$elf_p" > "$out/node-plasticity.txt"; then
    echo "node (plasticity) exited with success ($(grep -c '^yield pulse ' "$out/node-plasticity.txt") yield pulse lines)"
else
    rc=$?
    echo "node (plasticity) FAILED (status $rc); its output:"
    cat "$out/node-plasticity.txt"
    status=1
fi
sed -n -e 's/^measure \(yield_[a-z0-9_]*\) \([0-9]*\)$/\1 \2/p' \
    -e 's/^measure \([a-z0-9_]*\) \([0-9]*\)$/plasticity_\1 \2/p' "$out/node-plasticity.txt" \
    >> "$out/measures.txt"
sizes "$elf_p" "plasticity_" "$streams_yield" | tee -a "$out/measures.txt"
set +e
python3 fw/nopanic.py --objdump "$tools/llvm-objdump" --package-src "$fw_src/src" "$elf_p" \
    > "$out/nopanic-plasticity.txt"
set -e
tail -1 "$out/nopanic-plasticity.txt"
sed -n 's/^nopanic: \([0-9]*\) kernel panic site(s), .*$/plasticity_nopanic_kernel_sites \1/p' \
    "$out/nopanic-plasticity.txt" >> "$out/measures.txt"
verdicts='^(chain )?(pulse|stuck|classified|rejected|counters) '
if diff <(grep -E "$verdicts" "$out/node.txt") <(grep -E "$verdicts" "$out/node-plasticity.txt") \
        > /dev/null; then
    echo "plasticity_verdicts_same 1" | tee -a "$out/measures.txt"
else
    echo "plasticity_verdicts_same 0  (paper or chain lines differ from the default node's)" \
        | tee -a "$out/measures.txt"
fi
# The flash the kernel's feature adds: `plasticity_kernel_flash_code_bytes` minus the default
# node's `flash_code_bytes` (same streams, same measuring code).
fwcargo build --release --target thumbv7em-none-eabihf --bin node --features coalshock/plasticity
sizes "$elf" "plasticity_kernel_" "$streams_node" | grep '_flash_code_bytes ' \
    | tee -a "$out/measures.txt"
fwcargo build --profile board --no-default-features --features board,coalshock/plasticity --bin reference_node
sizes "$target_dir/thumbv7em-none-eabihf/board/reference_node" "reference_node_plasticity_" 0 \
    | grep -v '_flash_code_bytes ' | tee -a "$out/measures.txt"

section "settle and noise_colour: the node without each of the kernel's features"
# The measuring node built without the fw feature `settle` (`--no-default-features --features
# noise_colour,second_order`): the same image as the default one but for the kernel's `settle`, whose
# monitor slot is then `NoSettle` (no RAM). `settle_flash_added_bytes` is the default node's
# `flash_code_bytes` minus this one's (`nosettle_flash_code_bytes`): the flash the feature adds
# to the measuring node (both backends, opt-level 3). Its RAM per monitor is the node's
# `settle_bytes`.
fwcargo build --release --target thumbv7em-none-eabihf --bin node --no-default-features \
    --features noise_colour,second_order
sizes "$elf" "nosettle_" "$streams_node" | grep '_flash_code_bytes ' \
    | tee -a "$out/measures.txt"
# The same without the fw feature `noise_colour` (`--no-default-features --features
# settle,second_order`):
# `noise_colour_flash_added_bytes` is what the kernel's `noise_colour` adds (the colour's pass
# in the equaliser's design, the fits' weights and their quadratic form in the detector).
fwcargo build --release --target thumbv7em-none-eabihf --bin node --no-default-features \
    --features settle,second_order
sizes "$elf" "nocolour_" "$streams_node" | grep '_flash_code_bytes ' \
    | tee -a "$out/measures.txt"
# Run, for what the feature costs in instructions: a rigid scene's classification (the paper
# stream, `noise_colour_insns_classify_added`, the fits' bookkeeping for weights it never
# takes) and the chain scene's build (`noise_colour_insns_chain_scene_build_added`, the
# colour's pass).
if fw/run.sh "$elf" > "$out/node-nocolour.txt"; then
    sed -n -e 's/^measure \(insns_classify_max\|insns_chain_scene_build\) \([0-9]*\)$/nocolour_\1 \2/p' \
        "$out/node-nocolour.txt" | tee -a "$out/measures.txt"
else
    echo "node (without noise_colour) FAILED; its output:"
    cat "$out/node-nocolour.txt"
    status=1
fi
# What the plasticity, settle and noise_colour features add: differences of the builds above.
python3 - "$out/measures.txt" <<'PY' | tee -a "$out/measures.txt"
import sys
m = dict(l.split()[:2] for l in open(sys.argv[1]) if len(l.split()) == 2)
for key, a, b in [
    ("plasticity_flash_added_bytes", "plasticity_kernel_flash_code_bytes", "flash_code_bytes"),
    ("reference_node_plasticity_flash_added_bytes", "reference_node_plasticity_flash_bytes",
     "reference_node_flash_bytes"),
    ("plasticity_kernel_ram_added_bytes", "plasticity_kernel_ram_bytes", "kernel_ram_bytes"),
    ("settle_flash_added_bytes", "flash_code_bytes", "nosettle_flash_code_bytes"),
    ("noise_colour_flash_added_bytes", "flash_code_bytes", "nocolour_flash_code_bytes"),
    ("noise_colour_insns_classify_added", "insns_classify_max", "nocolour_insns_classify_max"),
    ("noise_colour_insns_chain_scene_build_added", "insns_chain_scene_build",
     "nocolour_insns_chain_scene_build"),
]:
    if a in m and b in m:
        print(f"{key} {int(m[a]) - int(m[b])}")
PY

# Leave the default images in place (cached: no rebuild).
fwcargo build --release --target thumbv7em-none-eabihf --bin node
fwcargo build --profile board --no-default-features --features board --bin reference_node

section "other cores: the kernel alone"
for t in thumbv6m-none-eabi thumbv8m.main-none-eabihf; do
    cargo build -p coalshock --release --target "$t"
done
echo "kernel builds for thumbv6m-none-eabi and thumbv8m.main-none-eabihf"

if [ "${FW_SKIP_M0:-0}" != 1 ]; then
    section "Cortex-M0 (thumbv6m-none-eabi): same firmware, QEMU -cpu cortex-m0 (report only)"
    fwcargo build --release --target thumbv6m-none-eabi --bin node
    elf0="$target_dir/thumbv6m-none-eabi/release/node"
    sizes "$elf0" "m0_" "$streams_node" | tee -a "$out/measures.txt"
    if FW_CPU=cortex-m0 fw/run.sh "$elf0" > "$out/node-m0.txt"; then
        sed -n 's/^measure \([a-z0-9_]*\) \([0-9]*\)$/m0_\1 \2/p' "$out/node-m0.txt" \
            >> "$out/measures.txt"
        if diff <(grep -E '^(chain )?(pulse|stuck|classified|rejected|counters) ' "$out/node.txt") \
                <(grep -E '^(chain )?(pulse|stuck|classified|rejected|counters) ' "$out/node-m0.txt") > /dev/null; then
            echo "m0_matches_m4 1" >> "$out/measures.txt"
            echo "Cortex-M0 verdicts identical to Cortex-M4F"
        else
            echo "m0_matches_m4 0" >> "$out/measures.txt"
            echo "Cortex-M0 verdicts DIFFER from Cortex-M4F (report only)"
        fi
        grep -E '^m0_(kernel_ram|stack_kernel|insns_)' "$out/measures.txt" || true
    else
        echo "Cortex-M0 run failed (report only):"
        cat "$out/node-m0.txt"
    fi
    fwcargo build --release --target thumbv8m.main-none-eabihf --bin node
    sizes "$target_dir/thumbv8m.main-none-eabihf/release/node" "m33_" "$streams_node" \
        | tee -a "$out/measures.txt"
fi

section "figures ($out/measures.txt)"
cat "$out/measures.txt"

section "budgets (fw/budgets.txt)"
if ! python3 fw/budget.py fw/budgets.txt "$out/measures.txt" "$out/budget.md"; then
    status=1
fi
exit "$status"
