#!/usr/bin/env python3
"""Writes a random scene (schemas/environment.schema.json) where planning matters, from a seed:

  clutter  the bundled table with 4-8 boxes and cylinders of 5-30 cm on it, sometimes a board
           above it on two posts;
  shelf    a shelf of 2-3 levels and 2-3 compartments per level in front of the robot;
  opening  a wall across the workspace with one window (25-40 cm) to reach through.

usage: make-scene.py KIND SEED OUT.json [--robot-clearance M]

Objects keep out of a cylinder of --robot-clearance (default 0.25 m) around the robot's base, so
that the arm's own ready region stays free. The same seed gives the same scene.
"""
import argparse
import json
import math
import random

TABLE = {"x": (0.35, 0.95), "y": (-0.6, 0.6), "top": 0.20}


def table_objects():
    """The bundled table.json's floor, top and legs."""
    objects = [{"name": "floor", "type": "box", "size": [2.0, 2.0, 0.02], "position": [0, 0, -0.01],
                "allowed_links": ["@base"]},
               {"name": "table_top", "type": "box", "size": [0.6, 1.2, 0.04], "position": [0.65, 0, 0.18]}]
    for i, (x, y) in enumerate([(0.375, 0.575), (0.375, -0.575), (0.925, 0.575), (0.925, -0.575)]):
        objects.append({"name": f"table_leg_{i}", "type": "cylinder", "radius": 0.025, "length": 0.16,
                        "position": [x, y, 0.08]})
    return objects


def r3(v):
    return [round(c, 4) for c in v]


def clutter(rng, clearance):
    objects = table_objects()
    for k in range(rng.randint(4, 8)):
        while True:
            x, y = rng.uniform(*TABLE["x"]), rng.uniform(*TABLE["y"])
            if math.hypot(x, y) > clearance + 0.1:
                break
        h = rng.uniform(0.05, 0.30)
        if rng.random() < 0.5:
            size = [rng.uniform(0.05, 0.30), rng.uniform(0.05, 0.30), h]
            objects.append({"name": f"box_{k}", "type": "box", "size": r3(size),
                            "position": r3([x, y, TABLE["top"] + h / 2]),
                            "rpy": r3([0, 0, rng.uniform(-math.pi, math.pi)])})
        else:
            objects.append({"name": f"cylinder_{k}", "type": "cylinder",
                            "radius": round(rng.uniform(0.025, 0.15), 4), "length": round(h, 4),
                            "position": r3([x, y, TABLE["top"] + h / 2])})
    if rng.random() < 0.4:  # a board above the table on two posts
        z = rng.uniform(0.55, 0.75)
        x = rng.uniform(0.5, 0.8)
        objects.append({"name": "board", "type": "box", "size": r3([0.3, 0.8, 0.02]),
                        "position": r3([x, 0, z])})
        for s in (-1, 1):
            objects.append({"name": f"board_post_{'lr'[(s + 1) // 2]}", "type": "cylinder",
                            "radius": 0.02, "length": round(z - TABLE["top"], 4),
                            "position": r3([x, s * 0.38, (z + TABLE["top"]) / 2])})
    return "clutter", objects


def shelf(rng, clearance):
    objects = table_objects()[:1]
    x = rng.uniform(max(0.55, clearance + 0.25), 0.75)  # the shelf's front
    depth, width = 0.3, rng.uniform(0.8, 1.1)
    levels = rng.randint(2, 3)
    z0, height = rng.uniform(0.15, 0.3), rng.uniform(0.25, 0.35)
    for k in range(levels + 1):
        objects.append({"name": f"shelf_board_{k}", "type": "box", "size": r3([depth, width, 0.02]),
                        "position": r3([x + depth / 2, 0, z0 + k * height])})
    columns = rng.randint(2, 3)
    for k in range(columns + 1):
        y = -width / 2 + k * width / columns
        objects.append({"name": f"shelf_side_{k}", "type": "box",
                        "size": r3([depth, 0.02, levels * height]),
                        "position": r3([x + depth / 2, y, z0 + levels * height / 2])})
    objects.append({"name": "shelf_back", "type": "box", "size": r3([0.02, width, levels * height]),
                    "position": r3([x + depth, 0, z0 + levels * height / 2])})
    return "shelf", objects


def opening(rng, clearance):
    objects = table_objects()
    x = rng.uniform(max(0.45, clearance + 0.15), 0.6)
    w, h = rng.uniform(0.25, 0.4), rng.uniform(0.25, 0.4)
    cy, cz = rng.uniform(-0.2, 0.2), rng.uniform(0.45, 0.65)
    top, y0, y1 = 1.2, -0.8, 0.8
    bottom = TABLE["top"] + 0.02
    parts = {"below": (y0, y1, bottom, cz - h / 2), "above": (y0, y1, cz + h / 2, top),
             "left": (cy + w / 2, y1, cz - h / 2, cz + h / 2), "right": (y0, cy - w / 2, cz - h / 2, cz + h / 2)}
    for name, (ya, yb, za, zb) in parts.items():
        objects.append({"name": f"wall_{name}", "type": "box", "size": r3([0.02, yb - ya, zb - za]),
                        "position": r3([x, (ya + yb) / 2, (za + zb) / 2])})
    return "opening", objects


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("kind", choices=["clutter", "shelf", "opening"])
    p.add_argument("seed", type=int)
    p.add_argument("out")
    p.add_argument("--robot-clearance", type=float, default=0.25)
    a = p.parse_args()
    rng = random.Random(f"{a.kind}-{a.seed}")
    kind, objects = {"clutter": clutter, "shelf": shelf, "opening": opening}[a.kind](rng, a.robot_clearance)
    scene = {"schema_version": 1, "name": f"{kind}-{a.seed}",
             "description": f"make-scene.py {a.kind} {a.seed}: a random {kind} scene.", "objects": objects}
    with open(a.out, "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
