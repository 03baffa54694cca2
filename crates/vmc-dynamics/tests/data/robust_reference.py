"""Reference stability of the blade's perturbed control loops (vmc-dynamics/src/control/robust.rs).

Independent of the Rust code: python-control discretises the perturbed plant (A, B_u, C_y)
and the controller with a zero-order hold, closes the sampled loop with one sample of
computation delay (state [x; x_K; u held]) and reports its spectral radius; it also closes
the continuous loop with python-control's order-2 Pade approximation of the 2-sample lag and
reports whether every pole lies in the left half-plane.

Run (python-control 0.10.2, scipy):
    python3 -m venv /tmp/pc && /tmp/pc/bin/pip install control scipy
    VMC_ROBUST_DUMP=/tmp/loops.json cargo test -p vmc-dynamics --release -- --ignored dump
    /tmp/pc/bin/python robust_reference.py /tmp/loops.json > robust_reference.csv
"""
import json
import sys

import numpy as np
import control as ct

print("# python-control", ct.__version__, "- made by robust_reference.py")
print("controller,case,sampled_spectral_radius,continuous_stable")
for item in json.load(open(sys.argv[1])):
    ts = 1.0 / item["rate_hz"]
    a, b, c = (np.array(item[k]) for k in ("a", "b", "c"))
    ka, kb, kc, kd = (np.array(item[k]) for k in ("ka", "kb", "kc", "kd"))
    plant = ct.ss(a, b, c, np.zeros((1, 1)))
    ctrl = ct.ss(ka, kb, kc, kd)
    pd = ct.c2d(plant, ts, method="zoh")
    kdsc = ct.c2d(ctrl, ts, method="zoh")
    n, nk = pd.A.shape[0], kdsc.A.shape[0]
    m = np.zeros((n + nk + 1, n + nk + 1))
    m[:n, :n] = pd.A
    m[:n, n + nk:] = pd.B
    m[n:n + nk, :n] = kdsc.B @ pd.C
    m[n:n + nk, n:n + nk] = kdsc.A
    m[n + nk:, :n] = kdsc.D @ pd.C
    m[n + nk:, n:n + nk] = kdsc.C
    rho = max(abs(np.linalg.eigvals(m)))
    num, den = ct.pade(2.0 * ts, 2)
    lag = ct.tf2ss(ct.tf(num, den))
    loop = ct.feedback(plant, ct.series(ctrl, lag), sign=1)
    stable = bool(np.all(np.real(loop.poles()) < 0.0))
    print(f'{item["controller"]},{item["case"]},{rho:.12f},{str(stable).lower()}')
