#!/usr/bin/env bash
# Builds and runs the `monitor` fuzz target for a bounded time (for CI: `fuzz/run.sh 60`).
#
#   fuzz/run.sh [SECONDS] [extra libFuzzer flags...]
#
# SECONDS defaults to 60. FUZZ_FEATURES=micromath fuzzes the micromath backend. Exits non-zero
# when the fuzzer finds a crash (a panic, or a broken invariant); the input that did it is
# written to fuzz/artifacts/monitor/ and can be replayed with
#   cargo +nightly fuzz run monitor fuzz/artifacts/monitor/<file>
set -euo pipefail

secs="${1:-60}"
shift || true
cd "$(dirname "$0")"

# cargo-fuzz needs a nightly toolchain (installed here if the machine lacks one) and the cargo
# subcommand (installed once if it is missing).
if ! rustup toolchain list | grep -q '^nightly'; then
    rustup toolchain install nightly --profile minimal
fi
if ! cargo +nightly fuzz --version >/dev/null 2>&1; then
    cargo install cargo-fuzz --locked
fi

features=()
if [[ -n "${FUZZ_FEATURES:-}" ]]; then
    features=(--features "$FUZZ_FEATURES")
fi

mkdir -p corpus/monitor
cargo +nightly fuzz build monitor "${features[@]}"
exec cargo +nightly fuzz run monitor "${features[@]}" corpus/monitor -- \
    -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 "$@"
