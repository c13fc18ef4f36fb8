"""Table of `axiscal diagnose` results (out/<case>/diagnosis.json) for the cases in cases.txt.

axiscal writes no member name for a candidate. The member is inferred here:
  * mass model from the parameter names (description masses / + payload offset / lumped);
  * load path for joint 2 (the joint driving the fractional 2->3 coupling): this binary has two
    joint-2 members per mass model; fingerprinted with noise-free truths built on the
    description's own masses (README.md, "Member fingerprints"): the member whose
    outside_refit_fraction is the LOWER of the pair is the actuator spring with the
    parallelogram's virtual-work load ("mechanism": fits a `mechanism` truth exactly), the
    other is the spring in joint 2 itself with the serial load, its sag not driving joint 3
    ("joint spring, serial": fits a truth whose q2 alone sags by tau_2/K exactly).
"""
import json, shlex

def mass_model(params):
    names = [p["name"] for p in params]
    if any("reflected" in n for n in names):
        return "mixed"
    if any("mass_link" in n for n in names):
        return "lumped"
    if any("payload_offset" in n for n in names):
        return "description masses + payload offset"
    return "description masses" if names else "-"

def named_member(d):
    if d["effect"] != "joint_compliance":
        return "-", None
    names = sorted(p["name"] for p in d["parameters"])
    same = [c for c in d["candidates"] if c["effect"] == d["effect"] and c["joint"] == d["joint"]]
    row = next((c for c in same if c["significant"] and "implausible" not in c
                and sorted(p["name"] for p in c["parameters"]) == names), None)
    mm = mass_model(d["parameters"])
    if row is None:
        return mm, None
    if d["joint"] == 2:
        pair = [c for c in same if mass_model(c["parameters"]) == mm]
        low = min(c["outside_refit_fraction"] for c in pair)
        path = ("actuator spring, mechanism load" if row["outside_refit_fraction"] == low and len(pair) > 1
                else "joint spring, serial load")
        return f"{path}; {mm}", row
    return f"serial load; {mm}", row

def main():
    print("| case | generator args | worst sag (mrad) | verdict | joint | confidence | gap before -> after (mm) | member (inferred) | outside refit | fitted stiffness (N m/rad) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for line in open("cases.txt"):
        if not line.strip():
            continue
        name, *args = shlex.split(line)
        d = json.load(open(f"out/{name}/diagnosis.json"))
        gentxt = open(f"cases/{name}.gen.txt").read()
        sag = gentxt.split("sag |max| ")[1].split(" mrad")[0] if "sag |max|" in gentxt else "?"
        p = {q["name"]: q for q in d["parameters"]}
        stiff = (f"{p['stiffness_nm_per_rad']['value']:.3g} +- {p['stiffness_nm_per_rad']['sigma']:.2g}"
                 if "stiffness_nm_per_rad" in p else "-")
        member, row = named_member(d)
        out = f"{row['outside_refit_fraction']:.3f}" if row else "-"
        verdict = d["effect"]
        if d["effect"] == "unexplained":
            best = d["candidates"][0]
            verdict += f" (best: {best['effect']} j{best['joint']}, {mass_model(best['parameters'])}{', implausible' if 'implausible' in best else ''})"
        print(f"| {name} | `{' '.join(args)}` | {sag} | {verdict} | {d['joint'] if d['joint'] is not None else '-'} | "
              f"{d['confidence']:.2f} | {d['gap_before_mm']:.3f} -> {d['gap_after_mm']:.3f} | {member} | {out} | {stiff} |")

if __name__ == "__main__":
    main()
