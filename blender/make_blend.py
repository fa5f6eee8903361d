"""Write a .blend ready to render from an exported .glb and the plan of `bsa blend`.

    .venv-blender/bin/python blender/make_blend.py -- --glb FILE.glb --plan PLAN.json --out FILE.blend

`bsa blend` computes the plan (src/output/blend/: the frame of every key, the view camera's
keyframes, the picture's rectangle, the contact sheet's frames, the curves) and runs this script,
which only applies it (see docs/blender.md):

  * fps set before the import (the importer keys at t * fps), then every key of the animation
    moved to its planned frame: the launch shifted by a fraction of a frame so that t is a whole
    frame, and the optional slow motion around t, keyed on every one of its frames (the pose
    of the motion's time that frame shows) so that its rate eases smoothly;
  * frame range from the launch to the first frame where every body is at rest; a marker `t`;
  * `camera_view` (16:9, vertical field of view from the plan) keyed from the wide shot of the
    motion to the close shot of the picture at t and back; the scene's camera; the resolution;
  * `camera_shadow` (orthographic, the picture's rectangle) clipped to the 5 cm above the
    receiver, so that it shows the shadow and not the bodies in flight, in a second scene
    `<name>_shadow` that shares every object but the curves, rendered at the target's size;
  * a hard shadow in both engines: point light radius 0, Cycles (64 samples, denoised) and
    EEVEE (shadows on, no filtering or jitter, fine shadow maps), a dim grey world (strength 0.05);
  * collections `bodies`, `stage` (receiver, table), `lights`, `cameras`, `trajectories`
    (curves of each body's flight to t, if the plan has them: seen by the camera only, so that
    they neither shadow the picture nor light the scene);
  * custom properties on the scene for the renderers (bsa_t_frame, bsa_contact_sheet, ...).

Prints one line `BSA_RESULT {...}` (frames, fps, t_frame, camera, file size) on stdout.
"""

import argparse
import json
import math
import os
import sys

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402

CYCLES_SAMPLES = 64
EEVEE_SAMPLES = 64
WORLD_STRENGTH = 0.05
SHADOW_CLIP_M = 0.05  # the shadow camera sees only this far above the receiver


def retime(bpy, np, fps, times, frames, t_frame):
    """Move every key of every action from frame time * fps (the importer's) to its planned
    frame; keys are matched by time, so the map is exact at the keys and linear between them."""
    moved = 0
    for action in bpy.data.actions:
        for fc in B.action_fcurves(action):
            for kp in fc.keyframe_points:
                old = kp.co.x
                new = float(np.interp(old / fps, times, frames))
                if abs(new - t_frame) < 1e-3:
                    new = float(t_frame)
                d = new - old
                kp.co.x = new
                kp.handle_left.x += d
                kp.handle_right.x += d
                moved += 1
            fc.update()
    return moved


def organise(bpy, scene, roles):
    """Collections for the artist: bodies, stage, lights, cameras."""
    groups = {
        "bodies": roles["occluder"],
        "stage": roles["receiver"] + roles["table"],
        "lights": [o for o in scene.collection.objects if o.type == "LIGHT"],
        "cameras": [o for o in scene.collection.objects if o.type == "CAMERA"],
    }
    made = {}
    for name, objs in groups.items():
        coll = bpy.data.collections.new(name)
        scene.collection.children.link(coll)
        for o in objs:
            for c in list(o.users_collection):
                c.objects.unlink(o)
            coll.objects.link(o)
        made[name] = coll
    return made


def view_camera(bpy, mathutils, cam, plan):
    c = plan["camera"]
    cam.data.type = "PERSP"
    cam.data.sensor_fit = "VERTICAL"
    cam.data.angle_y = c["fov_y_rad"]
    far = max(mathutils.Vector(k["location"]).length for k in c["keys"])
    cam.data.clip_start = 0.02
    cam.data.clip_end = max(100.0, 20.0 * far)
    cam.rotation_mode = "QUATERNION"
    if cam.animation_data:
        cam.animation_data_clear()
    for k in c["keys"]:
        cam.location = k["location"]
        cam.rotation_quaternion = k["rotation_wxyz"]
        cam.keyframe_insert("location", frame=k["frame"])
        cam.keyframe_insert("rotation_quaternion", frame=k["frame"])


