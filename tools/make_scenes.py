#!/usr/bin/env python3
"""Write scenes/fly/scene.json and scenes/tbc/scene.json from stroke sketches.

    cargo build --release && python3 tools/make_scenes.py   # plain Python 3

The thinker scene's start arrangement is searched for: `bsa check` (the release
binary) tells whether a candidate start guess has a contact (see `search_thinker`).

The brick scenes are designed the way the paper's user designs them: every brick is
given one stroke of the target (two end pixels, read off the picture), one hint (its
centre goes to the stroke's centre) and a start guess that sends it there. The start
guess is only where the search begins; the solver finds the launches.

How a start guess is made, for a stroke of length `l` px and a brick of length `L` m:
the shadow of a brick at height `z` under a light at height `h` is magnified by
`m = h / (h - z)`, so the brick's long edge covers the stroke when `m = l * px / L`
(`px` = metres per pixel on the receiver). The brick lies flat on the floor at launch
with its long axis along the stroke; its centre of mass is sent, in `t` seconds, to the
point at that height on the light ray through the stroke's centre, and it is given the
spin about its long axis that rolls it, by `t`, to the angle at which its shadow is as
wide as the stroke.

Bricks are wooden unit blocks (Caroline Pratt's system, still sold by every school
supplier), hard maple at 705 kg/m^3: unit 140 x 70 x 35 mm (about 240 g), double unit
280 x 70 x 35 mm, half unit 70 x 70 x 35 mm, pillar 140 x 35 x 35 mm and half pillar
70 x 35 x 35 mm (nominal 5 1/2 x 2 3/4 x 1 3/8 inch and multiples). See docs/results.md.
"""

from __future__ import annotations

import json
import math
import random
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

MAPLE = 705.0  # kg/m^3, hard maple (Acer saccharum), air dry
BLOCKS = {  # long, middle, short (m)
    "unit": (0.1397, 0.06985, 0.0349),
    "double": (0.2794, 0.06985, 0.0349),
    "half": (0.06985, 0.06985, 0.0349),
    "pillar": (0.1397, 0.0349, 0.0349),
    "half_pillar": (0.06985, 0.0349, 0.0349),
}

LIGHT_H = 6.0
T = 1.2
G = 9.81
W_PX, H_PX = 640, 480


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def quat_axis(axis, angle):
    s = math.sin(angle / 2)
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2))


