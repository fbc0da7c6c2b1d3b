"""Velocities and accelerations from sampled positions: a Savitzky–Golay fit (a polynomial of
degree ``order`` fitted by least squares to ``window`` samples centred on each one), which
is a symmetric FIR filter, hence zero-phase (no lag between q, v, a and the torques
filtered the same way). NumPy only."""

from __future__ import annotations

import math

import numpy as np

from ..errors import InvalidInputError


def savgol(t, x, window: int | None = None, order: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(x, ẋ, ẍ)`` smoothed and differentiated along axis 0 of ``x`` (N, …), sampled at
    uniform times ``t`` (N,). ``window``: odd number of samples (default: about 0.05 s, at
    least ``order + 3``); the first and last ``window // 2`` samples use the fit of the first
    and last window."""
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    n = len(t)
    if t.ndim != 1 or n < 2:
        raise InvalidInputError(f"t: expected a 1-d array of at least 2 times, got shape {t.shape}")
    dt = (t[-1] - t[0]) / (n - 1)
    steps = np.diff(t)
    if not (dt > 0 and np.all(np.abs(steps - dt) <= 1e-6 * dt)):
        raise InvalidInputError(
            f"t: expected uniformly spaced increasing times, got steps from {steps.min():g} to {steps.max():g}"
        )
    if window is None:
        window = max(order + 3, 2 * int(round(0.025 / dt)) + 1)
    window = int(window)
    if window % 2 == 0 or window <= order or window > n:
        raise InvalidInputError(
            f"window: expected an odd number of samples > order ({order}) and <= N ({n}), got {window}"
        )
    h = window // 2
    tau = np.arange(-h, h + 1) * dt
    vander = np.vander(tau, order + 1, increasing=True)
    coef = np.linalg.pinv(vander)  # (order+1, window): polynomial coefficients of a window
    out = []
    for d in range(3):
        # d-th derivative at the centre: d! c_d.
        w = coef[d] * math.factorial(d) if d <= order else np.zeros(window)
        flat = x.reshape(n, -1)
        y = np.empty_like(flat)
        win = np.lib.stride_tricks.sliding_window_view(flat, window, axis=0)  # (n-2h, m, window)
        y[h : n - h] = win @ w
        for lo, idx in ((0, range(h)), (n - window, range(n - h, n))):
            c = coef @ flat[lo : lo + window]  # (order+1, m)
            for i in idx:
                s = (i - lo - h) * dt
                powers = np.array(
                    [math.factorial(k) / math.factorial(k - d) * s ** (k - d) if k >= d else 0.0 for k in range(order + 1)]
                )
                y[i] = powers @ c
        out.append(y.reshape(x.shape))
    return out[0], out[1], out[2]
