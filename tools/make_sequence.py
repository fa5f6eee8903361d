#!/usr/bin/env python3
"""Write scenes/sequence: five wooden blocks whose shadows spell E at t1, then H at t2.

    python3 tools/make_sequence.py

Plain Python 3 (no packages). Writes scenes/sequence/scene.json, e.png and h.png; the
output depends on nothing else.

The letters are block letters drawn from the blocks' own shadows: every stroke is the
shadow of one block lying flat at the height where both pictures are the same size
(magnification MAG), with a small gap between strokes so that the blocks need not
touch. Three blocks stay where they are (E's left stroke in two blocks and its middle
bar are also H's); the top and bottom bars of E turn a quarter turn about the vertical
and move right to become H's right stroke. Why the pictures can both be met:

* heights: a block launched straight up from the table is at the same height at t1 and
  t2 when its apex is at (t1 + t2) / 2; that height is z0 + g t1 t2 / 2, so t1 and t2
  are chosen to put it where the magnification is MAG (light 6 m above the floor);
* places: at one height the shadow moves as the body does, scaled by MAG, and a body can
  move from any spot to any other in t2 - t1 with a launch position on the table
  (`"positions": "free"`: the solver moves the launch positions);
* turns: a flat block spun about the vertical turns at a constant rate (the axis of its
  largest moment of inertia is stable), so a quarter turn between t1 and t2 is a spin of
  pi / 2 / (t2 - t1); each block lies on the table with the yaw that makes it horizontal
  at t1;
* no contact: a moving block flies along a straight line (seen from above) through its
  two places, and E's top bar's line passes over the stem before t1: at one height they
  would collide. The moving blocks are launched LIFT m/s faster, so they pass a few
  centimetres above the stem (their strokes come out 4 % and 7 % longer, a price the
  pictures can pay).

The start guess is this design (positions, `start_velocity`, `start_angular_velocity`);
the solver refines it, with the launch positions free. The hints (one per block and
picture, at its stroke's centre) guide the search as in any scene.
"""

from __future__ import annotations

import json
import math
import struct
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "scenes" / "sequence"
W, H = 640, 480
RECEIVER_W, RECEIVER_H = 1.6, 1.2
LIGHT = 6.0
G = 9.81
T1, T2 = 0.6, 1.0
# Block: length x width x thickness (m), maple.
BLOCK = (0.16, 0.04, 0.02)
DENSITY = 705.0
Z0 = BLOCK[2] / 2
Z_T = Z0 + G * T1 * T2 / 2  # the height at t1 and t2
MAG = LIGHT / (LIGHT - Z_T)
LENGTH, WIDTH = BLOCK[0] * MAG, BLOCK[1] * MAG  # a stroke's shadow (m)
GAP = 0.02  # between strokes (m, on the floor)
LIFT = 0.35  # extra vertical launch speed of the moving blocks (m/s)


def strokes():
    """(name, E stroke, H stroke), each (x, y, vertical) in floor metres, centred."""
    x0 = -(WIDTH + GAP + LENGTH + GAP + WIDTH) / 2  # H's left edge; H is the wider
    left = x0 + WIDTH / 2
    bar = x0 + WIDTH + GAP + LENGTH / 2
    right = x0 + WIDTH + GAP + LENGTH + GAP + WIDTH / 2
    half = (GAP + LENGTH) / 2  # centre of an upper or lower stroke of a stem
    top = GAP / 2 + LENGTH - WIDTH / 2
    return [
        ("stem_top", (left, half, True), (left, half, True)),
        ("stem_bottom", (left, -half, True), (left, -half, True)),
        ("middle", (bar, 0.0, False), (bar, 0.0, False)),
        ("top", (bar, top, False), (right, half, True)),
        ("bottom", (bar, -top, False), (right, -half, True)),
    ]


def rect(x, y, vertical):
    hw, hh = (WIDTH / 2, LENGTH / 2) if vertical else (LENGTH / 2, WIDTH / 2)
    return (x - hw, x + hw, y - hh, y + hh)


def pixel_of(x, y):
    """Pixel coordinates (x right, y down, centres at +0.5) of a floor point."""
    return ((x / RECEIVER_W + 0.5) * W, (0.5 - y / RECEIVER_H) * H)