def make(name, img_w_m, strokes, launch_y, launch_x_span, stage, final, order, rounds=1):
    px = img_w_m / W_PX
    img_h_m = px * H_PX
    occluders, hints = [], []
    # Launch slots along a row in front of the picture, in the order of the strokes'
    # x so that the flights do not cross more than they must.
    by_x = sorted(range(len(strokes)), key=lambda k: (strokes[k][2][0] + strokes[k][3][0]))
    slots = {}
    n = len(strokes)
    for rank, k in enumerate(by_x):
        slots[k] = -launch_x_span / 2 + launch_x_span * rank / max(n - 1, 1)
    for k, (bname, block, p0, p1, width_px) in enumerate(strokes):
        upright = block.endswith("@up")
        L, B, C = BLOCKS[block.removesuffix("@up")]
        cx, cy = (p0[0] + p1[0]) / 2, (p0[1] + p1[1]) / 2
        dx, dy = p1[0] - p0[0], p1[1] - p0[1]
        l_px = math.hypot(dx, dy)
        theta = math.atan2(-dy, dx)  # world angle: pixel y runs down, world y up
        # An upright block (long axis vertical) shows its B x C end to the light.
        m = l_px * px / (B if upright else L)
        assert m > 1.05, f"{bname}: stroke too short for a {block} block (m = {m:.2f})"
        z = LIGHT_H * (1 - 1 / m)
        # Receiver point of the stroke centre, then the point at height z on its ray.
        rx = (cx + 0.0 - W_PX / 2) * px
        ry = (H_PX / 2 - cy) * px
        target = (rx * (1 - z / LIGHT_H), ry * (1 - z / LIGHT_H), z)
        # Roll about the long axis so that the shadow's width matches the stroke.
        w_m = width_px * px / m
        roll = 0.0
        best = 1e9
        for i in range(0, 91):
            a = math.radians(i)
            err = abs(B * math.cos(a) + C * math.sin(a) - w_m)
            if err < best:
                best, roll = err, a
        x0 = (slots[k], launch_y, L / 2 if upright else C / 2)
        v0 = [(target[i] - x0[i] - (0 if i < 2 else -G * T * T / 2)) / T for i in range(3)]
        axis = (math.cos(theta), math.sin(theta), 0.0)
        q = quat_axis((0.0, 0.0, 1.0), theta)
        if upright:
            # Long (body x) axis vertical, then no roll: the end face is the shadow.
            q = quat_mul(q, quat_axis((0.0, 1.0, 0.0), -math.pi / 2))
            roll = 0.0
        mass = MAPLE * L * B * C
        occluders.append({
            "name": bname,
            "shape": {"box": {"size": [L, B, C]}},
            "position": [round(v, 6) for v in x0],
            "orientation": [round(v, 9) for v in q],
            "mass": round(mass, 4),
            "start_velocity": [round(v, 6) for v in v0],
            "start_angular_velocity": [round(a * roll / T, 6) for a in axis],
        })
        hints.append({"occluder": bname, "point": [0.0, 0.0, 0.0], "pixel": [cx, cy], "weight": 1.0})
    scene = {
        "name": name,
        "target": "target.png",
        "t": T,
        "timestep": 1.0 / 60.0,
        "gravity": [0.0, 0.0, -G],
        "light": [0.0, 0.0, LIGHT_H],
        "receiver": {"center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0],
                     "width": round(img_w_m, 6), "height": round(img_h_m, 6)},
        "table": {"center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0]},
        "occluders": occluders,
        "hints": hints,
        "strategy": {"kind": "sequential", "order": order, "rounds": rounds, "stage": stage,
                     "final": final},
        "seed": 1,
    }
    path = ROOT / "scenes" / name / "scene.json"
    path.write_text(json.dumps(scene, indent=2) + "\n")
    print(f"wrote {path}")


def main():
    # Every scene uses the default weights (no `weights` in its stages) and contacts as
    # constraints (the scene's default `contacts`).
    stage = {"step": 0.05, "population": 24, "max_iterations": 80, "stagnation": 25}
    final = {"step": 0.02, "population": 32, "max_iterations": 60, "stagnation": 25}
    fly = [
        # name, block, stroke start px, stroke end px, stroke width px
        ("bar", "double", (144, 95), (382, 95), 46),
        ("stem", "double", (360, 100), (374, 300), 45),
        ("bowl", "unit", (372, 290), (430, 398), 45),
        ("hook", "unit", (445, 402), (478, 300), 40),
        ("upper_dot", "unit", (390, 176), (466, 104), 40),
        ("lower_dot", "unit", (396, 212), (480, 258), 40),
    ]
    make("fly", 1.6, fly, -1.0, 1.2, stage, final, "auto")
    tbc = [
        ("tsu_a", "unit", (60, 209), (152, 190), 22),
        ("tsu_b", "half_pillar", (150, 188), (206, 205), 22),
        ("tsu_c", "half_pillar", (212, 212), (202, 258), 22),
        ("tsu_d", "unit", (198, 258), (113, 304), 22),
        ("dzu_a", "unit", (250, 209), (342, 190), 22),
        ("dzu_b", "half_pillar", (340, 188), (396, 205), 22),
        ("dzu_c", "half_pillar", (402, 212), (392, 258), 22),
        ("dzu_d", "unit", (388, 258), (303, 304), 22),
        ("dot_1", "half_pillar@up", (375, 172), (399, 172), 24),
        ("dot_2", "half_pillar@up", (401, 163), (423, 163), 22),
        ("ku_a", "unit", (556, 160), (468, 232), 22),
        ("ku_b", "unit", (468, 236), (570, 312), 22),
    ]
    # Thin strokes leave little slack: a second pass lets early bricks use the room
    # that later ones left.
    make("tbc", 1.6, tbc, -1.0, 2.8, stage, final, "auto", rounds=2)
    # THE THINKER gives each stage more room: sixteen pieces leave each other less slack
    # than bricks do.
    bsa = str(ROOT / "target" / "release" / "bsa")
    search_thinker(dict(stage, max_iterations=200, stagnation=30),
                   dict(final, step=0.01, max_iterations=100), bsa)


# Chess pieces (scenes/thinker/pieces, examples/chess_pieces.rs): height (m) and
# centre-of-mass height (m) above the base, from docs/chess-pieces.md.
PIECES = {
    "pawn": (0.050, 0.0213),
    "rook": (0.055, 0.0242),
    "knight": (0.062, 0.0219),
    "bishop": (0.070, 0.0254),
    "queen": (0.085, 0.0326),
    "king": (0.095, 0.0341),
}
FILES = "abcdefgh"
BOXWOOD = 900.0  # kg/m^3, unweighted boxwood pieces
SQUARE = 0.057  # m, tournament board square (2 1/4 inch)


def make_thinker(stage, final, layout=None):
    """THE THINKER: 16 pieces, two hints each (base centre and top of the axis).

    A lying piece's axis is sent to the segment between its two hint pixels, at the
    height where the piece's length covers it; an upright piece (`up`) stands on its
    hint pixel, its base disc covering a circle of the given diameter (px)."""
    light_h = 3.0
    img_w_m = 0.96
    px = img_w_m / W_PX
    img_h_m = px * H_PX
    # name, piece, file (0-7 = a-h), rank (1 or 2), base px, top px (or diameter px)
    # The parts of the picture: piece, base px, top px (or the diameter px of an upright
    # piece's disc).
    parts = [
        ("rook", (160, 386), (262, 388)),
        ("knight", (166, 340), (290, 330)),
        ("bishop", (196, 320), (262, 180)),
        ("king", (222, 290), (318, 112)),
        ("queen", (300, 238), (388, 102)),
        ("bishop", (262, 250), (432, 246)),
        ("knight", (398, 222), (402, 120)),
        ("rook", (418, 84), 52),
        ("pawn", (256, 392), (342, 392)),
        ("pawn", (282, 346), (352, 302)),
        ("pawn", (340, 282), (346, 352)),
        ("pawn", (342, 352), (402, 356)),
        ("pawn", (336, 396), (418, 396)),
        ("pawn", (400, 278), (420, 362)),
        ("pawn", (410, 366), (472, 370)),
        ("pawn", (410, 394), (480, 396)),
    ]
    # The pieces stand on every other square of a board in front of the picture (files
    # a, c, e, g; ranks 1, 3, 5, 7), 114 mm apart, so that no two start within reach of
    # each other. Parts are dealt to columns of squares from left to right by their x in
    # the picture, and within a column the part highest in the picture (which flies
    # furthest) starts nearest to it, so that no flight overtakes or crosses another.
    if layout is None:
        def centre(part):
            b = part[1]
            t = part[2] if not isinstance(part[2], (int, float)) else part[1]
            return ((b[0] + t[0]) / 2, (b[1] + t[1]) / 2)
        order = sorted(range(16), key=lambda k: centre(parts[k])[0])
        layout = []
        for col in range(4):
            column = sorted(order[4 * col: 4 * col + 4], key=lambda k: centre(parts[k])[1])
            for row, k in enumerate(column):
                piece, base, top = parts[k]
                file, rank = 2 * col, 7 - 2 * row  # rank 7 is nearest to the picture
                name = f"{piece}_{FILES[file]}{rank}"
                layout.append((name, piece, file, rank, base, top))
    board_y = -(img_h_m / 2) - 0.20  # rank 8's centre line, in front of the picture

    def ray_point(pix, z):
        rx = (pix[0] - W_PX / 2) * px
        ry = (H_PX / 2 - pix[1]) * px
        f = 1 - z / light_h
        return (rx * f, ry * f, z)

    occluders, hints = [], []
    for name, piece, file, rank, base_px, top in layout:
        height, com_h = PIECES[piece]
        x0 = ((file - 3.5) * SQUARE, board_y - (8 - rank) * SQUARE, 0.0)
        com0 = (x0[0], x0[1], com_h)
        if isinstance(top, (int, float)):
            # Upright: the base disc (about 0.64 of the height wide for a rook) covers
            # a circle of `top` px: size the height from the piece's widest radius.
            widest = {"rook": 0.035}[piece]  # base diameter
            m = top * px / widest
            z = light_h * (1 - 1 / m)
            base = ray_point(base_px, z - height / 2)
            com_t = (base[0], base[1], base[2] + com_h)
            w = (0.0, 0.0, 0.0)
            top_px = base_px
        else:
            l_px = math.hypot(top[0] - base_px[0], top[1] - base_px[1])
            m = l_px * px / height
            assert m > 1.05, f"{name}: segment too short (m = {m:.2f})"
            z = light_h * (1 - 1 / m)
            b, tp = ray_point(base_px, z), ray_point(top, z)
            d = [(tp[i] - b[i]) / height for i in range(3)]
            com_t = tuple(b[i] + d[i] * com_h for i in range(3))
            # Tip the upright piece by 90 degrees about z x d within t.
            k = (-d[1], d[0], 0.0)
            kn = math.hypot(k[0], k[1])
            w = tuple(ki / kn * (math.pi / 2) / T for ki in k)
            top_px = top
        v0 = [(com_t[i] - com0[i] - (0 if i < 2 else -G * T * T / 2)) / T for i in range(3)]
        occluders.append({
            "name": name,
            "shape": {"mesh": {"obj": f"pieces/{piece}.obj"}},
            "position": [round(v, 6) for v in x0],
            "density": BOXWOOD,
            "start_velocity": [round(v, 6) for v in v0],
            "start_angular_velocity": [round(v, 6) for v in w],
        })
        hints.append({"occluder": name, "point": [0.0, 0.0, 0.0], "pixel": list(base_px), "weight": 1.0})
        hints.append({"occluder": name, "point": [0.0, 0.0, height], "pixel": list(top_px), "weight": 1.0})
    scene = {
        "name": "thinker",
        "target": "target.png",
        "t": T,
        "timestep": 1.0 / 60.0,
        "gravity": [0.0, 0.0, -G],
        "light": [0.0, 0.0, light_h],
        "receiver": {"center": [0.0, 0.0, 0.0], "u": [1.0, 0.0, 0.0], "v": [0.0, 1.0, 0.0],
                     "width": img_w_m, "height": round(img_h_m, 6)},
        "table": {"center": [0.0, 0.0, -0.5], "size": [40.0, 40.0, 1.0]},
        "occluders": occluders,
        "hints": hints,
        "strategy": {"kind": "sequential", "order": "auto", "rounds": 2, "stage": stage,
                     "final": final},
        "seed": 1,
    }
    path = ROOT / "scenes" / "thinker" / "scene.json"
    path.write_text(json.dumps(scene, indent=2) + "\n")
    print(f"wrote {path}")
    return layout


def start_contact(bsa):
    """Ask `bsa check` whether the thinker scene's start guess has a contact."""
    out = subprocess.run([bsa, "check", str(ROOT / "scenes" / "thinker")],
                         capture_output=True, text=True, check=True).stdout
    line = next(l for l in out.splitlines() if l.strip().startswith("start"))
    return "first contact" in line, line.strip()


def search_thinker(stage, final, bsa, tries=400):
    """Keep the parts of the picture, permute which piece of a kind plays which part.

    The first contact-free start guess of a seeded random search is written; the
    identity (parts ordered like the files) is tried first."""
    base = make_thinker(stage, final)
    rng = random.Random(1)
    for attempt in range(tries):
        layout = [list(r) for r in base]
        if attempt > 0:
            # Swap the squares of random pairs of parts.
            for _ in range(attempt % 3 + 1):
                a, b = rng.sample(range(len(layout)), 2)
                layout[a][2:4], layout[b][2:4] = layout[b][2:4], layout[a][2:4]
            for r in layout:
                r[0] = f"{r[1]}_{FILES[r[2]]}{r[3]}"
        make_thinker(stage, final, [tuple(r) for r in layout])
        contact, line = start_contact(bsa)
        print(f"  arrangement {attempt}: {line}")
        if not contact:
            return
    sys.exit("no contact-free start arrangement found")


if __name__ == "__main__":
    main()
