#!/usr/bin/env python3
"""Independent measurement-campaign generator for the PG arm (pg-arm.toml).

Physics and conventions (see README.md):
  * truth kinematics: classic DH (robot.py) with small errors drawn from a FIXED truth seed
    (TRUTH_SEED, the same robot for every case), base placement and tool-frame errors;
  * controller (docs/formats.md "Controller semantics"): u1 = cmd1, u2 = cmd2,
    u3 = cmd3 - slope*u2 = cmd3 + cmd2 (slope -1), u4..u6 = cmd4..cmd6;
    actuator displacement  th_k = u_k - offset_k  (identity transmissions);
    joint values           q_k  = th_k, except q3 = th3 + g(th2), g(t) = -t (exact parallelogram);
  * gravity compliance at ONE actuator (joint 2's, or 3's for case joint3): static equilibrium
    d = tau_act(q(th + d e_k)) / K_k, iterated to convergence (fixed point, |change| < 1e-14 rad);
    the sag d is an actuator displacement, so for actuator 2 it moves q2 by d and q3 by -d
    (the forearm keeps its absolute angle);
  * load paths (tau about a joint axis = z_axis . sum (c - o) x m g, g = (0,0,-9.81) m/s^2 in the
    instrument frame, c the centres of mass of the truth's links and the payload):
      serial            tau_act2 = tau_2  (links 2..6 + payload about axis 2, forearm included)
      mechanism         tau_act2 = tau_2 + slope*tau_3 = tau_2 - tau_3 (virtual work of the parallelogram)
      serial+balancer   tau_act2 = tau_2 - f * tau_2(link 2 alone)
      joint3            tau_act3 = tau_3  (links 3..6 + payload about axis 3), q3 += d
      none              no sag
  * repeatability: each joint value gets a fresh N(0, REPEAT_SIGMA) error whenever its
    actuator command u_k changes between consecutive poses (held actuators keep theirs);
  * measurement: isotropic Gaussian noise, --noise-mm per coordinate, instrument frame.
Commands of the axis experiments and the tool observation come from `axiscal plan`
(plan.csv); validation poses are drawn here (uniform in 90 % of each joint's range, payload
per pose from {0, 5, 10, 15, 20} kg at PAYLOAD_COM_TOOL_MM in the tool frame, 20 deg C).
"""
import argparse, csv, sys
import numpy as np
import kin, robot

TRUTH_SEED = 20240607
REPEAT_SIGMA = robot.REPEATABILITY
PAYLOAD_COM_TOOL_MM = [30.0, 0.0, 80.0]
G = np.array([0.0, 0.0, -9.81])


def make_truth(seed=TRUTH_SEED, nominal=False):
    r = np.random.default_rng(seed)
    t = {}
    dh = []
    for d, th, a, al in robot.DH:
        if nominal:
            dh.append((d, th, a, al)); continue
        e = np.clip(r.normal(0, 0.3, 4), -0.6, 0.6)  # mm, mrad, mm, mrad
        dh.append((d + e[0], th + np.degrees(e[1] * 1e-3), a + e[2], al + np.degrees(e[3] * 1e-3)))
    t["dh"] = robot.dh_si(dh)
    t["dh_file"] = dh
    p = dict(robot.PLACEMENT)
    tf = dict(robot.TOOL_FRAME)
    if not nominal:
        p = dict(translation_mm=list(np.add(p["translation_mm"], r.normal(0, 2.0, 3))),
                 rpy_deg=list(np.add(p["rpy_deg"], np.degrees(r.normal(0, 1e-3, 3)))))
        tf = dict(translation_mm=list(np.add(tf["translation_mm"], r.normal(0, 0.5, 3))),
                  rpy_deg=list(np.add(tf["rpy_deg"], np.degrees(r.normal(0, 2e-3, 3)))))
    t["base"] = kin.placement(**p)
    t["tool"] = kin.placement(**tf)
    t["offset"] = np.zeros(6) if nominal else r.normal(0, 3e-3, 6)  # transducer zero offsets [rad]
    # truth masses: description's times a factor 0.5-0.8 or 1.2-1.5 (20-50 % off)
    up, lo, heavier = r.uniform(1.2, 1.5, 6), r.uniform(0.5, 0.8, 6), r.random(6) < 0.5
    fac = np.where(heavier, up, lo)
    t["mass"] = np.array(robot.MASS) * (np.ones(6) if nominal else fac)
    t["com"] = [np.asarray(c) * 1e-3 for c in robot.COM]
    return t


