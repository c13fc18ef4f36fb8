#!/usr/bin/env python3
"""Independent free-pose test-data generator for a 6R arm with non-geometric effects.

Written from the physics, without axiscal's code. Conventions (see README.md):

* lengths in mm, angles in rad inside; CSV commands in degrees, coordinates in mm;
* classic DH, link i placed in link i-1 by  A_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i),
  joint i turns about the z axis of frame i-1 through its origin; link i is rigid with frame i;
* the base (DH frame 0) stands in the tracker frame at  Trans(t) Rz(yaw) Ry(pitch) Rx(roll);
* the controller reads cmd_i; the truth joint angle is
      q_i = cmd_i + dtheta_i + backlash_i + harmonic_i + compliance_i
  where dtheta_i is the joint's zero offset (the truth DH theta minus the nominal one), so the
  reading is the truth angle minus the zero offset and minus the non-geometric deflections;
* gravity is -z of the robot base frame (DH frame 0), g = 9.80665 m/s^2.

Python 3.11+ (tomllib) and numpy only.
"""
import argparse
import json
import math
import sys
import tomllib

import numpy as np

G = 9.80665  # m/s^2

# ---- mass model (own choice): mass kg, centre of mass in the link's DH frame (mm) ----
LINK_MASS = {2: 40.0, 3: 25.0, 4: 8.0, 5: 3.0, 6: 1.0}
LINK_COM = {
    2: (-340.0, 0.0, -25.0),   # upper arm: mid-way between axis 2 and axis 3 (frame 2 sits on axis 3)
    3: (0.0, -15.0, 180.0),    # elbow housing + forearm tube, 180 mm along axis 4
    4: (0.0, -150.0, 0.0),     # forearm roll part: 150 mm behind the wrist centre (+y4 = axis 4 direction)
    5: (0.0, 0.0, 40.0),       # wrist
    6: (0.0, 0.0, -15.0),      # flange
}
PAYLOAD_COM = (50.0, 0.0, 80.0)  # payload centre of mass in the flange frame (50 mm off the axis)

# ---- targets on the flange (frame 6), mm: 100-150 mm from the flange centre, not collinear ----
TARGETS = np.array([
    [100.0, 0.0, 60.0],
    [-50.0, 90.0, 50.0],
    [-60.0, -85.0, 80.0],
])


# ------------------------------------------------------------------------------------------
# kinematics
# ------------------------------------------------------------------------------------------
def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def placement_matrix(t_mm, rpy_rad):
    m = np.eye(4)
    m[:3, :3] = rot_z(rpy_rad[2]) @ rot_y(rpy_rad[1]) @ rot_x(rpy_rad[0])
    m[:3, 3] = t_mm
    return m


def dh_frames(dh, q):
    """Frames 0..6 of every pose in the base frame: array (P, 7, 4, 4).

    dh: dict of arrays d, theta, a, alpha (mm, rad); q: (P, 6) joint variables (rad)."""
    q = np.atleast_2d(q)
    p = q.shape[0]
    frames = np.empty((p, 7, 4, 4))
    frames[:, 0] = np.eye(4)
    for i in range(6):
        th = q[:, i] + dh["theta"][i]
        ct, st = np.cos(th), np.sin(th)
        ca, sa = math.cos(dh["alpha"][i]), math.sin(dh["alpha"][i])
        a = np.zeros((p, 4, 4))
        a[:, 0, 0] = ct
        a[:, 0, 1] = -st * ca
        a[:, 0, 2] = st * sa
        a[:, 0, 3] = dh["a"][i] * ct
        a[:, 1, 0] = st
        a[:, 1, 1] = ct * ca
        a[:, 1, 2] = -ct * sa
        a[:, 1, 3] = dh["a"][i] * st
        a[:, 2, 1] = sa
        a[:, 2, 2] = ca
        a[:, 2, 3] = dh["d"][i]
        a[:, 3, 3] = 1.0
        frames[:, i + 1] = frames[:, i] @ a
    return frames


