"""Reference values for the control module's tests (vmc-dynamics/src/control).

Run: python3 -m venv /tmp/pc && /tmp/pc/bin/pip install control scipy
     /tmp/pc/bin/python control_reference.py
The printed numbers are stored in the Rust tests (lqg.rs, hinf.rs, pade.rs).
"""
import numpy as np
import control as ct

np.set_printoptions(precision=17)

# Two-mode oscillator (modes 1 and 3 rad/s, damping 0.05, 0.02), force input, position output.
w1, w2, z1, z2 = 1.0, 3.0, 0.05, 0.02
A = np.array([
    [0, 0, 1, 0],
    [0, 0, 0, 1],
    [-w1**2, 0, -2*z1*w1, 0],
    [0, -w2**2, 0, -2*z2*w2],
])
B = np.array([[0], [0], [1], [0.5]])
C = np.array([[1.0, 1.0, 0, 0]])
Q = C.T @ C * 10.0
R = np.array([[0.1]])
K, X, _ = ct.lqr(A, B, Q, R)
print("lqr K", repr(K.ravel()))
W = np.array([[2.0]])
V = np.array([[0.01]])
L, P, _ = ct.lqe(A, B, C, W, V)
print("kalman L", repr(L.ravel()))
# H-infinity norm of the plant force -> position.
sys = ct.ss(A, B, C, 0)
print("hinf norm", ct.norm(sys, p="inf"))
# Pade approximations of exp(-s) and their phase at omega = 1.
for n in (1, 2, 3, 4):
    num, den = ct.pade(1.0, n)
    g = np.polyval(num, 1j) / np.polyval(den, 1j)
    print("pade", n, "num", repr(np.array(num)), "den", repr(np.array(den)),
          "phase", np.angle(g))
