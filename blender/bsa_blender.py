"""Shared helpers for blender/render_shadow.py and blender/render_video.py.

Works both under the PyPI `bpy` module (`.venv-blender/bin/python script.py -- ...`) and inside a
Blender binary (`blender -b -P script.py -- ...`). Only the standard library, `bpy` and `numpy`
(a dependency of `bpy`, and bundled with Blender) are used.

The .glb contract (written by the Rust exporter, see blender/README.md):
  * scene extras: `fps` (required unless --fps), `t` and/or `t_frame` (time of the picture),
    `target_width`, `target_height` (mask size);
  * nodes: `camera_shadow` (orthographic, looks along the receiver normal), `camera_view`
    (perspective), `light` (KHR_lights_punctual point light), `receiver`, `table`; every other
    mesh node is an occluder. A node may instead carry extras {"bsa_role": "receiver" | "table" |
    "occluder" | "ignore"}.
"""

import json
import math
import os
import re
import struct
import sys
import tempfile
import time
import zlib

RESULT_PREFIX = "BSA_RESULT "


class BsaError(Exception):
    pass


def script_argv():
    """Arguments after the first `--` (both bpy-module and `blender -b -P` invocations)."""
    argv = sys.argv
    if "--" in argv:
        return argv[argv.index("--") + 1:]
    return argv[1:]


def result(value):
    """Print the machine-readable result line that `bsa` looks for."""
    print(RESULT_PREFIX + json.dumps(value), flush=True)


def scratch_dir(prefix):
    """A temporary folder for renders, removed with everything in it when the `with` block
    ends, by a result, a failure (`fail` exits) or an exception alike."""
    return tempfile.TemporaryDirectory(prefix=prefix, ignore_cleanup_errors=True)


def fail(msg, code=2):
    sys.stderr.write("error: %s\n" % msg)
    print(RESULT_PREFIX + json.dumps({"error": msg}), flush=True)
    sys.exit(code)


# ---------------------------------------------------------------------------------------------
# .glb JSON chunk, read with the standard library (before bpy touches the file)

def read_glb_json(path):
    with open(path, "rb") as f:
        data = f.read()
    if len(data) < 20:
        raise BsaError("%s: too short for a .glb" % path)
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF":
        raise BsaError("%s: not a binary glTF (.glb) file" % path)
    if version != 2:
        raise BsaError("%s: glTF version %d, expected 2" % (path, version))
    chunk_len, chunk_type = struct.unpack_from("<II", data, 12)
    if chunk_type != 0x4E4F534A:  # b"JSON"
        raise BsaError("%s: first chunk is not JSON" % path)
    return json.loads(data[20:20 + chunk_len].decode("utf-8"))


def scene_extras(gltf):
    """Extras of the default scene, falling back to the root / asset extras."""
    out = {}
    for src in (gltf.get("asset", {}).get("extras"), gltf.get("extras")):
        if isinstance(src, dict):
            out.update(src)
    scenes = gltf.get("scenes") or []
    idx = gltf.get("scene", 0)
    if 0 <= idx < len(scenes) and isinstance(scenes[idx].get("extras"), dict):
        out.update(scenes[idx]["extras"])
    return out


def gltf_node(gltf, name):
    for n in gltf.get("nodes", []):
        if n.get("name") == name:
            return n
    return None


def gltf_camera(gltf, node_name):
    n = gltf_node(gltf, node_name)
    if n is None or "camera" not in n:
        return None
    return gltf["cameras"][n["camera"]]


def gltf_last_key_seconds(gltf):
    """Largest animation sampler input time (accessor max, else None)."""
    best = None
    accessors = gltf.get("accessors", [])
    for anim in gltf.get("animations", []):
        for s in anim.get("samplers", []):
            acc = accessors[s["input"]]
            mx = acc.get("max")
            if mx:
                best = mx[0] if best is None else max(best, mx[0])
    return best


