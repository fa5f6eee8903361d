"""Render the flight of an exported .glb as an MP4 (H.264) from the perspective camera.

    .venv-blender/bin/python blender/render_video.py -- --glb FILE.glb --out VIDEO.mp4 \
        [--samples 4] [--width 640 --height 480] [--seconds S | --frames A:B] [--fps F]
    blender -b -P blender/render_video.py -- --glb FILE.glb --out VIDEO.mp4 ...

Uses the node `camera_view`; frames 0 .. last animation key by default (the glTF importer does
not set the frame range). Occluders, table and receiver are visible; the point light `light` gets a
small radius and an energy chosen so that the receiver is well lit (the importer's watts =
cd * 4 pi / 683 is replaced unless --keep-light-energy); a neutral low-strength world keeps the
unlit sides from being pure black. Cycles on CPU, few samples, 0 bounces by default.
Prints one line `BSA_RESULT {"video": ..., "frames": [a, b], "bytes": N, ...}` on stdout.
"""

import argparse
import math
import os
import shutil
import sys
import tempfile

sys.dont_write_bytecode = True  # keep blender/ free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402


def parse(argv):
    p = argparse.ArgumentParser(prog="render_video.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--glb", required=True)
    p.add_argument("--out", required=True, help="output .mp4")
    p.add_argument("--samples", type=int, default=4)
    p.add_argument("--bounces", type=int, default=0, help="Cycles max bounces (0 or 1)")
    p.add_argument("--width", type=int, default=640)
    p.add_argument("--height", type=int, default=480)
    g = p.add_mutually_exclusive_group()
    g.add_argument("--seconds", type=float, help="render frames 0 .. round(S * fps)")
    g.add_argument("--frames", help="A:B, inclusive frame range")
    p.add_argument("--fps", type=float, help="frames per second (default: scene extras fps)")
    p.add_argument("--camera", default="camera_view")
    p.add_argument("--light", default="light")
    p.add_argument("--receiver", default="receiver")
    p.add_argument("--table", default="table")
    p.add_argument("--light-radius", type=float, default=0.03, help="point light radius in m")
    p.add_argument("--light-energy", type=float, help="point light power in W (default: auto)")
    p.add_argument("--keep-light-energy", action="store_true",
                   help="keep the imported energy (cd * 4 pi / 683 W)")
    p.add_argument("--receiver-lift", type=float, default=0.002,
                   help="m; lift the receiver towards the light above a coplanar table top")
    p.add_argument("--world-strength", type=float, default=0.25)
    p.add_argument("--denoise", action="store_true", help="OpenImageDenoise each frame (slower)")
    p.add_argument("--still", metavar="PNG",
                   help="render one frame to this PNG instead of a video (the first frame of "
                        "--frames, else the frame of t)")
    p.add_argument("--crf", default="MEDIUM",
                   help="H.264 quality: LOSSLESS PERC_LOSSLESS HIGH MEDIUM LOW VERYLOW LOWEST")
    return p.parse_args(argv)


def auto_light_energy(light, receiver_objs):
    """Power (W) so that the receiver point nearest the light gets irradiance ~ pi W/m^2,
    i.e. a white diffuse surface there renders near 1.0 (P / (4 pi d^2) = pi)."""
    lpos = light.matrix_world.translation
    best = None
    for o in receiver_objs:
        if o.type != "MESH" or not o.data.vertices:
            continue
        # centre of the receiver's bounding box in world space
        import mathutils
        corners = [o.matrix_world @ mathutils.Vector(c) for c in o.bound_box]
        c = sum(corners, mathutils.Vector((0, 0, 0))) / 8.0
        d = (c - lpos).length
        best = d if best is None else min(best, d)
    if best is None or best <= 0:
        best = 5.0
    return 4.0 * math.pi * math.pi * best * best, best


def lift_receivers(receivers, light, eps):
    """Move each receiver by eps along its normal, towards the light (video only). The table top
    is usually coplanar with the receiver: without this the two z-fight, and the receiver
    shadows the table top it lies on."""
    import mathutils
    lpos = light.matrix_world.translation
    for o in receivers:
        if o.type != "MESH" or not o.data.polygons:
            continue
        mw = o.matrix_world.copy()
        n = (mw.to_3x3().inverted_safe().transposed() @ o.data.polygons[0].normal).normalized()
        corners = [mw @ mathutils.Vector(c) for c in o.bound_box]
        c = sum(corners, mathutils.Vector((0, 0, 0))) / 8.0
        if n.dot(lpos - c) < 0:
            n = -n
        mw.translation = mw.translation + n * eps
        o.matrix_world = mw


