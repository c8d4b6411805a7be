#!/usr/bin/env bash
# Cargo runner for thumbv7em-none-eabihf: runs an ELF on QEMU's `netduinoplus2` (STM32F405,
# Cortex-M4F) and decodes its defmt output on the host. The firmware's exit status (semihosting
# exit) is the script's status; a hang ends after FW_TIMEOUT seconds (default 120) with 124.
#
# Usage: fw/run.sh path/to/elf
# Environment: FW_TIMEOUT, FW_MACHINE (default netduinoplus2), FW_CPU (default cortex-m4),
#              FW_QEMU_ARGS (extra QEMU arguments), FW_LOG_FORMAT (defmt-print format, default {s}).
#
# QEMU always runs with `-icount shift=0`: one guest instruction per virtual nanosecond, so
# the SysTick-based instruction counts the firmware reports are deterministic.
set -euo pipefail
elf=${1:?usage: run.sh ELF}
shift
machine=${FW_MACHINE:-netduinoplus2}
cpu=${FW_CPU:-cortex-m4}
# shellcheck disable=SC2086
timeout "${FW_TIMEOUT:-120}" qemu-system-arm \
    -cpu "$cpu" -machine "$machine" -nographic -monitor none -serial null \
    -semihosting-config enable=on,target=native \
    -icount shift=0 ${FW_QEMU_ARGS:-} \
    -kernel "$elf" "$@" \
    | defmt-print --log-format "${FW_LOG_FORMAT:-{s\}}" -e "$elf"
