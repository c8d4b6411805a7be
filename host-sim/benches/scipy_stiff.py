#!/usr/bin/env python3
"""scipy's stiff solvers on the heavily damped contact of `host-sim speed`, against host-sim.

The contact: the paper's coal sphere (R = 0.03 m, u = 1 m/s, no gravity) on carbon steel
under Adams IMPACT with d = 0.01 mm and c_max = 1 % of the Hertz stiffness in SI units
(e about 2.2e-5). scipy's Radau, BDF and LSODA (`solve_ivp`) integrate the same scaled
equation host-sim integrates (`x = delta / delta_max`, `v = delta' / u`, `tau = t / t_Hertz`:
`dx/dtau = C v`, `dv/dtau = -(t_Hertz / (u m)) F`, `C = 2.9432751843247`), Radau and BDF on
the exact Jacobian, with a terminal event at separation and events at the turn (`v = 0`,
`delta_max`) and at the force's peak (`dF/dtau = 0`). Each row is one tolerance pair: `rtol`
with `atol` `rtol * 1e-2` on `x` and `rtol * 1e-6` on `v`, since the sphere creeps out at
about 1e-5 u and its speed must keep relative accuracy (and one row with plain
`atol = rtol`). Errors are relative to host-sim's Rodas4 at rtol 1e-12 (which agrees with its
Dop853 at 1e-12 to 1e-9, `tests/integrator.rs`); "worst" is the largest of the four. The
host-sim rows are its Auto and Radau13, their force evaluations and, apart, their exact
Jacobians (about one per step, each costing about one force evaluation; `host-sim impact`'s
`jacobian_evals`).

Usage: python3 host-sim/benches/scipy_stiff.py [HOST_SIM_BINARY]
(from the repository root; needs numpy and scipy; the binary defaults to
target/release/host-sim).
"""
import subprocess
import sys

import numpy as np
from scipy.integrate import solve_ivp

C = 2.9432751843247
D_M = 1e-5
COLUMNS = ("delta_max_m", "peak_force_n", "duration_s", "rebound_speed_m_s")


def host_sim(binary, *args):
    """One `host-sim impact` row of the paper's coal sphere as a dict of its CSV columns."""
    out = subprocess.run([binary, "impact", "--material", "coal", "--radius", "0.03",
                          "--speed", "1", *args], check=True, capture_output=True,
                         text=True).stdout.strip().splitlines()
    return dict(zip(out[0].split(","), out[1].split(",")))


def problem(hertz):
    k = float(hertz["hertz_stiffness_n_m1_5"])
    m = float(hertz["mass_kg"])
    dm = float(hertz["hertz_delta_max_m"])
    t_h = float(hertz["hertz_duration_s"])
    c_max = 0.01 * k
    p = t_h / m

    def damping(delta):
        s = min(delta / D_M, 1.0)
        return c_max * s * s * (3.0 - 2.0 * s), (6.0 * c_max * s * (1.0 - s) / D_M if s < 1 else 0.0)

    def force(y):
        delta = y[0] * dm
        if delta <= 0.0:
            return 0.0
        c, _ = damping(delta)
        return max(0.0, k * delta ** 1.5 + c * y[1])

    def rhs(_t, y):
        return np.array([C * y[1], -p * force(y)])

    def jac(_t, y):
        delta = y[0] * dm
        if delta <= 0.0 or force(y) <= 0.0:
            return np.array([[0.0, C], [0.0, 0.0]])
        c, dc = damping(delta)
        return np.array([[0.0, C], [-p * dm * (1.5 * k * delta ** 0.5 + dc * y[1]), -p * c]])

    def force_rate(t, y):
        return -(jac(t, y)[1] @ rhs(t, y)) / p

    def separation(_t, y):
        return y[0]

    def turn(_t, y):
        return y[1]

    separation.terminal, separation.direction = True, -1
    turn.direction = -1
    force_rate.direction = -1
    return rhs, jac, (separation, turn, force_rate), (dm, t_h, force)


def scipy_row(method, rtol, atol, prob):
    rhs, jac, events, (dm, t_h, force) = prob
    kw = {} if method == "LSODA" else {"jac": jac}
    try:
        sol = solve_ivp(rhs, (0.0, 1e4), [0.0, 1.0], method=method, rtol=rtol, atol=atol,
                        events=events, **kw)
    except (ValueError, np.linalg.LinAlgError) as err:
        return None, str(err).splitlines()[0]
    if len(sol.t_events[0]) == 0:
        return None, sol.message
    y_end = sol.y_events[0][0]
    peak = max((force(y) for y in sol.y_events[2]), default=float("nan"))
    outputs = (sol.y_events[1][0][0] * dm, peak, sol.t_events[0][0] * t_h, -y_end[1])
    return (outputs, sol.nfev, sol.njev), None


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else "target/release/host-sim"
    hertz = host_sim(binary)
    prob = problem(hertz)
    c_max = "%.17g" % (0.01 * float(hertz["hertz_stiffness_n_m1_5"]))
    law = ["--law", "adams", "--c-max", c_max]
    ref_row = host_sim(binary, *law, "--method", "rodas4", "--tol", "1e-12")
    ref = [float(ref_row[c]) for c in COLUMNS]
    print("| solver | rtol | atol (x, v) | worst rel. error | t_c error | rebound error "
          "| force evals | Jacobians |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for method in ("auto", "radau13"):
        for tol in ("1e-9", "1e-6"):
            row = host_sim(binary, *law, "--method", method, "--tol", tol)
            errs = [abs(float(row[c]) / r - 1.0) for c, r in zip(COLUMNS, ref)]
            print("| host-sim %s | %s | relative (see --help) | %.1e | %.1e | %.1e | %s | %s |"
                  % (method, tol, max(errs), errs[2], errs[3], row["force_evals"],
                     row["jacobian_evals"]))
    for method in ("Radau", "BDF", "LSODA"):
        for rtol in (1e-6, 1e-8, 1e-9, 1e-10):
            for atol in ((rtol * 1e-2, rtol * 1e-6), rtol):
                got, why = scipy_row(method, rtol, list(atol) if isinstance(atol, tuple) else atol,
                                     prob)
                shown = "%.0e, %.0e" % atol if isinstance(atol, tuple) else "%.0e" % atol
                if got is None:
                    print("| scipy %s | %.0e | %s | failed: %s | | | | |" % (method, rtol, shown, why))
                    continue
                outputs, nfev, njev = got
                errs = [abs(o / r - 1.0) for o, r in zip(outputs, ref)]
                print("| scipy %s | %.0e | %s | %.1e | %.1e | %.1e | %d | %d |" % (
                    method, rtol, shown, max(errs), errs[2], errs[3], nfev, njev))


if __name__ == "__main__":
    main()
