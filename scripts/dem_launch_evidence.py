"""Per-grain launch evidence of a DEM case made by scripts/dem-launch-evidence.sh: speed and
direction after the stroke by depth below the fill's free surface, and end positions by depth,
the DEM's grains beside the model's particles (the case's own `model-trajectories.csv`)."""
import json, math, sys

import numpy as np

d = sys.argv[1]
case = json.load(open(f"{d}/case.json"))
des = case["design"]
L = case["launch_angle_rad"]
g = case["scenario"]["environment"]["g"]
# the fill's free surface: the direction of the effective acceleration + 90 deg + AOR
# (src/model/fill.rs `fill_surface_angle`, erratum 21)
geff = (-des["a"] * math.cos(L), -des["a"] * math.sin(L) - g)
beta = math.atan2(geff[1], geff[0]) + math.pi / 2 + math.radians(case["scenario"]["material"]["aor_deg"])


def depth_of(p):
    """Depth below the topmost point's surface line, m."""
    sd = p[:, 0] * math.sin(beta) - p[:, 1] * math.cos(beta)
    top = sd.max() if np.mean(sd < sd.max()) > 0.5 else sd.min()
    return np.abs(sd - top)


def frames_of(path):
    lines = open(path).read().split("\n")
    out, i = [], 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step, n = int(lines[i + 1]), int(lines[i + 3])
            cols = lines[i + 8].split()[2:]
            rows = np.array([list(map(float, l.split())) for l in lines[i + 9:i + 9 + n]])
            out.append((step, cols, rows[np.argsort(rows[:, cols.index("id")])]))
            i += 9 + n
        else:
            i += 1
    return out


frames = frames_of(f"{d}/traj.dump")
cols = frames[0][1]
x, y, vx, vy = (cols.index(c) for c in ("x", "y", "vx", "vy"))
dt = case["contact"]["timestep_s"]
t = np.array([(s - frames[0][0]) * dt for s, _, _ in frames])
start = frames[0][2][:, [x, y]]
depth = depth_of(start)
t_still = des["v0"] / des["a"]
q = np.quantile(depth, [0, 0.2, 0.4, 0.6, 0.8, 1.0])
print(f"{len(depth)} grains, fill depth {depth.max() * 1e3:.2f} mm; launch {math.degrees(L):.1f} deg at {des['v0']} m/s")
print("speed (m/s) and direction (deg) by depth fifth (shallowest first), t after the stroke ends")
for lag in [0.002, 0.010, 0.020, 0.030, 0.040]:
    k = int(np.argmin(np.abs(t - (t_still + lag))))
    f = frames[k][2]
    sp, ang = np.hypot(f[:, vx], f[:, vy]), np.degrees(np.arctan2(f[:, vy], f[:, vx]))
    row = [f"{sp[m].mean():.3f}±{sp[m].std():.3f} {ang[m].mean():5.1f}" for m in ((depth >= lo) & (depth <= hi) for lo, hi in zip(q[:-1], q[1:]))]
    print(f"  +{lag * 1e3:4.0f} ms: " + " | ".join(row))
_, fcols, fin = frames_of(f"{d}/final.dump")[0]
stroke = des["v0"] ** 2 / (2 * des["a"])
end_x = fin[:, fcols.index("x")] - stroke * math.cos(L)  # in the frame the stroke left the mesh in
m = np.genfromtxt(f"{d}/model-trajectories.csv", delimiter=",", names=True, dtype=None, encoding=None)
ms, me = [], []
for p in np.unique(m["particle"]):
    r = m[m["particle"] == p]
    ms.append([r["x_m"][0], r["y_m"][0]])
    me.append(r["x_m"][-1] if r["state"][-1] != "lost" else np.nan)
ms, me = np.array(ms), np.array(me)
md = depth_of(ms)
print("end x (mm) by relative depth: DEM mean sd (n) | model mean sd (n)")
for lo, hi in [(0, 1 / 3), (1 / 3, 2 / 3), (2 / 3, 1.01)]:
    a = (depth / depth.max() >= lo) & (depth / depth.max() < hi)
    b = (md / md.max() >= lo) & (md / md.max() < hi)
    print(f"  {lo:.2f}-{hi:.2f}: DEM {np.nanmean(end_x[a]) * 1e3:6.1f} {np.nanstd(end_x[a]) * 1e3:5.1f} ({a.sum()}) | "
          f"model {np.nanmean(me[b]) * 1e3:6.1f} {np.nanstd(me[b]) * 1e3:5.1f} ({b.sum()})")
ok = ~np.isnan(me)
print(f"corr(depth, end x): DEM {np.corrcoef(depth, end_x)[0, 1]:.2f}, model {np.corrcoef(md[ok], me[ok])[0, 1]:.2f}")