def main():
    timer = B.Timer()
    args = parse(B.script_argv())
    if args.width % 2 or args.height % 2:
        B.fail("H.264 needs an even width and height, got %dx%d" % (args.width, args.height))
    try:
        gltf = B.read_glb_json(args.glb)
    except (OSError, B.BsaError, ValueError) as e:
        B.fail(str(e))
    extras = B.scene_extras(gltf)
    try:
        fps, t, t_frame = B.resolve_timing(extras, args.fps, None)
    except B.BsaError as e:
        B.fail(str(e))
    warnings = []

    import bpy

    try:
        scene, _ = B.reset_and_import(args.glb, fps)
    except B.BsaError as e:
        B.fail(str(e))

    # Frame range: 0 .. last key unless asked otherwise.
    if args.still and not args.frames and t_frame is not None:
        a = b = int(round(t_frame))
    elif args.frames:
        try:
            a, b = (int(x) for x in args.frames.split(":"))
        except ValueError:
            B.fail("--frames must be A:B, got %r" % args.frames)
    elif args.seconds is not None:
        a, b = 0, int(round(args.seconds * fps))
    else:
        last = B.last_key_frame(gltf, fps)
        if last is None:
            last = t_frame if t_frame is not None else 0
            warnings.append("no animation found; rendering frames 0..%d" % int(math.ceil(last)))
        a, b = 0, int(math.ceil(last - 1e-6))
    if b < a:
        B.fail("empty frame range %d:%d" % (a, b))
    scene.frame_start, scene.frame_end, scene.frame_step = a, b, 1

    cam = B.find_object(args.camera, "CAMERA")
    if cam is None:
        B.fail("no camera node `%s` in %s" % (args.camera, args.glb))
    scene.camera = cam
    r = scene.render
    r.resolution_x, r.resolution_y = args.width, args.height
    r.resolution_percentage = 100

    roles = B.classify(args.receiver, args.table)
    for o in roles["occluder"] + roles["table"] + roles["receiver"]:
        o.hide_render = False
        o.visible_camera = True
        o.visible_shadow = True
    for o in roles["table"]:
        # As in the solver, the table casts no shadow (it may also be coplanar with the receiver,
        # which would otherwise shadow its top face).
        o.visible_shadow = False
    for o in roles["ignore"]:
        o.hide_render = True

    light = B.find_object(args.light, "LIGHT")
    if light is None:
        B.fail("no light node `%s` in %s" % (args.light, args.glb))
    if roles["table"] and args.receiver_lift > 0:
        lift_receivers(roles["receiver"], light, args.receiver_lift)
    ld = light.data
    imported_energy = ld.energy
    if ld.type == "SUN":
        ld.angle = math.radians(0.5)
        if not args.keep_light_energy:
            ld.energy = args.light_energy or 3.0
        dist = None
    else:
        ld.shadow_soft_size = args.light_radius
        scene.frame_set(a)
        auto, dist = auto_light_energy(light, roles["receiver"])
        if args.light_energy:
            ld.energy = args.light_energy
        elif not args.keep_light_energy:
            ld.energy = auto
    ld.use_shadow = True

    B.cycles_common(scene, samples=args.samples, max_bounces=args.bounces)
    scene.cycles.use_denoising = bool(args.denoise)
    scene.cycles.filter_width = 1.5
    world = bpy.data.worlds.new("bsa_world")
    if world.node_tree is None and hasattr(world, "use_nodes"):
        world.use_nodes = True
    bg = world.node_tree.nodes.get("Background") if world.node_tree else None
    if bg is not None:
        bg.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
        bg.inputs["Strength"].default_value = args.world_strength
    world.color = (0.8 * args.world_strength,) * 3
    scene.world = world
    r.film_transparent = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"

    im = r.image_settings
    if args.still:
        if hasattr(im, "media_type"):
            im.media_type = "IMAGE"
        im.file_format = "PNG"
        im.color_mode = "RGB"
        out = os.path.abspath(args.still)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        r.filepath = out
        r.use_file_extension = False
        scene.frame_set(a)
        t0 = timer()
        bpy.ops.render.render(write_still=True)
        B.result({
            "still": out, "frame": a, "bytes": os.path.getsize(out),
            "light_energy_w": round(ld.energy, 3), "render_seconds": round(timer() - t0, 3),
            "seconds": timer(), "warnings": warnings})
        return

    # Video output. bpy 5.0: media_type BEFORE file_format.
    if hasattr(im, "media_type"):
        im.media_type = "VIDEO"
    im.file_format = "FFMPEG"
    ff = r.ffmpeg
    ff.format = "MPEG4"
    ff.codec = "H264"
    ff.constant_rate_factor = args.crf
    ff.ffmpeg_preset = "GOOD"
    ff.gopsize = max(1, int(round(fps)))
    ff.audio_codec = "NONE"
    tmpdir = tempfile.mkdtemp(prefix="bsa_video_")
    tmp_out = os.path.join(tmpdir, "video.mp4")
    r.filepath = tmp_out
    r.use_file_extension = True

    t0 = timer()
    bpy.ops.render.render(animation=True)
    t_render = round(timer() - t0, 3)
    produced = tmp_out if os.path.exists(tmp_out) else None
    if produced is None:
        cands = [os.path.join(tmpdir, f) for f in os.listdir(tmpdir)]
        produced = max(cands, key=os.path.getsize) if cands else None
    if produced is None or os.path.getsize(produced) == 0:
        B.fail("Blender wrote no video (looked in %s)" % tmpdir)
    out = os.path.abspath(args.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    shutil.move(produced, out)
    shutil.rmtree(tmpdir, ignore_errors=True)

    for w in warnings:
        sys.stderr.write("warning: %s\n" % w)
    summary = {
        "video": out,
        "bytes": os.path.getsize(out),
        "frames": [a, b],
        "frame_count": b - a + 1,
        "fps": fps,
        "t_frame": t_frame,
        "width": args.width,
        "height": args.height,
        "samples": args.samples,
        "light_energy_w": round(ld.energy, 3),
        "imported_light_energy_w": round(imported_energy, 3),
        "light_distance_m": None if dist is None else round(dist, 4),
        "occluders": sorted(o.name for o in roles["occluder"]),
        "blender": bpy.app.version_string,
        "render_seconds": t_render,
        "seconds": timer(),
        "warnings": warnings,
    }
    B.result(summary)


if __name__ == "__main__":
    main()
