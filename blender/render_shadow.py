"""Render the exact hard-shadow mask of an exported .glb at time t with Cycles.

    .venv-blender/bin/python blender/render_shadow.py -- --glb FILE.glb --out MASK.png \
        [--width W --height H] [--time T] [--fps F]
    blender -b -P blender/render_shadow.py -- --glb FILE.glb --out MASK.png ...

Writes an 8-bit grayscale PNG at the target resolution (top row first): 0 (black) where the
pixel centre is in shadow on the receiver, 255 (white) elsewhere. Prints one line
`BSA_RESULT {"mask": ..., "shadow_pixels": N, "frame": f, ...}` on stdout at the end.

Recipe (measured, see /work/shared/notes/field-notes.md "Blender as a Python module" and
blender/README.md): factory settings with an empty scene; fps from the scene extras BEFORE the
import; orthographic `camera_shadow`; occluders invisible to the camera but casting shadows;
table neither seen nor shadowing; point light radius 0 with huge energy; Cycles CPU, 1 sample,
0 bounces, no world, Standard view transform, filter width 0.01 px, transparent film.
Shadow pixel = alpha > 0.5 and Rec. 709 luma < 0.5.
"""

import argparse
import os
import sys

sys.dont_write_bytecode = True  # keep blender/ free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402

LIGHT_ENERGY_W = 1.0e7  # "huge": every lit receiver pixel saturates to white


def parse(argv):
    p = argparse.ArgumentParser(prog="render_shadow.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--glb", required=True, help="input .glb written by the exporter")
    p.add_argument("--out", required=True, help="output mask PNG (8-bit grayscale, 0 = shadow)")
    p.add_argument("--width", type=int, help="mask width (default: scene extras target_width)")
    p.add_argument("--height", type=int, help="mask height (default: scene extras target_height)")
    p.add_argument("--time", type=float, help="time t in s (default: scene extras t_frame / t)")
    p.add_argument("--fps", type=float, help="frames per second (default: scene extras fps)")
    p.add_argument("--camera", default="camera_shadow", help="orthographic camera node name")
    p.add_argument("--light", default="light", help="light node name")
    p.add_argument("--receiver", default="receiver", help="receiver node name")
    p.add_argument("--table", default="table", help="table node name")
    p.add_argument("--keep-render", metavar="PNG", help="also keep Cycles' raw RGBA render here")
    return p.parse_args(argv)


