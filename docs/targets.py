"""The targets of docs/grid.md, checked on one `host-sim evaluate --json` object, and the
lines both tables print about them.

docs/grid-table.sh and docs/random-table.sh import it, and docs/chain-tables.sh and
docs/clipping-chain-table.sh its `worst_bin` (run from the repository root with docs/ on the
path). A row misses a target when:
  forced choice     the kernel is more than 1 pp below the reference limit beyond two standard
                    errors of the difference;
  confident errors  more than 1 % of its Class verdicts are wrong;
  calibration       a reliability bin of at least `min_verdicts` verdicts has
                    |stated - observed| above 2 pp beyond two of the bin's standard errors.
A row above the limit by more than three standard errors is listed apart (`beats_reference`).
"""


def check(d):
    """(the targets missed, kernel - reference, its standard error, the worst bin's excess)."""
    gap = d["kernel_vs_reference"]["difference"]
    se = d["kernel_vs_reference"]["std_error"]
    rel = d["reliability"]
    worst_bin = 0.0
    for b in rel["bins"]:
        if b["verdicts"] >= rel["min_verdicts"]:
            worst_bin = max(worst_bin, abs(b["stated"] - b["observed"]) - 2 * b["std_error"])
    fails = []
    if gap + 2 * se < -0.01:
        fails.append("forced choice")
    if d["confident_error_rate"] > 0.01:
        fails.append("confident errors")
    if worst_bin > 0.02:
        fails.append("calibration")
    return fails, gap, se, worst_bin


def beats_reference(d):
    """Whether the kernel stands above the reference limit by more than three standard errors
    of the difference: no miss of the kernel's, but a sign that the limit is no limit."""
    k = d["kernel_vs_reference"]
    return k["difference"] - 3 * k["std_error"] > 0


def print_beaten(beaten, total):
    """The line of the scenes where the kernel beats the reference limit (see
    `beats_reference`)."""
    print("- above the reference limit beyond three standard errors (the limit in doubt, not a"
          " miss): %d of %d%s" % (len(beaten), total, names(beaten)))


def worst_bin(d):
    """The reliability bin of at least `min_verdicts` verdicts farthest from its stated
    posterior (a dict with `stated`, `observed`, `verdicts`)."""
    rel = d["reliability"]
    full = [b for b in rel["bins"] if b["verdicts"] >= rel["min_verdicts"]]
    return max(full, key=lambda b: abs(b["stated"] - b["observed"]))


REFUSED = "the kernel refused the scene"


def refusal(err):
    """The kernel's reason for refusing a scene, from `host-sim evaluate`'s stderr, or None."""
    if REFUSED not in err:
        return None
    return err[err.index(REFUSED):].splitlines()[0]


def names(v):
    """` (a, b, c)` for a non-empty list of scene names, else nothing."""
    return (" (" + ", ".join(v) + ")") if v else ""


def print_misses(misses, total):
    """One line per target: how many of `total` scenes miss it, and which."""
    for key, v in misses.items():
        print("- %s: %d of %d%s" % (key, len(v), total, names(v)))


def print_refused(refused):
    """The line of the scenes the kernel refused at the scene build."""
    print("\nRefused by the kernel at the scene build (not counted above): %d%s" % (
        len(refused), names(refused)))
