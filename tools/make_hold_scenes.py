#!/usr/bin/env python3
"""Write scenes/mickey_hold and scenes/fly_hold from scenes/mickey and the hand-made fly.

    python3 tools/make_hold_scenes.py

Plain Python 3. The same pictures, objects, light and table; what changes, and why
(docs/results.md has the figures):

* `hold`: the picture must hold over +-0.1 s (Mickey) or +-0.05 s (fly) at 60 fps.
* `t`: a body's vertical speed at t is fixed by t, its height at t (which its shadow's size
  fixes) and its launch height: v_z = (z_t - z_0) / t - g t / 2, whatever the launch.
  A shadow grows or shrinks at v_z / (light height - z_t) per second, so at t = 1.2 s
  Mickey's head shrinks by about 11 % over 0.1 s and no launch can hold it. The hold
  scenes take t where the bodies are near the top of their flight: 0.46 s for Mickey
  (between the head's apex time, 0.34 s, and the ears', 0.54 s) and 0.8 s for fly (the
  blocks' apex at the height of their shadows' size).
* `"positions": "free"`: with fixed launch positions a body must cross the table to reach
  its place at t, and its shadow slides by its horizontal speed times the
  magnification; free positions let it start under its place. The start guess moves each
  body to the nearest free spot under where its hints send it.
* Mickey: `"contacts": "constraint"` (three spheres launched side by side must not
  touch), and a third stage with the `worst` hold objective, which balances the two ends
  of the window (the mean favours the middle).
* fly: the start guess lifts the blocks by 3.1 m (`start.rise`, their height at the
  apex) instead of 1.5 m, keeps the original start spins scaled to the same turn at the
  new t, and the sequential strategy runs three rounds of 150 iterations.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def load(name):
    return json.loads((ROOT / "scenes" / name / "scene.json").read_text())


def load_hand_made(name):
    """A scene as it was written by hand before `bsa new` designed the examples
    (benches/hand-made/, kept for the benchmarks and for this derived scene), with its
    target named as in its own folder."""
    s = json.loads((ROOT / "benches" / "hand-made" / name / "scene.json").read_text())
    s["target"] = "target.png"
    return s


def save(name, scene, base):
    out = ROOT / "scenes" / name
    out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(ROOT / "scenes" / base / "target.png", out / "target.png")
    (out / "scene.json").write_text(json.dumps(scene, indent=2) + "\n")
    print(f"wrote {out}")


def mickey_hold():
    s = load("mickey")
    s["name"] = "mickey_hold"
    s["t"] = 0.46
    s["hold"] = {"window": 0.1, "fps": 60}
    s["positions"] = "free"
    s["contacts"] = "constraint"
    s["stages"][1]["max_iterations"] = 300
    hold = dict(s["stages"][1], name="hold", step=0.05, objective="worst")
    s["stages"].append(hold)
    save("mickey_hold", s, "mickey")


def fly_hold():
    s = load_hand_made("fly")
    old_t = s["t"]
    s["name"] = "fly_hold"
    s["t"] = 0.8
    s["hold"] = {"window": 0.05, "fps": 60}
    s["positions"] = "free"
    s["start"] = {"rise": 3.1}
    for o in s["occluders"]:
        # Aimed by the hints from where the start guess puts the block.
        o.pop("start_velocity", None)
        o["start_angular_velocity"] = [
            round(w * old_t / s["t"], 6) for w in o["start_angular_velocity"]
        ]
    st = s["strategy"]
    st["rounds"] = 3
    st["stage"]["max_iterations"] = 150
    st["final"]["max_iterations"] = 150
    save("fly_hold", s, "fly")


if __name__ == "__main__":
    mickey_hold()
    fly_hold()