def joint_values(th):
    q = np.array(th, float)
    q[2] = th[2] + robot.COUPLING_SLOPE * th[1]  # exact parallelogram g(t) = -t
    return q


def frames(t, q):
    F = kin.dh_frames(t["dh"], q, t["base"])
    return F, F[6] @ t["tool"]


def torques(t, q, payload):
    """tau_2 (links 2..6 + payload about axis 2), tau_3 (links 3..6 + payload about axis 3),
    tau_2 of link 2 alone."""
    F, T = frames(t, q)
    loads = []  # (link index 1..7 (7 = payload), com world, mass)
    for k in range(1, 7):
        loads.append((k, (F[k] @ np.r_[t["com"][k - 1], 1])[:3], t["mass"][k - 1]))
    if payload > 0:
        loads.append((7, (T @ np.r_[np.asarray(PAYLOAD_COM_TOOL_MM) * 1e-3, 1])[:3], payload))

    def about(j, links):  # joint j rotates about z of F[j-1]
        o, z = F[j - 1][:3, 3], F[j - 1][:3, 2]
        return sum(z @ np.cross(c - o, m * G) for k, c, m in loads if k in links)
    return about(2, range(2, 8)), about(3, range(3, 8)), about(2, [2])


def sag_joint_values(t, th, payload, case, K2, K3, f):
    if case == "none":
        return joint_values(th), 0.0
    k = 2 if case == "joint3" else 1  # 0-based actuator index
    K = K3 if case == "joint3" else K2
    d = 0.0
    for _ in range(100):
        tha = np.array(th, float); tha[k] += d
        q = joint_values(tha)
        if case == "serial-jointspring":
            q = joint_values(th); q[1] += d
        t2, t3, t2own = torques(t, q, payload)
        tau = {"serial": t2, "serial-jointspring": t2, "mechanism": t2 + robot.COUPLING_SLOPE * t3,
               "serial+balancer": t2 - f * t2own, "joint3": t3}[case]
        dn = tau / K
        if abs(dn - d) < 1e-14:
            d = dn; break
        d = dn
    if case == "serial-jointspring":  # spring in joint 2 itself: q2 moves, q3 does not (forearm turns)
        q = joint_values(th); q[1] += d
        return q, d
    tha = np.array(th, float); tha[k] += d
    return joint_values(tha), d


def point(t, q, kind, target):
    F, T = frames(t, q)
    if kind == "tool":
        p = np.asarray(robot.TOOL_TARGETS[target]) * 1e-3
        return (T @ np.r_[p, 1])[:3]
    link, pos = kind
    return (F[link] @ np.r_[np.asarray(pos) * 1e-3, 1])[:3]


