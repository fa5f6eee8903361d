"""Import an exported .glb the way the render scripts do and report what Blender sees.

    .venv-blender/bin/python blender/check_import.py -- --glb FILE.glb

Prints one line `BSA_RESULT {...}` with: fps, the frame range (set to 0 .. last key, since
the glTF importer sets none), the frame of t, the cameras (type, ortho scale, lens), the
lights (type, energy in W), the number of actions and animated objects, and the world
pose of every object at the frame of t (location, quaternion w x y z; Blender is Z-up
like the solver's world), and every object's custom properties (from the glTF node extras:
mass_kg, launch_velocity_m_s, angular_velocity_rad_s, launched, scene). The test suite compares
those poses and properties with the solver's.
"""

import argparse
import os
import sys

sys.dont_write_bytecode = True
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402


def plain(value):
    """A custom property as plain JSON: ID property arrays and groups become lists and dicts."""
    if hasattr(value, "to_dict"):
        return {k: plain(v) for k, v in value.to_dict().items()}
    if hasattr(value, "to_list"):
        return [plain(v) for v in value.to_list()]
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, (bool, int, float, str)) or value is None:
        return value
    return str(value)


def main():
    p = argparse.ArgumentParser(prog="check_import.py")
    p.add_argument("--glb", required=True)
    args = p.parse_args(B.script_argv())
    try:
        gltf = B.read_glb_json(args.glb)
        fps, t, frame = B.resolve_timing(B.scene_extras(gltf))
    except (OSError, ValueError, B.BsaError) as e:
        B.fail(str(e))
    if frame is None:
        B.fail("the .glb has no scene extras `t_frame` or `t`")
    import bpy

    try:
        scene, imported = B.reset_and_import(args.glb, fps)
    except B.BsaError as e:
        B.fail(str(e))
    last = B.last_key_frame(gltf, fps)
    scene.frame_start = 0
    scene.frame_end = int(round(last)) if last is not None else 0
    B.set_frame(scene, frame)
    cameras = {}
    lights = {}
    poses = {}
    props = {}
    for o in imported:
        keys = [k for k in o.keys() if not k.startswith("_")]
        if keys:
            props[B.base_name(o.name)] = {k: plain(o[k]) for k in keys}
        if o.type == "CAMERA":
            cameras[B.base_name(o.name)] = {
                "type": o.data.type,
                "ortho_scale": o.data.ortho_scale,
                "lens": o.data.lens,
            }
        elif o.type == "LIGHT":
            lights[B.base_name(o.name)] = {"type": o.data.type, "energy_w": o.data.energy}
        m = o.matrix_world
        loc = m.to_translation()
        q = m.to_quaternion()
        poses[B.base_name(o.name)] = {
            "location": [loc.x, loc.y, loc.z],
            "quaternion_wxyz": [q.w, q.x, q.y, q.z],
        }
    animated = sorted(B.base_name(o.name) for o in imported if o.animation_data and o.animation_data.action)
    B.result({
        "fps": scene.render.fps / scene.render.fps_base,
        "frame_start": scene.frame_start,
        "frame_end": scene.frame_end,
        "frame_t": frame,
        "t": t,
        "cameras": cameras,
        "lights": lights,
        "actions": len(bpy.data.actions),
        "animated_objects": animated,
        "poses_at_t": poses,
        "custom_properties": props,
    })


if __name__ == "__main__":
    main()
