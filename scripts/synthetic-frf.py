#!/usr/bin/env python3
"""Writes machines/benchmarks/frf-example.csv: the receptance of a tool tip with known modes
(x: 3, y: 2), with seeded measurement noise, in the FRF format of `vmc-twin modal-fit`
(docs/file-formats.md). It is an example input, not a measurement: the modes below are what a
fit should give back.

H(f) = sum_k (1/k_k) / (1 - r^2 + 2 i zeta_k r), r = f / f_k (mode shape 1 at the tip, m/N),
plus complex Gaussian noise of 1 % of |H| per component and 0.2 % of the direction's peak
(random.Random(7), Box-Muller by the standard library). Python 3 standard library only.

Usage: python3 scripts/synthetic-frf.py > machines/benchmarks/frf-example.csv
"""

import random
import sys

# (frequency_hz, damping_ratio, stiffness_n_per_m)
MODES = {
    "x": [(650.0, 0.035, 1.8e7), (1450.0, 0.02, 3.0e7), (3150.0, 0.015, 4.5e7)],
    "y": [(680.0, 0.03, 2.0e7), (3100.0, 0.016, 5.0e7)],
}
FREQUENCIES_HZ = [200.0 + 4.0 * i for i in range(951)]  # 200 ... 4000 Hz
SEED = 7


def receptance(modes, f_hz):
    h = 0j
    for fn, zeta, k in modes:
        r = f_hz / fn
        h += 1.0 / (k * complex(1.0 - r * r, 2.0 * zeta * r))
    return h


def main():
    rng = random.Random(SEED)
    clean = {d: [receptance(m, f) for f in FREQUENCIES_HZ] for d, m in MODES.items()}
    peak = {d: max(abs(h) for h in hs) for d, hs in clean.items()}
    out = sys.stdout
    out.write("# Example FRF for `vmc-twin modal-fit`: synthetic, written by scripts/synthetic-frf.py\n")
    for d, modes in MODES.items():
        text = "; ".join(f"{f:g} Hz zeta {z:g} k {k:g} N/m" for f, z, k in modes)
        out.write(f"# {d}: {text}\n")
    out.write("# noise: 1 % of |H| + 0.2 % of the peak per component, seed 7\n")
    out.write("frequency_hz,x_re_m_per_n,x_im_m_per_n,y_re_m_per_n,y_im_m_per_n\n")
    for i, f in enumerate(FREQUENCIES_HZ):
        fields = [f"{f:g}"]
        for d in ("x", "y"):
            h = clean[d][i]
            sigma = 0.01 * abs(h) + 0.002 * peak[d]
            noisy = h + complex(rng.gauss(0.0, sigma), rng.gauss(0.0, sigma))
            fields += [f"{noisy.real:.6e}", f"{noisy.imag:.6e}"]
        out.write(",".join(fields) + "\n")


if __name__ == "__main__":
    main()