def main():
    timer = B.Timer()
    args = parse(B.script_argv())
    try:
        gltf = B.read_glb_json(args.glb)
    except (OSError, B.BsaError, ValueError) as e:
        B.fail(str(e))
    extras = B.scene_extras(gltf)
    try:
        fps, t, frame = B.resolve_timing(extras, args.fps, args.time)
    except B.BsaError as e:
        B.fail(str(e))
    if frame is None:
        B.fail("the .glb has no scene extras `t_frame` or `t`: pass --time")
    width = args.width or extras.get("target_width")
    height = args.height or extras.get("target_height")
    if not width or not height:
        B.fail("the .glb has no scene extras target_width/target_height: pass --width and --height")
    width, height = int(width), int(height)
    warnings = []

    import bpy
    import numpy as np

    try:
        scene, _ = B.reset_and_import(args.glb, fps)
    except B.BsaError as e:
        B.fail(str(e))
    t_import = timer()

    # Camera: the orthographic shadow camera, looking along the receiver normal.
    cam = B.find_object(args.camera, "CAMERA")
    if cam is None:
        B.fail("no camera node `%s` in %s" % (args.camera, args.glb))
    if cam.data.type != "ORTHO":
        B.fail("camera `%s` is %s, expected orthographic" % (args.camera, cam.data.type))
    scene.camera = cam
    gcam = B.gltf_camera(gltf, args.camera)
    if gcam and "orthographic" in gcam:
        o = gcam["orthographic"]
        want = 2.0 * max(o["xmag"], o["ymag"])
        if abs(cam.data.ortho_scale - want) > 1e-6 * max(1.0, want):
            warnings.append("ortho_scale %.9g != 2*max(xmag,ymag) %.9g; using the latter"
                            % (cam.data.ortho_scale, want))
            cam.data.ortho_scale = want
        if o["ymag"] > 0:
            a_cam = o["xmag"] / o["ymag"]
            a_img = width / height
            if abs(a_cam - a_img) > 1e-6 * a_cam:
                warnings.append("image aspect %d:%d != camera xmag/ymag %.6g: the mask does not "
                                "cover the camera rectangle exactly" % (width, height, a_cam))
    cam.data.sensor_fit = "AUTO"
    cam.data.shift_x = cam.data.shift_y = 0.0

    r = scene.render
    r.resolution_x, r.resolution_y = width, height
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0

    # Roles.
    roles = B.classify(args.receiver, args.table)
    if not roles["receiver"]:
        B.fail("no receiver node `%s` in %s" % (args.receiver, args.glb))
    if not roles["occluder"]:
        warnings.append("no occluder mesh found")
    for o in roles["occluder"]:
        o.visible_camera = False  # seen through, still casts shadows
        o.visible_shadow = True
        o.hide_render = False
    for o in roles["table"] + roles["ignore"]:
        # The table may be coplanar with the receiver: it must neither be seen nor shadow.
        for attr in ("visible_camera", "visible_shadow", "visible_diffuse", "visible_glossy",
                     "visible_transmission", "visible_volume_scatter"):
            setattr(o, attr, False)
        o.hide_render = True
    # Receiver: plain white diffuse (its exported material may carry a picture), seen by the
    # camera, no shadow terminator offsets (a flat plane needs none).
    white = bpy.data.materials.new("bsa_receiver_white")
    white.diffuse_color = (1.0, 1.0, 1.0, 1.0)
    nt = white.node_tree
    if nt is not None:
        bsdf = nt.nodes.get("Principled BSDF")
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = (1.0, 1.0, 1.0, 1.0)
            bsdf.inputs["Roughness"].default_value = 1.0
            if "Specular IOR Level" in bsdf.inputs:
                bsdf.inputs["Specular IOR Level"].default_value = 0.0
    for o in roles["receiver"]:
        o.visible_camera = True
        o.hide_render = False
        o.shadow_terminator_geometry_offset = 0.0
        o.shadow_terminator_shading_offset = 0.0
        if o.type == "MESH":
            o.data.materials.clear()
            o.data.materials.append(white)
            for poly in o.data.polygons:
                poly.material_index = 0

    # Light: hard point light, huge energy. Any other light is switched off.
    light = B.find_object(args.light, "LIGHT")
    if light is None:
        B.fail("no light node `%s` in %s" % (args.light, args.glb))
    for o in bpy.data.objects:
        if o.type == "LIGHT" and o is not light:
            o.hide_render = True
            warnings.append("extra light `%s` disabled" % o.name)
    ld = light.data
    if ld.type == "SUN":
        ld.angle = 0.0
        ld.energy = 1.0e4
    else:
        ld.shadow_soft_size = 0.0
        ld.energy = LIGHT_ENERGY_W
        if ld.type == "SPOT":
            warnings.append("spot light: pixels outside its cone are unlit and read as shadow")
    ld.use_shadow = True
    if hasattr(ld, "use_soft_falloff"):
        ld.use_soft_falloff = False
    light.hide_render = False

    # Cycles recipe.
    B.cycles_common(scene, samples=1, max_bounces=0)
    scene.cycles.filter_width = 0.01
    scene.world = None  # a default world is grey and lights the shadow
    r.film_transparent = True
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.display_settings.display_device = "sRGB"
    scene.sequencer_colorspace_settings.name = "sRGB"

    B.set_frame(scene, frame)

    # Render to a temporary PNG, read it back.
    im = r.image_settings
    if hasattr(im, "media_type"):  # bpy 5.0
        im.media_type = "IMAGE"
    im.file_format = "PNG"
    im.color_mode = "RGBA"
    im.color_depth = "8"
    im.compression = 0
    r.use_file_extension = False
    with B.scratch_dir("bsa_shadow_") as tmpdir:
        raw_path = os.path.join(tmpdir, "render.png")
        r.filepath = raw_path
        t0 = timer()
        bpy.ops.render.render(write_still=True)
        t_render = round(timer() - t0, 3)
        if not os.path.exists(raw_path):
            B.fail("Cycles did not write %s" % raw_path)
        if args.keep_render:
            import shutil
            shutil.copyfile(raw_path, args.keep_render)
        img = bpy.data.images.load(raw_path)
        if tuple(img.size) != (width, height):
            B.fail("render size %r != %dx%d" % (tuple(img.size), width, height))
        px = np.empty(width * height * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
        bpy.data.images.remove(img)
    px = px.reshape(height, width, 4)[::-1]  # Image.pixels rows run bottom-up
    luma = 0.2126 * px[..., 0] + 0.7152 * px[..., 1] + 0.0722 * px[..., 2]
    shadow = (px[..., 3] > 0.5) & (luma < 0.5)
    mask = np.where(shadow, 0, 255).astype(np.uint8)
    B.write_gray_png(args.out, mask.tobytes(), width, height)

    for w in warnings:
        sys.stderr.write("warning: %s\n" % w)
    summary = {
        "mask": os.path.abspath(args.out),
        "width": width,
        "height": height,
        "shadow_pixels": int(shadow.sum()),
        "covered_pixels": int((px[..., 3] > 0.5).sum()),
        "frame": frame,
        "t": t,
        "fps": fps,
        "occluders": sorted(o.name for o in roles["occluder"]),
        "blender": bpy.app.version_string,
        "import_seconds": t_import,
        "render_seconds": t_render,
        "seconds": timer(),
        "warnings": warnings,
    }
    B.result(summary)


if __name__ == "__main__":
    main()
