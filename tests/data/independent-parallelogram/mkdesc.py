"""Writes pg-arm.toml from robot.py: the DH table as given, masses/com and targets converted
from DH link frames into axiscal's phi-model link frames (read from `axiscal describe`)."""
import re, subprocess, sys
import numpy as np
import kin, robot

def describe(path):
    out = subprocess.run(["./axiscal", "describe", path], capture_output=True, text=True, check=True).stdout
    phis = [float(m) for m in re.findall(r"phi_deg =\s+(-?[\d.]+)", out)]
    rows, cur = [], None
    for line in out.splitlines():
        if line.startswith("[[rows]]"):
            cur = {}; rows.append(cur)
        m = re.match(r"(a_m|b_m|alpha_deg|beta_deg) = (\S+)", line)
        if m and cur is not None:
            cur[m.group(1)] = float(m.group(2))
    pl = re.search(r"placement: translation_mm = \[(.*?)\], rpy_deg = \[(.*?)\]", out)
    tf = re.search(r"tool.frame: translation_mm = \[(.*?)\], rpy_deg = \[(.*?)\]", out)
    f = lambda s: [float(x) for x in s.split(",")]
    return (np.radians(phis), [(r["a_m"], r["b_m"], np.radians(r["alpha_deg"]), np.radians(r["beta_deg"])) for r in rows],
            kin.placement(f(pl.group(1)), f(pl.group(2))), kin.placement(f(tf.group(1)), f(tf.group(2))))

def fmt(v):
    return "[" + ", ".join(f"{x:.6f}" for x in v) + "]"

def write(path, com_phi=None, t0=None, t1=None):
    L = []
    L.append(f'name = "{robot.NAME}"\ndh_convention = "classic"\n')
    if t0 is None:
        L.append("axis_targets = []\n")
    p = robot.PLACEMENT
    L.append(f"[placement]\ntranslation_mm = {p['translation_mm']}\nrpy_deg = {p['rpy_deg']}\n")
    for k in range(6):
        d, th, a, al = robot.DH[k]
        c = com_phi[k] if com_phi is not None else [0, 0, 0]
        L.append(f'[[joints]]\nkind = "revolute"\nlimits = [{robot.LIMITS[k][0]:.1f}, {robot.LIMITS[k][1]:.1f}]\n'
                 f"mass_kg = {robot.MASS[k]}\ncom_mm = {fmt(c)}   # DH-frame com {robot.COM[k]}\n"
                 f"repeatability_sigma = {robot.REPEATABILITY}   # [rad]\n"
                 f"dh = {{ d_mm = {d}, theta_deg = {th}, a_mm = {a}, alpha_deg = {al} }}\n")
    L.append('[[couplings]]\nfrom = 2\nto = 3\nslope = -1.0   # parallelogram: actuator 3 drives the forearm\'s absolute angle\nfit = { form = "fractional" }\n')
    t = robot.TOOL_FRAME
    L.append(f"[tool]\nframe = {{ translation_mm = {t['translation_mm']}, rpy_deg = {t['rpy_deg']} }}\n"
             f"targets_mm = {robot.TOOL_TARGETS}\n")
    if t0 is not None:
        for j in range(1, 7):
            link, pos = t0[j]
            s = f"[[axis_targets]]\njoint = {j}\ntarget0 = {{ link = {link}, position_mm = {fmt(pos)} }}\n"
            if j in t1:
                s += f"target1 = {{ link = {t1[j][0]}, position_mm = {fmt(t1[j][1])} }}\n"
            L.append(s)
    open(path, "w").write("\n".join(L))

if __name__ == "__main__":
    write("pg-draft.toml")
    phis, rows, w_f1, tool_phi = describe("pg-draft.toml")
    dh = robot.dh_si()
    base = kin.placement(**robot.PLACEMENT)
    tool_dh = kin.placement(**robot.TOOL_FRAME)
    rng = np.random.default_rng(0)
    Ts = []
    for trial in range(20):
        q = np.radians([rng.uniform(*l) for l in robot.LIMITS]) if trial else np.zeros(6)
        F = kin.dh_frames(dh, q, base)
        P = kin.phi_links(phis, rows, w_f1, q)
        T = [np.linalg.inv(P[k]) @ F[k + 1] for k in range(6)]  # phi_link_from_dh_link
        Ts.append(T)
        err_tool = np.abs(P[5] @ tool_phi - F[6] @ tool_dh).max()
        assert err_tool < 1e-9, err_tool
    spread = max(np.abs(Ts[i][k] - Ts[0][k]).max() for i in range(20) for k in range(6))
    print("phi_link_from_dh_link constant over 20 poses: max spread", spread)
    assert spread < 1e-9
    T = Ts[0]
    conv = lambda k, p: (T[k - 1] @ np.r_[np.asarray(p) * 1e-3, 1.0])[:3] * 1e3
    com_phi = [conv(k + 1, robot.COM[k]) for k in range(6)]
    t0 = {j: (l, conv(l, p)) for j, (l, p) in robot.AXIS_T0.items()}
    t1 = {j: (l, conv(l, p)) for j, (l, p) in robot.AXIS_T1.items()}
    write("pg-arm.toml", com_phi, t0, t1)
    np.save("phi_from_dh.npy", np.array(T))
    print("wrote pg-arm.toml")
