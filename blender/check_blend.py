"""Open a .blend written by `bsa blend` and measure it: what the tests check.

    .venv-blender/bin/python blender/check_blend.py -- --blend FILE.blend \
        [--view-size 480x270] [--no-view] [--mask OUT.png [--engine CYCLES|EEVEE] [--frame F]]

Reports the file's timing (fps, frame range, the marker `t` and whether it is a whole frame, the
occluders' keys there), its scenes, cameras and resolutions, then renders:

  * the view: the main scene's frame of the marker `t` from its active camera, at --view-size,
    with the bodies hidden from camera rays (they still cast shadows), the receiver cut to the
    picture's rectangle and the table hidden, Cycles with the exact-mask recipe (1 sample, no
    world, a radius-0 light of 1e7 W): `view.fraction` is the height of the shadow's bounding box
    over the frame's height;
  * with --mask, the shadow scene (`<name>_shadow`, camera_shadow, the target's size) at the
    marker's frame (or --frame): CYCLES with the same exact-mask recipe, and nothing else hidden
    (the shadow camera's clipping must keep the bodies out of its view); or EEVEE with the file's
    own light, world and EEVEE settings (only the samples lowered to --eevee-samples): dark pixels
    are those under half the 99th percentile of luminance. Writes the mask as an 8-bit PNG (0 =
    shadow, 255 = lit).

Prints one line `BSA_RESULT {...}`.
"""

import argparse
import math
import os
import sys

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402

MASK_LIGHT_W = 1.0e7


def marker_frame(scene):
    for m in scene.timeline_markers:
        if m.name == "t":
            return m.frame
    return None


def exact_mask_recipe(bpy, scene, samples=1):
    """Cycles as render_shadow.py: one sample on the pixel centre, direct light only, no world,
    a radius-0 light so bright that every lit pixel saturates, transparent film."""
    B.cycles_common(scene, samples=samples, max_bounces=0)
    scene.cycles.filter_width = 0.01
    scene.world = None
    scene.render.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    light = B.find_object("light", "LIGHT")
    light.data.shadow_soft_size = 0.0
    light.data.energy = MASK_LIGHT_W
    for o in bpy.data.objects:
        if o.type == "LIGHT" and o != light:
            o.hide_render = True


def activate(bpy, scene):
    """Make `scene` the one the window shows and renders: frame_set and the render operator
    evaluate the context's scene (a render of another scene keeps the window scene's frame)."""
    if bpy.context.window is not None:
        bpy.context.window.scene = scene


def render(bpy, np, scene, path):
    B.image_output(scene, path)
    scene.render.image_settings.color_mode = "RGBA"
    t0 = B.Timer()
    with bpy.context.temp_override(scene=scene):
        bpy.ops.render.render(write_still=True)
    return B.load_pixels(path), t0()


def luma(px):
    return 0.2126 * px[..., 0] + 0.7152 * px[..., 1] + 0.0722 * px[..., 2]


def view_fraction(bpy, np, scene, size, tmp):
    """The shadow's bounding box in the view camera's frame at the marker, as a share of the
    frame's height."""
    roles = B.classify()
    for o in roles["occluder"]:
        o.visible_camera = False
    for o in roles["table"]:
        o.hide_render = True
    for o in bpy.data.objects:
        if o.type == "CURVE":
            o.hide_render = True
    for o in roles["receiver"]:
        # The receiver is 1.5 times the picture's rectangle about its centre.
        o.scale = tuple(s / 1.5 for s in o.scale)
    exact_mask_recipe(bpy, scene)
    w, h = size
    scene.render.resolution_x, scene.render.resolution_y = w, h
    px, secs = render(bpy, np, scene, os.path.join(tmp, "view.png"))
    shadow = (px[..., 3] > 0.5) & (luma(px) < 0.5)
    rows = np.nonzero(shadow.any(axis=1))[0]
    cols = np.nonzero(shadow.any(axis=0))[0]
    if rows.size == 0:
        return {"fraction": 0.0, "shadow_pixels": 0, "render_seconds": secs}
    return {
        "fraction": float(rows[-1] - rows[0] + 1) / h,
        "width_fraction": float(cols[-1] - cols[0] + 1) / w,
        "bbox_rows": [int(rows[0]), int(rows[-1])],
        "bbox_cols": [int(cols[0]), int(cols[-1])],
        "shadow_pixels": int(shadow.sum()),
        "size": [w, h],
        "render_seconds": secs,
    }


