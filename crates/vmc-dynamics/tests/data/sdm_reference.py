"""Converged first-order semi-discretisation lobes of the Insperger-Stepan 1-DOF benchmark.

An implementation of the first-order semi-discretisation (Insperger & Stepan, 2004) written
apart from the crate's: numpy/scipy, the step means of the directional factor by Gauss-Legendre
quadrature (split at the engagement edges) instead of closed-form integrals, the step
exponentials by scipy's expm of the Van Loan block, the monodromy matrix by propagating all
unit initial states through a ring buffer of delayed samples, the multipliers by LAPACK (numpy
eigvals), and the period started at a tooth's entry instead of at phi = 0. The lowest unstable
depth at each speed: a scan of 200 depths over (0, 20 a_zoa] at a coarse resolution, then a
fine-resolution check of depths under the coarse boundary and a bisection to 1e-7 relative.

Benchmark (machines/benchmarks/insperger-1dof.toml): N = 2 straight teeth, K_t = 6e8 N/m^2,
K_n = 2e8 N/m^2, f_n = 922 Hz, zeta = 0.011, m = 0.03993 kg, flexible in x only. Cases:
slotting (a_e/D = 1) and a_e/D = 0.05 down milling, every 250 rpm from 2000 to 30000 rpm.

Resolution: with c = f_n * tau vibration cycles per tooth period and w the fraction of the
period in which a tooth cuts, M = max(48, 2 ceil(12 c), 2 ceil(48 / w)) steps per tooth period
(about 24 steps per vibration cycle, 96 in the cut); the critical depth is computed at
M/2, M and 2M and extrapolated (Richardson, the O(m^-2) error of the first-order method):
a_ref = a_2M + (a_2M - a_M) / 3. The observed order log2((a_M/2 - a_M) / (a_M - a_2M)) is
written too, as the check that the three levels lie in the asymptotic range.

Run (about 10 minutes on one core):
    python3 -m venv /tmp/pyref && /tmp/pyref/bin/pip install numpy scipy
    OPENBLAS_NUM_THREADS=1 /tmp/pyref/bin/python sdm_reference.py > sdm_reference_1dof.csv
Output columns: immersion, spindle_rpm, steps_m, depth_half_m_mm, depth_m_mm, depth_2m_mm,
observed_order, reference_depth_mm.
"""
import math
import sys

import numpy as np
from scipy.linalg import expm

TEETH = 2
KT, KN = 6.0e8, 2.0e8
FN_HZ, ZETA, MASS_KG = 922.0, 0.011, 0.03993
OMEGA_N = 2 * math.pi * FN_HZ
GL_X, GL_W = np.polynomial.legendre.leggauss(8)


def window(immersion):
    """Down milling: entry arccos(2 a_e/D - 1), exit pi (tooth angle from +y, clockwise)."""
    return math.acos(max(-1.0, min(1.0, 2 * immersion - 1))), math.pi


def hxx(phi, entry, exit_):
    """Directional factor F_x / (a_p dx) summed over the teeth in cut, N/m^2."""
    total = np.zeros_like(phi)
    for j in range(TEETH):
        p = np.mod(phi + 2 * math.pi * j / TEETH, 2 * math.pi)
        inside = (p >= entry) & (p <= exit_)
        s, c = np.sin(p), np.cos(p)
        total += np.where(inside, -(KT * s * c + KN * s * s), 0.0)
    return total


def step_means(m, entry, exit_):
    """Mean of hxx over each of m equal steps of a tooth period (angle 2 pi / N), the period
    starting at the entry angle; each step split at the window edges of every tooth."""
    pitch = 2 * math.pi / TEETH
    edges = []
    for j in range(TEETH):
        for e in (entry, exit_):
            base = e - 2 * math.pi * j / TEETH
            for k in range(-2, 3):
                edges.append(base + 2 * math.pi * k)
    edges = np.array(sorted(edges))
    out = np.empty(m)
    for i in range(m):
        a = entry + pitch * i / m
        b = entry + pitch * (i + 1) / m
        cuts = [a] + [e for e in edges if a < e < b] + [b]
        acc = 0.0
        for u, v in zip(cuts[:-1], cuts[1:]):
            mid, half = 0.5 * (u + v), 0.5 * (v - u)
            # Evaluate just inside the piece so the screen is unambiguous at its edges.
            x = mid + half * GL_X * (1 - 1e-12)
            acc += half * np.dot(GL_W, hxx(x, entry, exit_))
        out[i] = acc / (b - a)
    return out


def step_maps(a_m, h, dt):
    """P, R0, R1 of one step of x' = A x + B q(t - tau) with q(t - tau) linear in the step."""
    a = np.array([[0.0, 1.0], [-OMEGA_N**2 + a_m * h / MASS_KG, -2 * ZETA * OMEGA_N]])
    b = np.array([[0.0], [-a_m * h / MASS_KG]])
    big = np.zeros((4, 4))
    big[:2, :2] = a * dt
    big[:2, 2:3] = b * dt
    big[2, 3] = 1.0
    e = expm(big)
    p, phi0, phi1 = e[:2, :2], e[:2, 2:3], e[:2, 3:4]
    return p, phi0 - phi1, phi1