def target_points(base, dh, q, targets):
    """Targets in the tracker frame: (P, T, 3) mm."""
    f6 = base[None] @ dh_frames(dh, q)[:, 6]
    return np.einsum("pij,tj->pti", f6[:, :3, :3], targets) + f6[:, None, :3, 3]


# ------------------------------------------------------------------------------------------
# robot description
# ------------------------------------------------------------------------------------------
def read_description(path):
    with open(path, "rb") as f:
        desc = tomllib.load(f)
    if desc.get("dh_convention") != "classic":
        sys.exit(f"{path}: dh_convention must be \"classic\"")
    joints = desc["joints"]
    if len(joints) != 6:
        sys.exit(f"{path}: expected 6 joints")
    dh = {
        "d": np.array([j["dh"]["d_mm"] for j in joints], float),
        "theta": np.radians([j["dh"]["theta_deg"] for j in joints]),
        "a": np.array([j["dh"]["a_mm"] for j in joints], float),
        "alpha": np.radians([j["dh"]["alpha_deg"] for j in joints]),
    }
    limits = np.radians([j["limits"] for j in joints])
    pl = desc.get("placement", {})
    t = np.array(pl.get("translation_mm", [0.0, 0.0, 0.0]), float)
    rpy = np.radians(pl.get("rpy_deg", [0.0, 0.0, 0.0]))
    return desc, dh, limits, t, rpy


# ------------------------------------------------------------------------------------------
# random walk through the joint space
# ------------------------------------------------------------------------------------------
STEP_DEG = np.array([[4, 30], [3, 20], [3, 25], [5, 60], [4, 40], [5, 60]], float)
WALK_RANGE_DEG = np.array([[-170, 170], [-55, 95], [-110, 120], [-180, 180], [-120, 120], [-180, 180]], float)


def walk_ok(dh, q):
    """Keep the wrist centre above the floor plane of the base and away from the column."""
    f = dh_frames(dh, q[None])[0]
    w = f[4, :3, 3]  # wrist centre = origin of frame 4 (= 5)
    flange = f[6, :3, 3]
    return w[2] > 150.0 and flange[2] > 100.0 and math.hypot(w[0], w[1]) > 450.0


def random_walk(rng, dh_nom, limits, n):
    lo = np.maximum(np.radians(WALK_RANGE_DEG[:, 0]), limits[:, 0])
    hi = np.minimum(np.radians(WALK_RANGE_DEG[:, 1]), limits[:, 1])
    q = np.radians([0.0, 20.0, 10.0, 0.0, 40.0, 0.0])
    out = np.empty((n, 6))
    step_lo, step_hi = np.radians(STEP_DEG[:, 0]), np.radians(STEP_DEG[:, 1])
    for i in range(n):
        if i > 0:
            for _ in range(200):
                mag = rng.uniform(step_lo, step_hi)
                sgn = rng.choice([-1.0, 1.0], size=6)
                new = q + sgn * mag
                # a move that would leave the range goes the other way
                flip = (new < lo) | (new > hi)
                new[flip] = q[flip] - sgn[flip] * mag[flip]
                new = np.clip(new, lo, hi)
                if walk_ok(dh_nom, new):
                    break
            else:
                raise RuntimeError("random walk stuck")
            q = new
        out[i] = q
    return out


