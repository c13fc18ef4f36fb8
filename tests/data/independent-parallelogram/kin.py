"""Shared kinematics for the independent generator (numpy only).

Written from first principles: classic (standard) Denavit-Hartenberg
  A_k(q_k) = Rz(theta0_k + q_k) Tz(d_k) Tx(a_k) Rx(alpha_k),  joint k about z_{k-1},
frame k rigid with link k.  The phi-model FK below is only used to express points given in
DH link frames in axiscal's phi-model link frames for the description file
(docs/method.md "Phi-model", docs/formats.md "Frames").
"""
import numpy as np

def rz(t):
    c, s = np.cos(t), np.sin(t)
    T = np.eye(4); T[0, 0] = c; T[0, 1] = -s; T[1, 0] = s; T[1, 1] = c
    return T

def rx(t):
    c, s = np.cos(t), np.sin(t)
    T = np.eye(4); T[1, 1] = c; T[1, 2] = -s; T[2, 1] = s; T[2, 2] = c
    return T

def ry(t):
    c, s = np.cos(t), np.sin(t)
    T = np.eye(4); T[0, 0] = c; T[0, 2] = s; T[2, 0] = -s; T[2, 2] = c
    return T

def tr(x, y, z):
    T = np.eye(4); T[:3, 3] = (x, y, z)
    return T

def placement(translation_mm, rpy_deg):
    t_mm = translation_mm
    r, p, y = np.radians(rpy_deg)
    T = rz(y) @ ry(p) @ rx(r)
    T[:3, 3] = np.asarray(t_mm, float) * 1e-3
    return T

def dh_frames(dh, q, world_from_base):
    """dh: list of (d_m, theta0_rad, a_m, alpha_rad). Returns world frames F[0..N]
    (F[0] = DH base frame 0, F[k] = frame of link k)."""
    F = [world_from_base]
    T = world_from_base
    for (d, th0, a, al), qk in zip(dh, q):
        T = T @ rz(th0 + qk) @ tr(0, 0, d) @ tr(a, 0, 0) @ rx(al)
        F.append(T)
    return F

# ---- phi-model (only for converting description coordinates) ----
R0 = np.eye(4)
R0[:3, :3] = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float)  # columns Y_i, Z_i, X_i

def phi_row(a, b, alpha, beta, gamma=0.0, h=0.0):
    return tr(0, 0, a) @ rz(beta) @ tr(b, 0, 0) @ rx(alpha) @ rz(gamma) @ tr(0, 0, h)

def phi_links(phis, rows, world_from_frame1, q):
    """world poses of the phi-model's moving link frames 1..N (list index 0..N-1)."""
    Fk = world_from_frame1
    links = []
    for k, qk in enumerate(q):
        L = Fk @ rz(qk)
        links.append(L)
        if k < len(rows):
            Fk = L @ rz(phis[k]) @ R0 @ phi_row(*rows[k])
    return links