def shadow_mask(bpy, np, shadow_scene, engine, frame, out, eevee_samples, tmp):
    activate(bpy, shadow_scene)
    if engine == "CYCLES":
        exact_mask_recipe(bpy, shadow_scene)
    else:
        shadow_scene.render.engine = "BLENDER_EEVEE"
        shadow_scene.eevee.taa_render_samples = eevee_samples
    B.set_frame(shadow_scene, frame)
    px, secs = render(bpy, np, shadow_scene, os.path.join(tmp, "mask.png"))
    lum = luma(px)
    if engine == "CYCLES":
        dark = (px[..., 3] > 0.5) & (lum < 0.5)
        covered = int((px[..., 3] > 0.5).sum())
    else:
        dark = lum < 0.5 * float(np.percentile(lum, 99))
        covered = int(lum.size)
    h, w = dark.shape
    rows = np.where(dark, 0, 255).astype(np.uint8)
    B.write_gray_png(out, rows.tobytes(), w, h)
    return {"png": os.path.abspath(out), "engine": engine, "frame": frame, "width": w, "height": h,
            "shadow_pixels": int(dark.sum()), "covered_pixels": covered,
            "lit_mean": float(lum[~dark].mean()) if (~dark).any() else 0.0,
            "shadow_mean": float(lum[dark].mean()) if dark.any() else 0.0,
            "render_seconds": secs}


def main():
    timer = B.Timer()
    p = argparse.ArgumentParser(prog="check_blend.py")
    p.add_argument("--blend", required=True)
    p.add_argument("--view-size", default="480x270")
    p.add_argument("--no-view", action="store_true")
    p.add_argument("--mask", help="render the shadow scene's mask to this PNG")
    p.add_argument("--engine", default="CYCLES", choices=["CYCLES", "EEVEE"])
    p.add_argument("--eevee-samples", type=int, default=4)
    p.add_argument("--frame", type=float, help="the mask's frame (default: the marker t)")
    args = p.parse_args(B.script_argv())
    import bpy
    import numpy as np

    if not os.path.isfile(args.blend):
        B.fail("%s does not exist" % args.blend)
    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(args.blend))
    scene = bpy.context.scene
    name = scene.get("bsa_scene", scene.name)
    shadow = bpy.data.scenes.get(name + "_shadow")
    t_frame = marker_frame(scene)
    if t_frame is None or shadow is None:
        B.fail("%s has no marker `t` or no scene %s_shadow" % (args.blend, name))
    # Keys of the bodies at the marker's frame (one per animated channel).
    keyed = 0
    for action in bpy.data.actions:
        for fc in B.action_fcurves(action):
            if any(abs(kp.co.x - t_frame) < 1e-4 for kp in fc.keyframe_points):
                keyed += 1
    report = {
        "scene": scene.name,
        "fps": scene.render.fps / scene.render.fps_base,
        "frame_start": scene.frame_start,
        "frame_end": scene.frame_end,
        "t_frame": t_frame,
        "t_frame_whole": float(t_frame).is_integer(),
        "channels_keyed_at_t": keyed,
        "bsa_t_frame": scene.get("bsa_t_frame"),
        "readable_frames": list(scene.get("bsa_readable_frames", [])),
        "slow_motion_factor": scene.get("bsa_slow_motion_factor"),
        "camera": scene.camera.name if scene.camera else None,
        "camera_type": scene.camera.data.type if scene.camera else None,
        "resolution": [scene.render.resolution_x, scene.render.resolution_y],
        "engine": scene.render.engine,
        "shadow_scene": shadow.name,
        "shadow_camera": shadow.camera.name if shadow.camera else None,
        "shadow_camera_type": shadow.camera.data.type if shadow.camera else None,
        "shadow_resolution": [shadow.render.resolution_x, shadow.render.resolution_y],
        "light_radius_m": B.find_object("light", "LIGHT").data.shadow_soft_size,
        "curves": sorted(o.name for o in bpy.data.objects if o.type == "CURVE"),
        "curves_cast_shadows": any(o.visible_shadow for o in bpy.data.objects if o.type == "CURVE"),
        "curves_light_the_scene": any(o.visible_diffuse or o.visible_glossy
                                      for o in bpy.data.objects if o.type == "CURVE"),
        "collections": sorted(c.name for c in scene.collection.children),
    }
    with B.scratch_dir("bsa_check_blend_") as tmp:
        if args.mask:
            frame = args.frame if args.frame is not None else t_frame
            report["mask"] = shadow_mask(bpy, np, shadow, args.engine, frame, args.mask,
                                         args.eevee_samples, tmp)
        if not args.no_view:
            try:
                w, h = (int(v) for v in args.view_size.lower().split("x"))
            except ValueError:
                B.fail("--view-size must be WxH, got %r" % args.view_size)
            activate(bpy, scene)
            B.set_frame(scene, t_frame)
            report["view"] = view_fraction(bpy, np, scene, (w, h), tmp)
        report["seconds"] = timer()
        B.result(report)


if __name__ == "__main__":
    main()