# ------------------------------------------------------------------------------------------
# effects
# ------------------------------------------------------------------------------------------
def gravity_torques(dh, q, payload_kg):
    """Gravity torques about axes 2 and 3 (N m), by the links they carry.

    Returns dict with
      t2_link2: torque about axis 2 of link 2 alone,
      t2_beyond: torque about axis 2 of links 3..6 + payload,
      t3: torque about axis 3 of links 3..6 + payload.
    Joint j turns about z of frame j-1 through its origin; positive torque turns q_j positively.
    """
    f = dh_frames(dh, q)
    grav = np.array([0.0, 0.0, -G])

    def com_world(link, com):
        return np.einsum("pij,j->pi", f[:, link, :3, :3], np.array(com)) + f[:, link, :3, 3]

    bodies = [(k, LINK_MASS[k], com_world(k, LINK_COM[k])) for k in range(2, 7)]
    if payload_kg > 0:
        bodies.append((7, payload_kg, com_world(6, PAYLOAD_COM)))

    def torque_about(axis_frame, sel):
        z = f[:, axis_frame, :3, 2]
        o = f[:, axis_frame, :3, 3]
        tot = np.zeros(q.shape[0])
        for k, m, c in bodies:
            if sel(k):
                r = (c - o) / 1000.0  # m
                tot += np.einsum("pi,pi->p", z, np.cross(r, m * grav))
        return tot

    return {
        "t2_link2": torque_about(1, lambda k: k == 2),
        "t2_beyond": torque_about(1, lambda k: k >= 3),
        "t3": torque_about(2, lambda k: k >= 3),
    }


def compliance(dh, q, args):
    """Joint deflections (P, 6) rad of the gravity compliance of joints 2 and 3."""
    dq = np.zeros_like(q)
    if args.load_path == "none":
        return dq, None
    t = gravity_torques(dh, q, args.payload)
    k2, k3 = args.stiffness
    balancer = -args.balancer * t["t2_link2"]  # a spring that carries fraction F of link 2's own torque
    if args.load_path == "serial":
        tau2 = t["t2_link2"] + t["t2_beyond"] + balancer
        tau3 = t["t3"]
        dq[:, 1] = tau2 / k2
        dq[:, 2] = tau3 / k3
    else:  # parallelogram: actuator 3 holds the forearm's absolute angle from the base
        tau2 = t["t2_link2"] + balancer
        tau3 = t["t3"]
        dq[:, 1] = tau2 / k2
        dq[:, 2] = tau3 / k3 - dq[:, 1]
    return dq, {"tau2_nm": tau2, "tau3_nm": tau3}


def approach_directions(cmd):
    """Sign of the last move of each joint: cmd(i) - cmd(i-1), the previous sign kept on no move,
    0 at the first pose."""
    dirs = np.zeros_like(cmd)
    for i in range(1, cmd.shape[0]):
        s = np.sign(cmd[i] - cmd[i - 1])
        dirs[i] = np.where(s == 0, dirs[i - 1], s)
    return dirs


def backlash(cmd, halfband):
    """The joint stops short of its command by the half-band: dq = -b * direction."""
    return -approach_directions(cmd) * halfband[None, :]


def harmonic(cmd, specs):
    dq = np.zeros_like(cmd)
    for h in specs:
        j = h["joint"] - 1
        dq[:, j] += h["amplitude_rad"] * np.sin(h["order"] * cmd[:, j] + h["phase_rad"])
    return dq


# ------------------------------------------------------------------------------------------
# geometry-only reference fit (own least squares, optional): what a purely kinematic
# calibration of DH + zero offsets + base + targets leaves of the effects
# ------------------------------------------------------------------------------------------
def pack(dh, t, rpy, targets):
    return np.concatenate([dh["d"], dh["theta"], dh["a"], dh["alpha"], t, rpy, targets.ravel()])


def unpack(x):
    dh = {"d": x[0:6], "theta": x[6:12], "a": x[12:18], "alpha": x[18:24]}
    return dh, x[24:27], x[27:30], x[30:39].reshape(3, 3)


def model_points(x, cmd):
    dh, t, rpy, tg = unpack(x)
    return target_points(placement_matrix(t, rpy), dh, cmd, tg)


