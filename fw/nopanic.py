#!/usr/bin/env python3
"""No-panic check of a linked release ELF.

With `panic = "abort"`, fat LTO and `--gc-sections`, a panic path survives in the final image
only if some code can reach it. So the check is on the linked firmware, not the source: every
direct branch into the panic machinery (`core::panicking::*`, bounds checks, slice/str index
failures, `unwrap`/`expect` failures, `f32::clamp`'s assertion, ...) is a panic site. The panic
handler itself (`rust_begin_unwind`) and the machinery's internal calls are not sites.

For every site the script prints the function that contains it, the source line of the call
and the source lines of the conditional branches that lead into the cold block holding it
(the checks that can fail; LLVM merges identical cold blocks, so the call's own line can
belong to another inlined function), and says whether the kernel (a `coalshock::` function,
or a line under the package's `src/`) is involved.

Usage: nopanic.py ELF --package-src DIR [--objdump PATH] [--strict]
Exit status: 0 when no site involves the kernel (with --strict: no site at all),
1 otherwise, 2 on a usage or tool error.
"""

import argparse
import re
import subprocess
import sys

# The panic machinery: branching to any of these is a panic site.
PANIC_ROOT = re.compile(
    r"^(core::panicking::|core::slice::index::|core::str::slice_error_fail|"
    r"core::option::(unwrap_failed|expect_failed)|core::result::unwrap_failed|"
    r"core::cell::panic_|core::fmt::.*panic|rust_begin_unwind$|__rust_start_panic|"
    r"core::num::.*(overflow|div_by_zero)|core::array::.*fail|"
    r"<f32>::clamp::do_panic|<f64>::clamp::do_panic|core::f(32|64)::.*do_panic)"
)

# Functions that are part of the machinery (their own calls into it are not sites).
MACHINERY = re.compile(
    r"^(core::panicking::|core::slice::index::.*fail|core::str::slice_error_fail|"
    r"core::option::(unwrap_failed|expect_failed)|core::result::unwrap_failed|"
    r"rust_begin_unwind$|__rust_start_panic|core::fmt::|<core::fmt::|"
    r"<&T as core::fmt::|<char>::escape_debug|core::unicode::)"
)

FUNC = re.compile(r"^([0-9a-f]+) <(.+)>:$")
INSN = re.compile(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$")
TARGET = re.compile(r"(0x[0-9a-f]+) <([^>]+?)(\+0x[0-9a-f]+)?>")
BRANCH = re.compile(
    r"^(bl|blx|b|b\.w|b(eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le)(\.w)?|cbz|cbnz)$")
# Instructions after which the next one starts a new basic block.
TERMINATOR = re.compile(r"^(b|b\.w|bx|pop|pop\.w|udf|bkpt)$")


def clean(path):
    path = re.sub(r"^.*/registry/src/[^/]+/", "", path)
    path = re.sub(r"^/rustc/[0-9a-f]+/", "", path)
    return path


def parse(text):
    """Functions as lists of (addr, mnemonic, operands, source line)."""
    funcs = {}
    func = None
    source = None
    for line in text.splitlines():
        m = FUNC.match(line)
        if m:
            func, source = m.group(2), None
            funcs.setdefault(func, [])
            continue
        if line.startswith("; "):
            source = clean(line[2:].strip())
            continue
        m = INSN.match(line)
        if m and func is not None:
            addr, mnemonic, rest = m.groups()
            funcs[func].append((int(addr, 16), mnemonic, rest, source or "?"))
    return funcs


def target_of(rest):
    t = TARGET.search(rest)
    if not t:
        return None, None, None
    return int(t.group(1), 16), t.group(2), t.group(3)


LIBRARY = re.compile(r"^(library/|[A-Za-z0-9_-]+-\d+\.\d+\.\d+[^/]*/|\?)")


def owner(insns, k, window=48):
    """The nearest source line at or before instruction `k` that is not library code."""
    for a, m, r, s in reversed(insns[max(0, k - window):k + 1]):
        if not LIBRARY.match(s):
            return s
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("elf")
    ap.add_argument("--objdump", default="llvm-objdump")
    ap.add_argument("--package-src", required=True,
                    help="directory of the kernel's sources as the debug info names it")
    ap.add_argument("--strict", action="store_true",
                    help="fail on any panic site, not only those involving the kernel")
    args = ap.parse_args()
    package_src = args.package_src.rstrip("/") + "/"

    cmd = [args.objdump, "-d", "-C", "-l", "--no-show-raw-insn", args.elf]
    try:
        text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"nopanic: cannot disassemble {args.elf}: {e}", file=sys.stderr)
        return 2

    funcs = parse(text)
    sites = []
    for func, insns in funcs.items():
        if MACHINERY.search(func):
            continue
        for i, (addr, mnemonic, rest, source) in enumerate(insns):
            if not BRANCH.match(mnemonic):
                continue
            _, target, offset = target_of(rest)
            if target is None or offset is not None or not PANIC_ROOT.search(target):
                continue
            # The cold block holding the call: back to the previous terminator or panic call.
            j = i
            while j > 0:
                pm, prest = insns[j - 1][1], insns[j - 1][2]
                _, ptarget, _ = target_of(prest)
                if TERMINATOR.match(pm) or (ptarget and PANIC_ROOT.search(ptarget)):
                    break
                j -= 1
            lo, hi = insns[j][0], addr
            # The checks: branches anywhere in the function into that block.
            checks = []
            for a2, m2, r2, s2 in insns:
                if BRANCH.match(m2) and not m2.startswith("bl"):
                    t2, _, _ = target_of(r2)
                    if t2 is not None and lo <= t2 <= hi:
                        checks.append(s2)
            checks = list(dict.fromkeys(checks))
            # Code of the kernel inlined into a caller (e.g. the firmware's `step` wrapper):
            # the nearest line before each check (and before the call) that is not in a
            # library decides who owns it.
            owners = []
            for k, (a2, m2, r2, s2) in enumerate(insns):
                if a2 == addr or (s2 in checks and BRANCH.match(m2) and not m2.startswith("bl")):
                    owners.append(owner(insns, k))
            owners = list(dict.fromkeys(o for o in owners if o))
            where = [source] + checks + owners
            kernel = "coalshock::" in func or any(w.startswith(package_src) for w in where)
            sites.append((addr, func, target, source, checks + [f"(code of {o})" for o in owners], kernel))

    def show(path):
        return path[len(package_src):] if path.startswith(package_src) else path

    kernel_sites = [s for s in sites if s[5]]
    other_sites = [s for s in sites if not s[5]]
    print(f"nopanic: {len(kernel_sites)} kernel panic site(s), {len(other_sites)} elsewhere")
    for addr, func, target, source, checks, kernel in sites:
        tag = "KERNEL" if kernel else "other "
        print(f"  {tag} 0x{addr:08x} in {func}")
        print(f"         calls {target} ({show(source)})")
        for c in checks:
            if c.startswith("(code of "):
                print(f"         {c[:9]}{show(c[9:-1])})")
            else:
                print(f"         reached from a check at {show(c)}")
    if kernel_sites or (args.strict and sites):
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