def resolve_timing(extras, fps_arg=None, time_arg=None):
    """(fps, t, frame) from the extras, with command-line overrides. frame = t * fps."""
    fps = fps_arg if fps_arg is not None else extras.get("fps")
    if fps is None:
        raise BsaError("the .glb has no scene extras `fps`: pass --fps")
    fps = float(fps)
    if not fps > 0:
        raise BsaError("fps must be > 0, got %r" % fps)
    if time_arg is not None:
        t = float(time_arg)
        frame = t * fps
    elif "t_frame" in extras:
        frame = float(extras["t_frame"])
        t = float(extras.get("t", frame / fps))
    elif "t" in extras:
        t = float(extras["t"])
        frame = t * fps
    else:
        t = frame = None
    if frame is not None and abs(frame - round(frame)) < 1e-6:
        frame = float(round(frame))
    return fps, t, frame


# ---------------------------------------------------------------------------------------------
# Blender side

def reset_and_import(glb, fps):
    """Factory settings with an empty scene, fps set BEFORE import (the importer keys at t * fps)."""
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    fps_int = int(round(fps))
    if abs(fps - fps_int) > 1e-9:
        # Not expected from the Rust side; keep the exact rate through fps_base.
        sys.stderr.write("warning: non-integer fps %r, using fps=%d fps_base=%r\n"
                         % (fps, max(fps_int, 1), max(fps_int, 1) / fps))
        fps_int = max(fps_int, 1)
        scene.render.fps = fps_int
        scene.render.fps_base = fps_int / fps
    else:
        scene.render.fps = fps_int
        scene.render.fps_base = 1.0
    before = set(bpy.data.objects)
    res = bpy.ops.import_scene.gltf(filepath=os.path.abspath(glb))
    if "FINISHED" not in res:
        raise BsaError("glTF import of %s failed: %r" % (glb, res))
    scene = bpy.context.scene
    imported = [o for o in bpy.data.objects if o not in before]
    activate_stashed_animations(imported)
    return scene, imported


def activate_stashed_animations(objects):
    """The importer makes only the FIRST glTF animation active; the others land on (muted) NLA
    tracks. The Rust exporter writes a single animation, but if a file has several, play them all:
    give every object without an active action the action of its first NLA strip."""
    fixed = []
    for o in objects:
        ad = o.animation_data
        if ad is None or ad.action is not None:
            continue
        for track in ad.nla_tracks:
            strips = [s for s in track.strips if s.action is not None]
            if not strips:
                continue
            strip = strips[0]
            ad.action = strip.action
            slot = getattr(strip, "action_slot", None)
            if slot is not None and hasattr(ad, "action_slot"):
                try:
                    ad.action_slot = slot
                except Exception:
                    pass
            track.mute = True
            fixed.append(o.name)
            break
    if fixed:
        sys.stderr.write("warning: the .glb has several animations; activated the stashed ones of %s "
                         "(write all channels in ONE animation)\n" % ", ".join(sorted(fixed)))
    return fixed


_SUFFIX = re.compile(r"\.\d{3}$")


def base_name(name):
    return _SUFFIX.sub("", name)


def find_object(name, kind=None):
    """Object by exact name, else by name without Blender's `.001` suffix."""
    import bpy
    o = bpy.data.objects.get(name)
    if o is not None and (kind is None or o.type == kind):
        return o
    for o in bpy.data.objects:
        if base_name(o.name) == name and (kind is None or o.type == kind):
            return o
    return None


def role_of(obj, receiver_name="receiver", table_name="table"):
    """'receiver', 'table', 'occluder' or 'ignore' for a mesh object; None for non-meshes."""
    role = None
    try:
        role = obj.get("bsa_role")
    except Exception:
        role = None
    if isinstance(role, str) and role in ("receiver", "table", "occluder", "ignore"):
        return role
    if obj.type not in ("MESH", "CURVE", "SURFACE", "META", "FONT"):
        return None
    # The object itself, or an ancestor (a node with a mesh child), named receiver/table.
    o = obj
    while o is not None:
        b = base_name(o.name)
        if b == receiver_name:
            return "receiver"
        if b == table_name:
            return "table"
        o = o.parent
    return "occluder"