def geometric_fit(x0, cmd, meas, iters=12):
    scale = np.concatenate([np.ones(6), np.full(6, 1e-3), np.ones(6), np.full(6, 1e-3),
                            np.ones(3), np.full(3, 1e-3), np.ones(9)])
    x = x0.copy()
    for _ in range(iters):
        r = (meas - model_points(x, cmd)).ravel()
        jac = np.empty((r.size, x.size))
        for k in range(x.size):
            h = 1e-3 * scale[k]  # 1 um, 1 urad
            xp = x.copy()
            xp[k] += h
            xm = x.copy()
            xm[k] -= h
            jac[:, k] = ((model_points(xp, cmd) - model_points(xm, cmd)).ravel()) / (2 * h)
        js = jac * scale[None]
        # truncated SVD: the redundant combinations (d1 with the base height, theta1 with the
        # yaw, d6 with the targets, ...) get no step
        u, sv, vt = np.linalg.svd(js, full_matrices=False)
        keep = sv > 1e-6 * sv[0]
        step = vt[keep].T @ ((u[:, keep].T @ r) / sv[keep])
        x = x + step * scale
        if np.max(np.abs(step)) < 1e-7:
            break
    return x


def rms3(d):
    """3-D RMS of a (..., 3) array of displacements: sqrt(mean |d|^2)."""
    return float(np.sqrt(np.mean(np.sum(d ** 2, axis=-1))))


# ------------------------------------------------------------------------------------------
def parse_backlash(text):
    out = np.zeros(6)
    for item in text.split(","):
        j, b = item.split(":")
        out[int(j) - 1] = float(b) * 1e-3
    return out


