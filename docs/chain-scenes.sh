# Shell functions that docs/chain-tables.sh, docs/noise-table.sh and docs/damped-chain-table.sh
# source (not run on its own): a chain scene with its [sensor] table told how well the chain is
# known.

# The `[sensor]` line of a chain known exactly.
EXACT_TOLERANCE='chain_tolerance = { frequency = 0.0, damping = 0.0, gain = 0.0 }'

# with_sensor_lines FILE LINES: scene file FILE with LINES put first in its [sensor] table.
with_sensor_lines() {
    awk -v lines="$2" '/^\[sensor\]/ { print; print lines; next } 1' "$1"
}

# identified_tolerance BIN DIR NAME: the tolerance lines `BIN identify` prints for a stream of
# 60 impacts (seed 1) of scenes/NAME.toml, written into DIR: with --accelerometer where the
# scene has one, and --hertz-pulses for the MEMS band, which does not ring long enough to be
# identified from its ring.
identified_tolerance() {
    local bin=$1 dir=$2 name=$3 fs flags=()
    "$bin" stream --scene "scenes/$name.toml" --n 60 --seed 1 --out "$dir/${name}_id" > /dev/null
    fs=$(awk -F'[= ]+' '/^sample_rate_hz/ { print $2; exit }' "scenes/$name.toml")
    grep -q '^accelerometer' "scenes/$name.toml" && flags+=(--accelerometer)
    [ "$name" = mems_chain ] && flags+=(--hertz-pulses)
    "$bin" identify --stream "$dir/${name}_id.bin" --sample-rate "$fs" "${flags[@]}" |
        grep -E '^(chain|accelerometer)_tolerance' | sed 's/ *#.*//'
}