def classify(receiver_name="receiver", table_name="table"):
    import bpy
    roles = {"receiver": [], "table": [], "occluder": [], "ignore": []}
    for o in bpy.data.objects:
        r = role_of(o, receiver_name, table_name)
        if r is not None:
            roles[r].append(o)
    return roles


def action_fcurves(action):
    """Every F-curve of an action: Blender 5.0 keeps them in layers, strips and channel bags (one
    bag per slot, i.e. per animated object); older versions in `action.fcurves`."""
    if hasattr(action, "layers") and len(action.layers):
        for layer in action.layers:
            for strip in layer.strips:
                for bag in getattr(strip, "channelbags", []):
                    yield from bag.fcurves
    elif hasattr(action, "fcurves"):
        yield from action.fcurves


def set_frame(scene, frame):
    """Go to a (possibly fractional) frame."""
    fi = math.floor(frame)
    sub = frame - fi
    if sub > 1e-9:
        scene.frame_set(int(fi), subframe=sub)
    else:
        scene.frame_set(int(fi))


def last_key_frame(gltf, fps):
    """Last animation key in frames: from the glb accessors, else from the imported actions."""
    import bpy
    t = gltf_last_key_seconds(gltf)
    if t is not None:
        return t * fps
    best = None
    for a in bpy.data.actions:
        try:
            end = a.frame_range[1]
        except Exception:
            continue
        best = end if best is None else max(best, end)
    return best


def cycles_common(scene, samples, max_bounces):
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    c.samples = samples
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.max_bounces = max_bounces
    c.diffuse_bounces = min(max_bounces, c.diffuse_bounces)
    c.glossy_bounces = min(max_bounces, c.glossy_bounces)
    c.transmission_bounces = min(max_bounces, c.transmission_bounces)
    c.volume_bounces = 0
    c.transparent_max_bounces = max(max_bounces, 0)
    c.caustics_reflective = False
    c.caustics_refractive = False
    c.seed = 0
    scene.render.use_motion_blur = False
    scene.render.resolution_percentage = 100
    scene.render.use_border = False
    scene.render.use_persistent_data = False


def image_output(scene, path):
    """Render stills to `path` as an 8-bit RGB PNG."""
    r = scene.render
    im = r.image_settings
    if hasattr(im, "media_type"):  # bpy 5.0: media_type before file_format
        im.media_type = "IMAGE"
    im.file_format = "PNG"
    im.color_mode = "RGB"
    im.color_depth = "8"
    r.filepath = os.path.abspath(path)
    r.use_file_extension = False


def load_pixels(path):
    """A PNG as a (height, width, 4) float array, top row first (Blender's rows run bottom-up)."""
    import bpy
    import numpy as np
    img = bpy.data.images.load(os.path.abspath(path))
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1]


# ---------------------------------------------------------------------------------------------
# PNG writing (8-bit grayscale), standard library only

def write_gray_png(path, rows, width, height):
    """rows: bytes-like of width*height values, top row first."""
    raw = bytearray()
    for j in range(height):
        raw.append(0)  # filter type None
        raw += rows[j * width:(j + 1) * width]

    def chunk(tag, payload):
        c = struct.pack(">I", len(payload)) + tag + payload
        return c + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)

    png = b"\x89PNG\r\n\x1a\n"
    png += chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0))
    png += chunk(b"IDAT", zlib.compress(bytes(raw), 9))
    png += chunk(b"IEND", b"")
    d = os.path.dirname(os.path.abspath(path))
    os.makedirs(d, exist_ok=True)
    tmp = os.path.join(d, ".%s.tmp%d" % (os.path.basename(path), os.getpid()))
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


class Timer:
    def __init__(self):
        self.t0 = time.perf_counter()

    def __call__(self):
        return round(time.perf_counter() - self.t0, 3)
