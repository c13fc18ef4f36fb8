"""The nominal PG arm: DH table, masses, centres of mass, targets -- all in DH link frames.
Single source for mkdesc.py (writes pg-arm.toml) and gen.py (the truth)."""
import numpy as np

NAME = "PG arm (DH, parallelogram 2->3)"
# classic DH: (d_mm, theta0_deg, a_mm, alpha_deg)
DH = [
    (500.0, 0.0, 175.0, -90.0),
    (0.0, -90.0, 900.0, 0.0),
    (0.0, 0.0, 175.0, -90.0),
    (960.0, 0.0, 0.0, 90.0),
    (0.0, 0.0, 0.0, -90.0),
    (135.0, 0.0, 0.0, 0.0),
]
LIMITS = [(-170, 170), (-60, 80), (-100, 60), (-180, 180), (-120, 120), (-300, 300)]
PLACEMENT = dict(translation_mm=[2000.0, 1000.0, 0.0], rpy_deg=[0.0, 0.0, 30.0])  # DH frame 0
TOOL_FRAME = dict(translation_mm=[0.0, 0.0, 150.0], rpy_deg=[0.0, 0.0, 0.0])     # in DH frame 6
TOOL_TARGETS = [[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]]          # in the tool frame
# nominal (description) link masses [kg] and centres of mass [mm] in DH link frames k=1..6
MASS = [150.0, 110.0, 70.0, 35.0, 12.0, 3.0]
COM = [
    [-80.0, 150.0, 0.0],     # turret (frame 1 sits on axis 2)
    [-450.0, 0.0, 80.0],     # upper arm: halfway between axis 2 and axis 3 (frame 2 on axis 3)
    [-80.0, 0.0, 200.0],     # elbow housing + wrist motors (frame 3: z along the forearm)
    [0.0, -400.0, 0.0],      # forearm tube, 400 mm before the wrist centre (frame 4)
    [0.0, 0.0, 40.0],        # wrist
    [0.0, 0.0, -30.0],       # flange
]
REPEATABILITY = 2.0e-5  # rad per joint
# axis-experiment targets: joint -> (link, position in DH link frame [mm]); target1 for joint 2
AXIS_T0 = {1: (6, [60.0, 40.0, 200.0]), 2: (2, [-300.0, 0.0, 150.0]), 3: (6, [60.0, 40.0, 200.0]),
           4: (6, [60.0, 40.0, 200.0]), 5: (6, [60.0, 40.0, 200.0]), 6: (6, [60.0, 40.0, 200.0])}
AXIS_T1 = {2: (6, [0.0, 100.0, 150.0])}
COUPLING_SLOPE = -1.0  # 2 -> 3

def dh_si(dh=DH):
    return [(d * 1e-3, np.radians(t), a * 1e-3, np.radians(al)) for d, t, a, al in dh]
