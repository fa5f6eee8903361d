"""Render an exported .glb as imported, and measure the picture: the artist's check.

    .venv-blender/bin/python blender/check_render.py -- --glb FILE.glb --target TARGET.png
        [--scale 0.5] [--samples 4] [--keep-render RAW.png]

Unlike render_shadow.py, which swaps in its own light, receiver material and recipe to get an
exact mask, this keeps what the importer made of the file (default importer settings): the
imported light with its energy, the imported materials, the table, Blender's default view
transform. Only what a render needs is set: the frame of t (scene extras), the shadow camera,
Cycles (CPU, few samples, a 0.01 px pixel filter so that a pixel is judged at its centre, as the
rasterizer does), the render size (target size x --scale). The bodies are hidden from
camera rays only (they still cast shadows): the shadow camera stands at the light, where it would
otherwise see the bodies' lit tops instead of the shadow. No world (factory empty scene).

The render's luminance (display values 0..1, after the view transform) is split into dark and lit
pixels at half the 99th percentile; prints one line `BSA_RESULT {...}` with: iou (dark pixels vs
the target's dark pixels, < 128, sampled at the render's pixel centres), lit_mean, shadow_mean,
ratio = lit_mean / shadow_mean, black (true if the lit level is under 0.05), seconds.
"""

import argparse
import os
import sys
from time import perf_counter as timer

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402


def main():
    p = argparse.ArgumentParser(prog="check_render.py")
    p.add_argument("--glb", required=True)
    p.add_argument("--target", required=True, help="target picture (dark = shadow)")
    p.add_argument("--scale", type=float, default=1.0, help="render size / target size")
    p.add_argument("--samples", type=int, default=4)
    p.add_argument("--bounces", type=int, default=0,
                   help="Cycles max bounces (0: direct light only, noise-free at few samples)")
    p.add_argument("--keep-render", help="also keep the render (PNG)")
    args = p.parse_args(B.script_argv())
    t_start = timer()
    try:
        gltf = B.read_glb_json(args.glb)
        extras = B.scene_extras(gltf)
        fps, t, frame = B.resolve_timing(extras)
    except (OSError, ValueError, B.BsaError) as e:
        B.fail(str(e))
    if frame is None:
        B.fail("the .glb has no scene extras `t_frame` or `t`")
    import bpy
    import numpy as np

    try:
        scene, _ = B.reset_and_import(args.glb, fps)
    except B.BsaError as e:
        B.fail(str(e))
    cam = B.find_object("camera_shadow", "CAMERA")
    if cam is None:
        B.fail("no camera_shadow in %s" % args.glb)
    scene.camera = cam
    roles = B.classify()
    for o in roles["occluder"]:
        o.visible_camera = False
    target = B.load_pixels(args.target)
    th, tw = target.shape[:2]
    w, h = max(1, int(round(tw * args.scale))), max(1, int(round(th * args.scale)))
    r = scene.render
    r.resolution_x, r.resolution_y = w, h
    B.cycles_common(scene, samples=args.samples, max_bounces=args.bounces)
    # A pixel is dark when its centre is in the shadow, as the rasterizer decides: with
    # Blender's default 1.5 px filter an edge pixel is a blend, which the non-linear view
    # transform lifts over the threshold, and every outline loses half a pixel (4 % of
    # IoU on the thin strokes of tbc).
    scene.cycles.filter_width = 0.01
    B.set_frame(scene, frame)

    with B.scratch_dir("bsa_check_render_") as tmpdir:
        raw = args.keep_render or os.path.join(tmpdir, "render.png")
        B.image_output(scene, raw)
        t0 = timer()
        bpy.ops.render.render(write_still=True)
        t_render = timer() - t0
        px = B.load_pixels(raw)
    if px.shape[:2] != (h, w):
        B.fail("render size %r != %dx%d" % (px.shape[:2], w, h))
    luma = 0.2126 * px[..., 0] + 0.7152 * px[..., 1] + 0.0722 * px[..., 2]
    # Target's dark pixels at the render's pixel centres.
    tl = target[..., 0]
    ys = np.minimum(((np.arange(h) + 0.5) * th / h).astype(int), th - 1)
    xs = np.minimum(((np.arange(w) + 0.5) * tw / w).astype(int), tw - 1)
    want = tl[np.ix_(ys, xs)] < 0.5
    lit_level = float(np.percentile(luma, 99))
    dark = luma < 0.5 * lit_level
    inter = int((dark & want).sum())
    union = int((dark | want).sum())
    lit_mean = float(luma[~dark].mean()) if (~dark).any() else 0.0
    shadow_mean = float(luma[dark].mean()) if dark.any() else 0.0
    light = B.find_object("light", "LIGHT")
    B.result({
        "width": w,
        "height": h,
        "frame": frame,
        "samples": args.samples,
        "view_transform": scene.view_settings.view_transform,
        "light_energy_w": light.data.energy if light is not None else None,
        "iou": inter / union if union else 1.0,
        "dark_pixels": int(dark.sum()),
        "target_dark_pixels": int(want.sum()),
        "lit_mean": lit_mean,
        "shadow_mean": shadow_mean,
        "ratio": lit_mean / shadow_mean if shadow_mean > 0 else None,
        "black": lit_level < 0.05,
        "render_seconds": round(t_render, 3),
        "seconds": round(timer() - t_start, 3),
    })


if __name__ == "__main__":
    main()