def parse_harmonic(text):
    parts = text.split(":")
    if len(parts) not in (3, 4):
        raise argparse.ArgumentTypeError("harmonic is JOINT:ORDER:AMPLITUDE_MRAD[:PHASE_DEG]")
    j, n = int(parts[0]), int(parts[1])
    if not 1 <= j <= 6 or not 1 <= n <= 8:
        raise argparse.ArgumentTypeError("joint 1..6, order 1..8")
    return {"joint": j, "order": n, "amplitude_rad": float(parts[2]) * 1e-3,
            "phase_rad": math.radians(float(parts[3])) if len(parts) == 4 else 0.5}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--robot", default="/work/gen/kr-arm.toml", help="nominal description (classic DH TOML)")
    ap.add_argument("--out", required=True, help="measurement CSV to write")
    ap.add_argument("--truth", help="truth JSON (default: OUT with .truth.json)")
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--poses", type=int, default=600)
    ap.add_argument("--experiment", default="poses")
    ap.add_argument("--noise", type=float, default=0.02, help="Gaussian sigma per coordinate, mm")
    ap.add_argument("--no-perturb", action="store_true", help="truth = nominal geometry and placement")
    ap.add_argument("--sigma-length", type=float, default=0.3, help="DH d, a sigma, mm")
    ap.add_argument("--sigma-angle", type=float, default=0.3, help="DH alpha, theta (zero offset) sigma, mrad")
    ap.add_argument("--sigma-base-mm", type=float, default=3.0)
    ap.add_argument("--sigma-base-mrad", type=float, default=2.0)
    ap.add_argument("--load-path", choices=["none", "serial", "parallelogram"], default="none")
    ap.add_argument("--balancer", type=float, default=0.0, help="fraction of link 2's own torque a spring balancer carries")
    ap.add_argument("--stiffness", type=lambda s: [float(v) for v in s.split(",")], default=[1.25e6, 5.0e5],
                    help="k2,k3 in N m/rad (default 1.25e6,5e5)")
    ap.add_argument("--payload", type=float, default=10.0, help="payload kg (compliance only)")
    ap.add_argument("--payload-column", action="store_true", help="write the payload_kg column")
    ap.add_argument("--backlash", nargs="?", const="1:0.15,2:0.10,3:0.05", default=None,
                    help="J:HALFBAND_MRAD,... (bare flag: 1:0.15,2:0.10,3:0.05)")
    ap.add_argument("--harmonic", type=parse_harmonic, action="append", default=[],
                    help="JOINT:ORDER:AMPLITUDE_MRAD[:PHASE_DEG] (repeatable; phase default 28.6 deg)")
    ap.add_argument("--geometric-fit", action="store_true",
                    help="also run an own geometry-only calibration (even poses) and report its held-out RMS")
    args = ap.parse_args()
    if args.balancer and args.load_path == "none":
        ap.error("--balancer needs --load-path serial or parallelogram")
    truth_path = args.truth or (args.out[:-4] if args.out.endswith(".csv") else args.out) + ".truth.json"

    desc, dh_nom, limits, t_nom, rpy_nom = read_description(args.robot)
    rng = np.random.default_rng(args.seed)

    # 1. truth geometry (draws made whatever the flags, so files of one seed share them)
    dd = rng.normal(0, args.sigma_length, 6)
    da = rng.normal(0, args.sigma_length, 6)
    dalpha = rng.normal(0, args.sigma_angle * 1e-3, 6)
    dtheta = rng.normal(0, args.sigma_angle * 1e-3, 6)
    dt = rng.normal(0, args.sigma_base_mm, 3)
    drpy = rng.normal(0, args.sigma_base_mrad * 1e-3, 3)
    if args.no_perturb:
        dd[:] = da[:] = dalpha[:] = dtheta[:] = dt[:] = drpy[:] = 0.0
    dh_true = {"d": dh_nom["d"] + dd, "theta": dh_nom["theta"] + dtheta,
               "a": dh_nom["a"] + da, "alpha": dh_nom["alpha"] + dalpha}
    t_true, rpy_true = t_nom + dt, rpy_nom + drpy
    base_true = placement_matrix(t_true, rpy_true)

    # 2. commands: random walk in measuring order
    cmd = random_walk(rng, dh_nom, limits, args.poses)
    noise = rng.normal(0, 1, (args.poses, 3, 3)) * args.noise

    # 3. effects on the true joint angle
    halfband = parse_backlash(args.backlash) if args.backlash else np.zeros(6)
    dq_back = backlash(cmd, halfband)
    dq_harm = harmonic(cmd, args.harmonic)
    q_pre = cmd + dq_back + dq_harm  # joint variable added to the truth DH theta (zero offset inside)
    dq_comp, torques = compliance(dh_true, q_pre, args)
    q_true = q_pre + dq_comp

    pts_rigid = target_points(base_true, dh_true, cmd, TARGETS)
    pts_true = target_points(base_true, dh_true, q_true, TARGETS)
    meas = pts_true + noise

    def part(dq):
        return target_points(base_true, dh_true, cmd + dq, TARGETS) - pts_rigid

    disp_comp = target_points(base_true, dh_true, q_pre, TARGETS)
    disp_comp = pts_true - disp_comp
    disp_back = part(dq_back)
    disp_harm = part(dq_harm)
    flange_sag = (dh_frames(dh_true, q_true)[:, 6, :3, 3] - dh_frames(dh_true, q_pre)[:, 6, :3, 3])

    # 4. CSV
    cmd_deg = np.degrees(cmd)
    with open(args.out, "w") as f:
        f.write(f"# freepose_gen.py seed={args.seed} poses={args.poses} noise_mm={args.noise} "
                f"load_path={args.load_path} balancer={args.balancer} backlash={args.backlash} "
                f"harmonic={[(h['joint'], h['order'], h['amplitude_rad']) for h in args.harmonic]} "
                f"perturbed={not args.no_perturb}\n")
        cols = ["experiment", "moved_joint", "step", "target", "x_mm", "y_mm", "z_mm"] + [f"cmd_{k}" for k in range(1, 7)]
        if args.payload_column:
            cols.append("payload_kg")
        f.write(",".join(cols) + "\n")
        for i in range(args.poses):
            for t in range(3):
                row = [args.experiment, "0", str(i), str(t)] + [repr(float(v)) for v in meas[i, t]] \
                    + [repr(float(v)) for v in cmd_deg[i]]
                if args.payload_column:
                    row.append(repr(float(args.payload)))
                f.write(",".join(row) + "\n")

    summary = {
        "noise_sigma_per_coordinate_mm": args.noise,
        "noise_rms_3d_mm": args.noise * math.sqrt(3),
        "noise_rms_3d_realised_mm": rms3(noise),
        "compliance_rms_3d_mm": rms3(disp_comp),
        "backlash_rms_3d_mm": rms3(disp_back),
        "harmonic_rms_3d_mm": rms3(disp_harm),
        "effects_total_rms_3d_mm": rms3(pts_true - pts_rigid),
        "flange_sag_mm": {"min": float(np.min(np.linalg.norm(flange_sag, axis=1))),
                          "max": float(np.max(np.linalg.norm(flange_sag, axis=1))),
                          "rms": rms3(flange_sag)},
    }
    if args.geometric_fit:
        x0 = pack(dh_nom, t_nom, rpy_nom, TARGETS + np.array([0.0, 0.0, 0.0]))
        ev, od = slice(0, None, 2), slice(1, None, 2)
        x = geometric_fit(x0, cmd[ev], meas[ev])
        summary["own_geometric_fit"] = {
            "train_rms_3d_mm": rms3(meas[ev] - model_points(x, cmd[ev])),
            "heldout_rms_3d_mm": rms3(meas[od] - model_points(x, cmd[od])),
            "heldout_rms_3d_noise_free_mm": rms3(pts_true[od] - model_points(x, cmd[od])),
        }

    truth = {
        "generator": "freepose_gen.py",
        "args": {k: v for k, v in vars(args).items() if k != "harmonic"},
        "conventions": {
            "dh": "classic: A_i = Rz(theta_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)",
            "placement": "base (DH frame 0) in tracker frame = Trans(t) Rz(yaw) Ry(pitch) Rx(roll)",
            "joint": "q_true_i = cmd_i + backlash_i + harmonic_i + compliance_i, added to the truth theta_i "
                     "(= nominal theta_i + zero offset)",
            "gravity": "-z of the robot base frame, 9.80665 m/s^2",
            "rms": "3-D RMS over all points: sqrt(mean |d|^2)",
        },
        "nominal_description": args.robot,
        "truth_dh": [{"d_mm": float(dh_true["d"][i]), "theta_deg": math.degrees(dh_true["theta"][i]),
                      "a_mm": float(dh_true["a"][i]), "alpha_deg": math.degrees(dh_true["alpha"][i])}
                     for i in range(6)],
        "perturbation": {"d_mm": dd.tolist(), "a_mm": da.tolist(), "alpha_rad": dalpha.tolist(),
                         "zero_offset_rad": dtheta.tolist()},
        "placement": {"translation_mm": t_true.tolist(), "rpy_deg": np.degrees(rpy_true).tolist(),
                      "delta_translation_mm": dt.tolist(), "delta_rpy_rad": drpy.tolist()},
        "targets_flange_mm": TARGETS.tolist(),
        "effects": {
            "load_path": args.load_path, "balancer_fraction": args.balancer,
            "stiffness_nm_per_rad": {"k2": args.stiffness[0], "k3": args.stiffness[1]},
            "payload_kg": args.payload, "payload_com_flange_mm": list(PAYLOAD_COM),
            "link_mass_kg": {str(k): v for k, v in LINK_MASS.items()},
            "link_com_mm": {str(k): list(v) for k, v in LINK_COM.items()},
            "backlash_halfband_rad": halfband.tolist(),
            "harmonics": args.harmonic,
        },
        "summary": summary,
        "per_pose": {
            "flange_sag_mm": np.linalg.norm(flange_sag, axis=1).tolist(),
            "flange_sag_z_mm": flange_sag[:, 2].tolist(),
            "compliance_dq_rad": dq_comp[:, 1:3].tolist(),
            "backlash_direction": approach_directions(cmd)[:, :3].tolist(),
        },
    }
    with open(truth_path, "w") as f:
        json.dump(truth, f, indent=1)

    print(f"wrote {args.out} ({args.poses} poses x 3 targets) and {truth_path}")
    for k, v in summary.items():
        print(f"  {k}: {v}")


if __name__ == "__main__":
    main()