def read_plan(path):
    hdr_comment = None
    rows = []
    with open(path) as fh:
        lines = [l for l in fh]
    for l in lines:
        if l.startswith("# axiscal.description"):
            hdr_comment = l.rstrip("\n")
    body = [l for l in lines if not l.startswith("#")]
    for r in csv.DictReader(body):
        if r["experiment"] == "validation":
            continue
        rows.append(r)
    return hdr_comment, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--case", required=True, choices=["none", "serial", "mechanism", "serial+balancer", "joint3", "serial-jointspring"])
    ap.add_argument("--k2", type=float, default=1e6, help="actuator-2 stiffness [N m/rad]")
    ap.add_argument("--k3", type=float, default=1e6, help="actuator-3 stiffness [N m/rad] (case joint3)")
    ap.add_argument("--f", type=float, default=0.7, help="balancer fraction of link 2's own torque")
    ap.add_argument("--seed", type=int, default=1, help="noise, jitter, validation poses and payloads")
    ap.add_argument("--out", required=True)
    ap.add_argument("--plan", default="plan.csv")
    ap.add_argument("--validation-poses", type=int, default=100)
    ap.add_argument("--noise-mm", type=float, default=0.05, help="per coordinate")
    ap.add_argument("--no-repeatability", action="store_true")
    ap.add_argument("--nominal", action="store_true", help="error-free truth, no noise (convention check)")
    ap.add_argument("--desc-masses", action="store_true",
                    help="truth uses the description's masses and the payload at the tool frame origin (member fingerprinting)")
    a = ap.parse_args()

    t = make_truth(nominal=a.nominal)
    if a.desc_masses:
        global PAYLOAD_COM_TOOL_MM
        t["mass"] = np.array(robot.MASS, float)
        PAYLOAD_COM_TOOL_MM = [0.0, 0.0, 0.0]
    rng = np.random.default_rng(a.seed)
    hdr, plan = read_plan(a.plan)
    ncmd = 6
    # poses in order: (experiment, moved_joint, step, [(target, kind)], cmd strings, payload)
    poses = []
    for r in plan:
        key = (r["experiment"], r["step"])
        tgt = int(r["target"])
        if r["experiment"] == "tool":
            kind = "tool"
        else:
            j = int(r["moved_joint"])
            kind = robot.AXIS_T0[j] if tgt == 0 else robot.AXIS_T1[j]
        if poses and poses[-1][0] == r["experiment"] and poses[-1][2] == r["step"]:
            poses[-1][3].append((tgt, kind))
        else:
            poses.append([r["experiment"], r["moved_joint"], r["step"], [(tgt, kind)],
                          [r[f"cmd_{k}"] for k in range(1, ncmd + 1)], 0.0])
    lim = np.array(robot.LIMITS, float)
    mid, half = lim.mean(1), 0.45 * (lim[:, 1] - lim[:, 0])
    for s in range(a.validation_poses):
        c = mid + half * rng.uniform(-1, 1, 6)
        poses.append(["validation", "0", str(s), [(0, "tool"), (1, "tool"), (2, "tool")],
                      [f"{x:.6f}" for x in c], float(rng.choice([0.0, 5.0, 10.0, 15.0, 20.0]))])

    out = open(a.out, "w")
    if hdr:
        out.write(hdr + "\n")
    out.write(f"# generated by gen.py --case {a.case} --k2 {a.k2:g} --k3 {a.k3:g} --f {a.f:g} --seed {a.seed}"
              f" (truth seed {TRUTH_SEED}, noise {a.noise_mm} mm per coordinate)\n")
    out.write("experiment,moved_joint,step,target,x_mm,y_mm,z_mm," +
              ",".join(f"cmd_{k}" for k in range(1, 7)) + ",payload_kg,temperature_c\n")
    prev_u = None
    jitter = np.zeros(6)
    sags = []
    for exp, mj, step, targets, cmds, payload in poses:
        cmd = np.radians([float(x) for x in cmds])
        u = cmd.copy()
        u[2] = cmd[2] - robot.COUPLING_SLOPE * u[1]
        if not (a.no_repeatability or a.nominal):
            moved = np.ones(6, bool) if prev_u is None else np.abs(u - prev_u) > 1e-12
            jitter[moved] = rng.normal(0, REPEAT_SIGMA, moved.sum())
        prev_u = u
        th = u - t["offset"]
        q, d = sag_joint_values(t, th, payload, a.case, a.k2, a.k3, a.f)
        sags.append((d, exp))
        if not a.nominal:
            q = q + jitter
        for tgt, kind in targets:
            p = point(t, q, kind, tgt) * 1e3
            if not a.nominal:
                p = p + rng.normal(0, a.noise_mm, 3)
            out.write(f"{exp},{mj},{step},{tgt},{p[0]:.6f},{p[1]:.6f},{p[2]:.6f},{','.join(cmds)},{payload:g},20\n")
    out.close()
    ds = np.array([s for s, _ in sags])
    dv = np.array([s for s, e in sags if e == "validation"])
    print(f"{a.out}: {len(poses)} poses; sag |max| {np.abs(ds).max()*1e3:.3f} mrad "
          f"(validation: max {np.abs(dv).max()*1e3:.3f}, rms {np.sqrt((dv**2).mean())*1e3:.3f} mrad)", file=sys.stderr)


if __name__ == "__main__":
    main()
