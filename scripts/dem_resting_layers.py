#!/usr/bin/env python3
"""Share of a DEM campaign's grains that rest on the mesh rather than only on other grains.

Usage: python3 scripts/dem_resting_layers.py RUN_DIR... (campaign folders of `sawtooth dem
run`, e.g. runs/dem/campaigns/lunar-deep-slow; they hold each run's final.dump).

A grain rests on the mesh when its centre lies within 1.1 radii of the sled's profile (the
mesh's facets in the x-y plane, moved by the stroke v0^2/(2a) along the launch direction,
where the run's stroke left it). What this measures is how many layers a fill forms in the
catches: in a single layer every grain touches the mesh; grains above it landed on grains.
Why it matters: a grain that lands on a resting grain meets a contact normal tilted from
the wall's, which is what the model's impact-scatter candidate draws at random
(docs/diagnosis-report.md, "Lunar DEM campaigns"). Standard library only.
"""
import json
import math
import pathlib
import sys


def profile_segments(stl, offset):
    """The mesh's edges in x-y (the STL extrudes the profile along z), moved by offset."""
    segs, tri = set(), []
    for line in open(stl):
        f = line.split()
        if f and f[0] == "vertex":
            tri.append((float(f[1]) + offset[0], float(f[2]) + offset[1]))
            if len(tri) == 3:
                for i in range(3):
                    a, b = tri[i], tri[(i + 1) % 3]
                    if a != b:
                        segs.add((a, b))
                tri = []
    return list(segs)


def distance(p, a, b):
    dx, dy = b[0] - a[0], b[1] - a[1]
    length2 = dx * dx + dy * dy
    t = 0.0 if length2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / length2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def on_mesh_share(run):
    case = json.load(open(run / "case.json"))
    m = case["motion"]
    stroke = m["v0_m_s"] ** 2 / (2 * m["a_m_s2"])
    segs = profile_segments(run / "sled.stl", (stroke * m["launch"][0], stroke * m["launch"][1]))
    lines = open(run / "final.dump").read().splitlines()
    cols = lines[8].split()[2:]
    ix, iy, idia = cols.index("x"), cols.index("y"), cols.index("diameter")
    grains = [list(map(float, l.split())) for l in lines[9:] if l.strip()]
    on = 0
    for g in grains:
        p, radius = (g[ix], g[iy]), g[idia] / 2
        near = [s for s in segs if min(abs(s[0][0] - p[0]), abs(s[1][0] - p[0])) < 0.01]
        if near and min(distance(p, a, b) for a, b in near) < 1.1 * radius:
            on += 1
    return on / len(grains)


for folder in sys.argv[1:]:
    runs = sorted(pathlib.Path(folder).glob("run-*"))
    shares = [on_mesh_share(r) for r in runs if (r / "final.dump").exists()]
    print(f"{folder}: on the mesh {' '.join(f'{s:.2f}' for s in shares)} (runs in seed order)")
