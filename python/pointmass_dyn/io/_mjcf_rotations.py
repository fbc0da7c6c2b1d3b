"""Rotations between our joints' coordinates and MuJoCo's (quaternions w-first, ZYZ Euler
angles as ball joints), for the MJCF writer and the state conversions of ``_mjcf``."""

from __future__ import annotations

import math

import numpy as np


def quat_wxyz_of(r: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of one rotation matrix (Shepperd's method)."""
    t = np.trace(r)
    if t > 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif r[1, 1] > r[2, 2]:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    q = np.array(q)
    return q / np.linalg.norm(q)


def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product of (w, x, y, z) quaternions, broadcasting."""
    aw, ax, ay, az = np.moveaxis(a, -1, 0)
    bw, bx, by, bz = np.moveaxis(b, -1, 0)
    return np.stack([aw * bw - ax * bx - ay * by - az * bz,
                     aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw], -1)


def zyz_quat(e: np.ndarray) -> np.ndarray:
    """(w, x, y, z) of Rz(φ) Ry(θ) Rz(ψ), for e (..., 3)."""
    phi, th, psi = np.moveaxis(e, -1, 0)
    c, s = np.cos(th / 2), np.sin(th / 2)
    return np.stack([c * np.cos((phi + psi) / 2), -s * np.sin((phi - psi) / 2),
                     s * np.cos((phi - psi) / 2), c * np.sin((phi + psi) / 2)], -1)


def zyz_rate(e: np.ndarray) -> np.ndarray:
    """L(φ, θ) (..., 3, 3): relative angular velocity in the joint frame = L · Euler rates."""
    phi, th = e[..., 0], e[..., 1]
    z, o = np.zeros_like(phi), np.ones_like(phi)
    sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    return np.stack([np.stack([z, -sp, cp * st], -1), np.stack([z, cp, sp * st], -1),
                     np.stack([o, z, ct], -1)], -2)


def zyz_rate_dot(e: np.ndarray, ed: np.ndarray) -> np.ndarray:
    """dL/dt for Euler rates ed."""
    phi, th = e[..., 0], e[..., 1]
    dp, dt = ed[..., 0], ed[..., 1]
    z = np.zeros_like(phi)
    sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    return np.stack([
        np.stack([z, -cp * dp, -sp * st * dp + cp * ct * dt], -1),
        np.stack([z, -sp * dp, cp * st * dp + sp * ct * dt], -1),
        np.stack([z, z, -st * dt], -1)], -2)


def wrap_near(x: np.ndarray, like: np.ndarray) -> np.ndarray:
    return x + 2 * np.pi * np.round((like - x) / (2 * np.pi))


def zyz_of_rot(r: np.ndarray, like: np.ndarray | None) -> np.ndarray:
    """Euler angles of rotations r (..., 3, 3); of the two branches (θ > 0 or θ < 0) and the
    2π-shifts the one nearest ``like`` (default θ ∈ [0, π], φ, ψ ∈ (−π, π])."""
    th = np.arccos(np.clip(r[..., 2, 2], -1.0, 1.0))
    phi = np.arctan2(r[..., 1, 2], r[..., 0, 2])
    psi = np.arctan2(r[..., 2, 1], -r[..., 2, 0])
    if like is None:
        return np.stack([phi, th, psi], -1)
    a = np.stack([wrap_near(phi, like[..., 0]), wrap_near(th, like[..., 1]),
                  wrap_near(psi, like[..., 2])], -1)
    b = np.stack([wrap_near(phi + np.pi, like[..., 0]), wrap_near(-th, like[..., 1]),
                  wrap_near(psi + np.pi, like[..., 2])], -1)
    pick_b = np.sum((b - like) ** 2, -1) < np.sum((a - like) ** 2, -1)
    return np.where(pick_b[..., None], b, a)


def axis_of(d: np.ndarray, angle: float) -> np.ndarray:
    a = np.array([d[2, 1] - d[1, 2], d[0, 2] - d[2, 0], d[1, 0] - d[0, 1]]) / (2 * math.sin(angle))
    return a / np.linalg.norm(a)