def spectral_radius(a_mm, means, tau):
    """Largest multiplier modulus of the monodromy matrix at depth a_mm."""
    m = len(means)
    dt = tau / m
    a_m = a_mm * 1e-3
    size = 2 + m
    # State z = [x (2); q_{-m} ... q_{-1}]: column k of the result is the response to unit z_k.
    x = np.zeros((2, size))
    x[0, 0] = x[1, 1] = 1.0
    hist = np.zeros((m, size))  # ring: hist[k] holds the delayed sample q_{k-m} (as rows)
    for k in range(m):
        hist[k, 2 + k] = 1.0
    free = None
    for i in range(m):
        q_now = x[0].copy()
        if means[i] == 0.0:
            if free is None:
                free = expm(np.array([[0.0, 1.0], [-OMEGA_N**2, -2 * ZETA * OMEGA_N]]) * dt)
            x = free @ x
        else:
            p, r0, r1 = step_maps(a_m, means[i], dt)
            older = hist[i]
            newer = hist[i + 1] if i + 1 < m else q_now
            x = p @ x + r0 @ older[None, :] + r1 @ newer[None, :]
        hist[i] = q_now  # q_i replaces q_{i-m}, which no later step reads
    phi = np.vstack([x, hist])
    keep = np.flatnonzero(np.any(phi != 0.0, axis=0))
    reduced = phi[np.ix_(keep, keep)]
    return np.max(np.abs(np.linalg.eigvals(reduced)))


def zoa_minimum_mm(entry, exit_):
    """Zero-order minimum depth (Altintas-Budak, x only): with hbar the mean of hxx over a
    tooth period, a_lim = 1 / (2 hbar Re G) on the side of the resonance where hbar Re G > 0,
    smallest at the extreme of Re G: -1/(4 k zeta (1 + zeta)) or 1/(4 k zeta (1 - zeta))."""
    hbar = float(np.mean(step_means(4000, entry, exit_)))
    k = MASS_KG * OMEGA_N**2
    re_g = -1 / (4 * k * ZETA * (1 + ZETA)) if hbar < 0 else 1 / (4 * k * ZETA * (1 - ZETA))
    return 1e3 / (2 * hbar * re_g)


def lowest_unstable(means, tau, max_mm, coarse=None, scan=400, rel_tol=1e-7):
    """Lowest unstable depth. Without `coarse`: an even scan of `scan` depths over
    (0, max_mm], then bisection. With `coarse` (the boundary at a coarser resolution): the
    depths 0.2, 0.4, 0.6, 0.7, 0.8 and 0.9 of it are checked first and the bracket is the first
    unstable one with the one below it (else [0.9, 1.0] of it, widened upwards)."""
    rho = lambda a: spectral_radius(a, means, tau)
    if coarse is None:
        grid = max_mm * np.arange(1, scan + 1) / scan
    else:
        grid = coarse * np.array([0.2, 0.4, 0.6, 0.7, 0.8, 0.9, 1.0])
    lo, hi = 0.0, None
    for a in grid:
        if rho(a) >= 1.0:
            hi = a
            break
        lo = a
    if hi is None:
        if coarse is None:
            return None
        hi = lo
        while rho(hi) < 1.0:
            lo, hi = hi, hi * 1.05
    while hi - lo > rel_tol * hi:
        mid = 0.5 * (lo + hi)
        if rho(mid) < 1.0:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def main():
    only = [float(v) for v in sys.argv[1:]]
    speeds = only or [2000.0 + 250.0 * i for i in range(113)]
    print("immersion,spindle_rpm,steps_m,depth_half_m_mm,depth_m_mm,depth_2m_mm,"
          "observed_order,reference_depth_mm")
    for immersion in (1.0, 0.05):
        entry, exit_ = window(immersion)
        # The crate's lobes search (0, 20 x the zero-order minimum].
        max_mm = 20 * zoa_minimum_mm(entry, exit_)
        cut_fraction = min(1.0, (exit_ - entry) * TEETH / (2 * math.pi))
        for n in speeds:
            tau = 60.0 / (TEETH * n)
            cycles = FN_HZ * tau
            # About 24 steps per vibration cycle and per cut (at small immersion the cut is a
            # short part of the period and its stiffness a_p h / m raises the frequency in it).
            m = max(48, 2 * math.ceil(12 * cycles), 2 * math.ceil(12 * 4 / cut_fraction))
            coarse = lowest_unstable(step_means(m // 4, entry, exit_), tau, max_mm)
            if coarse is None:
                print(f"{immersion},{n:.0f},{m},,,,,", flush=True)
                continue
            depths = []
            for mm in (m // 2, m, 2 * m):
                means = step_means(mm, entry, exit_)
                depths.append(lowest_unstable(means, tau, max_mm, coarse=coarse))
            a_h, a_m, a_2m = depths
            order = math.log2(abs((a_h - a_m) / (a_m - a_2m)))
            ref = a_2m + (a_2m - a_m) / 3.0
            print(f"{immersion},{n:.0f},{m},{a_h:.9f},{a_m:.9f},{a_2m:.9f},{order:.3f},{ref:.9f}",
                  flush=True)
            print(f"{immersion} {n:.0f} m={m} coarse={coarse:.5f} ref={ref:.6f} p={order:.2f}",
                  file=sys.stderr, flush=True)


if __name__ == "__main__":
    main()
