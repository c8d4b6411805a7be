#!/usr/bin/env python3
"""scipy's DOP853 against host-sim's Dop853 on the undamped Hertz contact, in one run.

scipy (`solve_ivp(method="DOP853")`, rtol = atol = tol, with a terminal event at separation,
as host-sim locates it) integrates the scaled contact host-sim's speed bench uses
(`x = delta / delta_max`, `v = delta' / u`, `tau = t / t_c`: `dx/dtau = C v`,
`dv/dtau = -1.25 C x^1.5`, `C = 2.9432751843247`), whose closed forms put separation at
`tau = 1` with `v = -1`. Its impacts/s are the best of repeated batches over about one second;
its errors are `|v_end + 1|` (the rebound speed) and `|tau_end - 1|` (the contact time).
host-sim's figures come from `host-sim speed --json` (its `dop853 rtol` rows) run just before,
on the same machine, so the ratio is of one run.

Usage: python3 host-sim/benches/scipy_dop853.py [HOST_SIM_BINARY]
(from the repository root; needs numpy and scipy; the binary defaults to
target/release/host-sim, built by `cargo build --release -p host-sim`).
"""
import json
import subprocess
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

C = 2.9432751843247
TOLS = ("1e-6", "1e-9", "1e-12")


def rhs(_tau, y):
    x = max(y[0], 0.0)
    return np.array([C * y[1], -1.25 * C * x * np.sqrt(x)])


def separation(_tau, y):
    return y[0]


separation.terminal = True
separation.direction = -1


def one_impact(tol):
    """Solves one impact; returns (rebound error, contact-time error, force evaluations)."""
    sol = solve_ivp(rhs, (0.0, 2.0), [0.0, 1.0], method="DOP853", rtol=tol, atol=tol,
                    events=separation, first_step=1e-3)
    tau = sol.t_events[0][-1]
    v = sol.y_events[0][-1][1]
    return abs(v + 1.0), abs(tau - 1.0), sol.nfev


def impacts_per_s(tol, seconds=1.0):
    best, start = 0.0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < 0.2:
            one_impact(tol)
            n += 1
        best = max(best, n / (time.perf_counter() - t0))
    return best


def host_sim_rows(binary):
    out = subprocess.run([binary, "speed", "--impacts", "1000", "--integrator-seconds", "1",
                          "--json"], check=True, capture_output=True, text=True).stdout
    rows = json.loads(out)["integrator"]
    return {r["method"]: r for r in rows if r["law"] == "Hertz"}


def main():
    binary = sys.argv[1] if len(sys.argv) > 1 else "target/release/host-sim"
    host = host_sim_rows(binary)
    print("| Hertz, rtol | scipy DOP853 impacts/s | error (rebound, t_c) | force evals "
          "| host-sim dop853 impacts/s | error (F_max, t_c) | force evals | host-sim / scipy |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for label in TOLS:
        tol = float(label)
        err_v, err_t, evals = one_impact(tol)
        rate = impacts_per_s(tol)
        h = host["dop853 rtol " + label]
        print("| %s | %.0f | %.1e, %.1e | %d | %.0f | %.1e, %.1e | %d | %.0f |" % (
            label, rate, err_v, err_t, evals, h["impacts_per_s"], h["rel_err_peak_force"],
            h["rel_err_duration"], h["force_evals"], h["impacts_per_s"] / rate))


if __name__ == "__main__":
    main()