def write_png(path, rects):
    rows = []
    for j in range(H):
        y = (0.5 - (j + 0.5) / H) * RECEIVER_H
        row = bytearray([0])  # filter: none
        for i in range(W):
            x = ((i + 0.5) / W - 0.5) * RECEIVER_W
            dark = any(a <= x <= b and c <= y <= d for a, b, c, d in rects)
            row.append(0 if dark else 255)
        rows.append(bytes(row))

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(b"".join(rows), 9))
    png += chunk(b"IEND", b"")
    path.write_bytes(png)


def yaw_quat(a):
    return [0.0, 0.0, round(math.sin(a / 2), 9), round(math.cos(a / 2), 9)]


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    s = strokes()
    write_png(OUT / "e.png", [rect(*e) for _, e, _ in s])
    write_png(OUT / "h.png", [rect(*h) for _, _, h in s])
    occluders, hints_e, hints_h = [], [], []
    t_mid = (T1 + T2) / 2
    for name, e, h in s:
        moves = e != h
        vz = G * t_mid + (LIFT if moves else 0.0)
        z1 = Z0 + vz * T1 - G * T1 * T1 / 2
        z2 = Z0 + vz * T2 - G * T2 * T2 / 2
        m1, m2 = LIGHT / (LIGHT - z1), LIGHT / (LIGHT - z2)
        # Centre of mass over the stroke's centre at both instants (the light is above the
        # picture's centre, so a shadow is the body's place scaled by its magnification).
        vx = (h[0] / m2 - e[0] / m1) / (T2 - T1)
        vy = (h[1] / m2 - e[1] / m1) / (T2 - T1)
        x0, y0 = e[0] / m1 - vx * T1, e[1] / m1 - vy * T1
        a1 = math.pi / 2 if e[2] else 0.0
        a2 = math.pi / 2 if h[2] else 0.0
        turn = a2 - a1
        if name == "bottom":
            turn = -turn  # the two bars turn opposite ways, mirror images
        spin = turn / (T2 - T1)
        occluders.append({
            "name": name,
            "shape": {"box": {"size": list(BLOCK)}},
            "position": [round(x0, 6), round(y0, 6), Z0],
            "orientation": yaw_quat(a1 - spin * T1),
            "density": DENSITY,
            "start_velocity": [round(vx, 6), round(vy, 6), round(vz, 6)],
            "start_angular_velocity": [0.0, 0.0, round(spin, 9)],
        })
        for hints, (x, y, _) in ((hints_e, e), (hints_h, h)):
            px, py = pixel_of(x, y)
            hints.append({"occluder": name, "point": [0.0, 0.0, 0.0],
                          "pixel": [round(px, 3), round(py, 3)], "weight": 1.0})
    stage = {
        "weights": {"xor": 1.0, "hint": 0.3, "barrier": 1.0, "contact": 100000.0, "reg": 0.01},
        "step": 0.05,
        "population": 24,
        "max_iterations": 80,
        "stagnation": 25,
    }
    final = dict(stage, step=0.02, population=32, max_iterations=150)
    scene = {
        "name": "sequence",
        "targets": [
            {"target": "e.png", "t": T1, "weight": 1.0, "hints": hints_e},
            {"target": "h.png", "t": T2, "weight": 1.0, "hints": hints_h},
        ],
        "timestep": 1.0 / 60.0,
        "gravity": [0.0, 0.0, -G],
        "light": [0.0, 0.0, LIGHT],
        "receiver": {"center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0],
                     "width": RECEIVER_W, "height": RECEIVER_H},
        "table": {"center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0]},
        "positions": "free",
        "contacts": "constraint",
        "occluders": occluders,
        "strategy": {"kind": "sequential", "order": "auto", "rounds": 2, "stage": stage,
                     "final": final},
        "seed": 1,
    }
    (OUT / "scene.json").write_text(json.dumps(scene, indent=2) + "\n")
    print(f"wrote {OUT}: E at {T1} s, H at {T2} s; blocks {Z_T:.3f} m high at both, "
          f"magnification {MAG:.3f}, strokes {LENGTH:.3f} x {WIDTH:.3f} m")


if __name__ == "__main__":
    main()
