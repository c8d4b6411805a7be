#!/usr/bin/env bash
# Installs what the firmware check (fw/ci.sh) needs on a fresh machine; skips whatever is
# already present, so running it again is cheap.
#   - Rust targets thumbv7em-none-eabihf (Cortex-M4F), thumbv6m-none-eabi (M0/M0+),
#     thumbv8m.main-none-eabihf (M33), and the llvm-tools component (llvm-size, llvm-objdump);
#   - qemu-system-arm (apt; about 45 s);
#   - defmt-print, the host-side defmt decoder (cargo install; about 2 min);
#   - python3 (used by the measurement scripts; expected to be present).
set -euo pipefail

step() { printf '[install] %s\n' "$*"; }

if command -v rustup > /dev/null; then
    installed=$(rustup target list --installed)
    for t in thumbv7em-none-eabihf thumbv6m-none-eabi thumbv8m.main-none-eabihf; do
        if grep -qx "$t" <<< "$installed"; then
            step "rust target $t: present"
        else
            step "rust target $t: installing"
            rustup target add "$t"
        fi
    done
    if rustup component list --installed | grep -q '^llvm-tools'; then
        step "llvm-tools: present"
    else
        step "llvm-tools: installing"
        rustup component add llvm-tools
    fi
else
    step "no rustup: the thumb targets and llvm-tools must come with the toolchain"
fi
host=$(rustc -vV | sed -n 's/^host: //p')
tools="$(rustc --print sysroot)/lib/rustlib/$host/bin"
for t in llvm-size llvm-objdump; do
    if [ ! -x "$tools/$t" ]; then
        echo "[install] $t missing under $tools (rustup component add llvm-tools)" >&2
        exit 1
    fi
done

if command -v qemu-system-arm > /dev/null; then
    step "qemu-system-arm: present ($(qemu-system-arm --version | sed -n 1p))"
else
    step "qemu-system-arm: installing (apt)"
    sudo=""
    if [ "$(id -u)" != 0 ]; then sudo="sudo"; fi
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends \
        qemu-system-arm
fi

if command -v defmt-print > /dev/null; then
    step "defmt-print: present ($(defmt-print --version | sed -n 1p))"
else
    step "defmt-print: installing (cargo install, about 2 minutes)"
    cargo install --locked defmt-print --version 1.2.0
fi

if command -v python3 > /dev/null; then
    step "python3: present"
else
    echo "[install] python3 is required by fw/measure.sh" >&2
    exit 1
fi
