# Sourced by fw/measure.sh and fw/profile.sh (from the repository root, `root` set to it): defines
# `fwcargo`, cargo in the firmware's workspace with its manifest named through a fixed path.
# The firmware is its own workspace (fw/Cargo.toml) and reads fw/.cargo/config.toml, so cargo
# runs in fw/; it shares the repository's target directory.
# The fixed path is a symlink to this checkout, so that the figures do not depend on where the
# checkout lies. The kernel (the repository root) and iis3dwb are path dependencies outside the
# firmware's workspace, and cargo hashes their absolute path into their `-C metadata`; rustc
# derives the symbol names from it, the names order the functions in the image, and the
# alignment padding between them follows: one commit measured `.text` 8 B apart from two
# checkouts (flash_code_bytes, settle_flash_added_bytes). `--remap-path-prefix` does not enter
# that hash. The lock, held until the sourcing script ends, makes a run from another checkout
# wait instead of repointing the symlink under this one's builds.
fw_src=/tmp/coalshock-fw-src
exec 9> "$fw_src.lock"
flock 9
ln -sfn "$root" "$fw_src"
fwcargo() { (cd fw && cargo "$@" --manifest-path "$fw_src/fw/Cargo.toml"); }