def shadow_camera(cam, receiver_point, normal):
    """Clip the orthographic camera to the few centimetres above the receiver: it then shows
    the shadow, not the bodies between it and the light (in Cycles and in EEVEE alike)."""
    d = abs((cam.matrix_world.translation - receiver_point).dot(normal))
    cam.data.clip_start = max(1e-3, d - SHADOW_CLIP_M)
    cam.data.clip_end = d + 1.0
    return d


def hard_shadow_settings(scene, world):
    """Cycles and EEVEE settings that draw the point light's hard shadow."""
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = CYCLES_SAMPLES
    c.use_denoising = True
    c.max_bounces = 4
    scene.render.use_motion_blur = False
    scene.render.resolution_percentage = 100
    scene.world = world
    scene.view_settings.view_transform = "AgX"
    e = scene.eevee
    e.taa_render_samples = EEVEE_SAMPLES
    e.use_shadows = True
    e.shadow_ray_count = 1
    e.shadow_step_count = 6
    e.shadow_resolution_scale = 1.0


def dim_world(bpy):
    world = bpy.data.worlds.new("bsa_world")
    if hasattr(world, "use_nodes"):
        world.use_nodes = True
    bg = world.node_tree.nodes.get("Background") if world.node_tree else None
    if bg is not None:
        bg.inputs["Color"].default_value = (0.8, 0.8, 0.8, 1.0)
        bg.inputs["Strength"].default_value = WORLD_STRENGTH
    world.color = (0.8 * WORLD_STRENGTH,) * 3
    return world


def trajectory_curves(bpy, coll, curves, width):
    for c in curves:
        cu = bpy.data.curves.new(c["name"] + "_flight", "CURVE")
        cu.dimensions = "3D"
        cu.bevel_depth = width
        cu.bevel_resolution = 2
        sp = cu.splines.new("POLY")
        sp.points.add(len(c["points"]) - 1)
        for p, xyz in zip(sp.points, c["points"]):
            p.co = (xyz[0], xyz[1], xyz[2], 1.0)
        obj = bpy.data.objects.new(c["name"] + "_flight", cu)
        # Seen by the camera only: a curve must neither shadow the picture nor light or
        # reflect into the scene.
        for flag in ("visible_shadow", "visible_diffuse", "visible_glossy",
                     "visible_transmission", "visible_volume_scatter"):
            setattr(obj, flag, False)
        mat = bpy.data.materials.new(c["name"] + "_flight")
        mat.diffuse_color = (1.0, 0.45, 0.1, 1.0)
        if hasattr(mat, "use_nodes"):
            mat.use_nodes = True
        bsdf = mat.node_tree.nodes.get("Principled BSDF") if mat.node_tree else None
        if bsdf is not None:
            bsdf.inputs["Base Color"].default_value = (1.0, 0.45, 0.1, 1.0)
        cu.materials.append(mat)
        coll.objects.link(obj)


