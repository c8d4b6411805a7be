#!/usr/bin/env python3
"""Deterministic stand-in for the paper-scene sample stream (little-endian i16).

Until host-sim writes `examples/data/paper_stream.bin` from its contact integrator and sensor
chain, this script produces a stream of the same shape so the firmware can be built, run and
measured: undamped Hertz pulses `F(t) = F_max sin^(3/2)(pi t / t_c)` of coal and sandstone
spheres (the paper scene: R in [0.015, 0.04] m, u in [1, 5] m/s, carbon-steel plate), converted
to ADC counts with the scene's sensor chain (100 kS/s, 50 kg / 30 counts per m/s^2), on a DC
offset with deterministic pseudo-noise of about 4 counts RMS, plus a few pulses that must be
rejected (spike, pile-up, saturation, stream ending inside a pulse).

Usage: gen_stream.py OUT.bin [--pulses N] [--gap SAMPLES]
Same arguments, same bytes: no randomness beyond a fixed-seed xorshift32.
"""

import argparse
import math
import struct
import sys

FS = 100_000.0  # samples per second
FORCE_PER_COUNT = 50.0 / 30.0  # N per count (plate mass / accelerometer sensitivity)
NOISE_RMS = 4.0  # counts
DC = 37  # counts
ADC_MIN, ADC_MAX = -32768, 32767

# density kg/m^3, Young's modulus Pa, Poisson's ratio (paper Tables 1-2)
COAL = (1380.0, 5.3e9, 0.32)
SANDSTONE = (2487.0, 13.5e9, 0.123)
STEEL = (7850.0, 2.06e11, 0.28)


class XorShift32:
    def __init__(self, seed):
        self.s = seed & 0xFFFFFFFF or 1

    def next(self):
        s = self.s
        s ^= (s << 13) & 0xFFFFFFFF
        s ^= s >> 17
        s ^= (s << 5) & 0xFFFFFFFF
        self.s = s
        return s

    def uniform(self):
        return self.next() / 4294967296.0

    def gauss(self):
        # Irwin-Hall with 12 terms: mean 0, variance 1.
        return sum(self.uniform() for _ in range(12)) - 6.0


def hertz(material, radius, speed):
    """Peak force (N) and contact duration (s) of an undamped sphere-on-plate impact."""
    rho = material[0]
    e_eff = 1.0 / ((1 - material[2] ** 2) / material[1] + (1 - STEEL[2] ** 2) / STEEL[1])
    delta = (5 * math.pi * rho / (4 * e_eff)) ** 0.4 * radius * speed**0.8
    force = 4.0 / 3.0 * e_eff * math.sqrt(radius) * delta**1.5
    duration = 2.9432752 * delta / speed
    return force, duration


def add_pulse(signal, start, peak_counts, duration_s):
    """Adds a sampled sin^(3/2) pulse starting at fractional sample `start`."""
    n = duration_s * FS
    if n < 1.0:  # shorter than a sample: one isolated sample (an EMI spike)
        i = int(round(start))
        if 0 <= i < len(signal):
            signal[i] += peak_counts
        return
    first = math.floor(start)
    for i in range(first, first + int(math.ceil(n)) + 2):
        t = i - start
        if 0 < t < n and 0 <= i < len(signal):
            signal[i] += peak_counts * math.sin(math.pi * t / n) ** 1.5


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--pulses", type=int, default=40, help="regular Hertz pulses")
    ap.add_argument("--gap", type=int, default=1500, help="quiet samples between pulses")
    ap.add_argument("--lead", type=int, default=4000, help="quiet samples before the first")
    args = ap.parse_args()

    rng = XorShift32(0x5EED_C0A1)
    events = []  # (start sample, peak counts, duration s, label)
    pos = float(args.lead)
    for k in range(args.pulses):
        name, mat = ("coal", COAL) if k % 2 == 0 else ("gangue", SANDSTONE)
        radius = math.exp(math.log(0.015) + rng.uniform() * math.log(0.04 / 0.015))
        speed = 1.0 + 4.0 * rng.uniform()
        force, duration = hertz(mat, radius, speed)
        events.append((pos + rng.uniform(), force / FORCE_PER_COUNT, duration,
                       f"{name} R={radius:.4f} u={speed:.3f}"))
        pos += args.gap
    # Pulses the kernel must reject.
    events.append((pos, 3000.0, 0.5 / FS, "spike"))
    pos += args.gap
    f, d = hertz(COAL, 0.03, 3.0)
    events.append((pos + 0.3, f / FORCE_PER_COUNT, d, "pileup a"))
    events.append((pos + 0.3 + 0.55 * d * FS, 0.8 * f / FORCE_PER_COUNT, d, "pileup b"))
    pos += args.gap
    f, d = hertz(SANDSTONE, 0.04, 5.0)
    events.append((pos + 0.7, 1.6 * f / FORCE_PER_COUNT, d, "saturated"))
    pos += args.gap
    f, d = hertz(COAL, 0.025, 2.0)
    length = int(pos) + int(0.4 * d * FS)  # the stream ends inside this last pulse
    events.append((pos + 0.1, f / FORCE_PER_COUNT, d, "truncated"))

    signal = [0.0] * length
    for start, peak, duration, _ in events:
        add_pulse(signal, start, peak, duration)
    out = bytearray()
    for v in signal:
        c = int(round(DC + v + NOISE_RMS * rng.gauss()))
        out += struct.pack("<h", max(ADC_MIN, min(ADC_MAX, c)))
    with open(args.out, "wb") as fh:
        fh.write(out)
    print(f"{args.out}: {length} samples, {len(events)} events", file=sys.stderr)
    for start, peak, duration, label in events:
        print(f"  at {start:10.1f}  peak {peak:8.0f} counts  {duration * FS:5.1f} samples  {label}",
              file=sys.stderr)


if __name__ == "__main__":
    main()