def main():
    timer = B.Timer()
    p = argparse.ArgumentParser(prog="make_blend.py")
    p.add_argument("--glb", required=True)
    p.add_argument("--plan", required=True)
    p.add_argument("--out", required=True)
    args = p.parse_args(B.script_argv())
    try:
        with open(args.plan) as f:
            plan = json.load(f)
        B.read_glb_json(args.glb)
    except (OSError, ValueError, B.BsaError) as e:
        B.fail(str(e))
    import bpy
    import mathutils
    import numpy as np

    fps = plan["fps"]
    try:
        scene, imported = B.reset_and_import(args.glb, fps)
    except B.BsaError as e:
        B.fail(str(e))
    name = plan["scene"]
    scene.name = name
    t_frame = plan["t_frame"]
    # Slow motion: the pose at each of its frames, read at the importer's timing first.
    extra = plan["frame_times"]
    captured = []
    for action in bpy.data.actions:
        for fc in B.action_fcurves(action):
            captured.append((fc, [fc.evaluate(time * fps) for _, time in extra]))
    moved = retime(bpy, np, fps, np.array(plan["key_times_s"]), np.array(plan["key_frames"]), t_frame)
    for fc, values in captured:
        for (frame, _), value in zip(extra, values):
            fc.keyframe_points.insert(frame, value, options={"FAST"})
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"
        fc.update()
    scene.frame_start = plan["frame_start"]
    scene.frame_end = plan["frame_end"]
    scene.frame_step = 1
    scene.timeline_markers.new("t", frame=t_frame)
    # A sequence's later pictures: one marker each.
    for m in plan["markers"]:
        scene.timeline_markers.new(m["label"], frame=m["frame"])

    roles = B.classify()
    colls = organise(bpy, scene, roles)
    cam_view = B.find_object("camera_view", "CAMERA")
    cam_shadow = B.find_object("camera_shadow", "CAMERA")
    light = B.find_object("light", "LIGHT")
    if cam_view is None or cam_shadow is None or light is None or not roles["receiver"]:
        B.fail("%s lacks camera_view, camera_shadow, light or receiver" % args.glb)
    view_camera(bpy, mathutils, cam_view, plan)
    receiver = roles["receiver"][0]
    normal = (receiver.matrix_world.to_3x3() @ receiver.data.polygons[0].normal).normalized()
    shadow_distance = shadow_camera(cam_shadow, receiver.matrix_world.translation, normal)

    # A hard shadow: a point light of radius 0; EEVEE's shadow maps unfiltered, unjittered.
    ld = light.data
    ld.shadow_soft_size = 0.0
    ld.use_shadow = True
    for attr, value in (("shadow_filter_radius", 0.0), ("use_shadow_jitter", False),
                        ("shadow_maximum_resolution", 0.0005)):
        if hasattr(ld, attr):
            setattr(ld, attr, value)

    world = dim_world(bpy)
    hard_shadow_settings(scene, world)
    scene.camera = cam_view
    scene.render.resolution_x, scene.render.resolution_y = plan["resolution"]
    scene.render.fps, scene.render.fps_base = fps, 1.0

    if plan["curves"]:
        coll = bpy.data.collections.new("trajectories")
        scene.collection.children.link(coll)
        c = plan["picture_corners"]
        width = 0.002 * max(1.0, math.dist(c[0], c[1]) + math.dist(c[1], c[2]))
        trajectory_curves(bpy, coll, plan["curves"], width)

    # The shadow scene: the same objects (not the curves), the shadow camera, the target's size.
    shadow = bpy.data.scenes.new(name + "_shadow")
    for coll in colls.values():
        shadow.collection.children.link(coll)
    hard_shadow_settings(shadow, world)
    shadow.camera = cam_shadow
    shadow.render.resolution_x, shadow.render.resolution_y = plan["target_size"]
    shadow.render.fps, shadow.render.fps_base = fps, 1.0
    shadow.frame_start, shadow.frame_end = scene.frame_start, scene.frame_end
    shadow.timeline_markers.new("t", frame=t_frame)

    sheet = [{"label": s["label"], "frame": s["frame"]} for s in plan["contact_sheet"]]
    for s in (scene, shadow):
        s["bsa_scene"] = name
        s["bsa_t_s"] = plan["t_s"]
        s["bsa_t_frame"] = t_frame
        s["bsa_launch_frame"] = plan["launch_frame"]
        s["bsa_readable_frames"] = plan["readable"]["frames"]
        s["bsa_contact_sheet"] = json.dumps(sheet)
        s["bsa_target_size"] = plan["target_size"]
        if plan["slow_motion"]:
            s["bsa_slow_motion_factor"] = plan["slow_motion"]["factor"]
    B.set_frame(shadow, t_frame)
    B.set_frame(scene, t_frame)

    for img in bpy.data.images:
        if img.source == "FILE" and img.packed_file is None:
            img.pack()
    out = os.path.abspath(args.out)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    tmp = os.path.join(os.path.dirname(out), ".%s.tmp%d.blend" % (os.path.basename(out), os.getpid()))
    bpy.ops.wm.save_as_mainfile(filepath=tmp, compress=True, relative_remap=False)
    os.replace(tmp, out)
    B.result({
        "blend": out,
        "bytes": os.path.getsize(out),
        "scene": name,
        "shadow_scene": shadow.name,
        "fps": fps,
        "frames": [scene.frame_start, scene.frame_end],
        "t_frame": t_frame,
        "keys_moved": moved,
        "collections": sorted(colls),
        "shadow_camera_clip_m": [cam_shadow.data.clip_start, cam_shadow.data.clip_end],
        "shadow_camera_distance_m": shadow_distance,
        "blender": bpy.app.version_string,
        "seconds": timer(),
    })


if __name__ == "__main__":
    main()
