"""Render the film of a .blend written by `bsa blend`: an MP4 (H.264) and the contact sheet's stills.

    .venv-blender/bin/python blender/render_video.py -- --blend FILE.blend --out VIDEO.mp4 \
        [--samples N] [--resolution WxH] [--seconds S] [--stills DIR] [--no-video]
    blender -b -P blender/render_video.py -- --blend FILE.blend ...

Renders the file's own scene as saved (its camera `camera_view`, frame range, fps, light, world,
Cycles settings); only the sample count, the resolution, denoising (off unless --denoise) and,
with --seconds, the end of the frame range are overridden. --stills DIR also renders the contact sheet's frames (the scene's custom
property `bsa_contact_sheet`: launch, mid-flight, t, after) as DIR/still_<k>.png; `bsa video`
lays them out with their labels. Prints one line `BSA_RESULT {"video": ..., "stills": [...], ...}`.
"""

import argparse
import json
import os
import shutil
import sys

sys.dont_write_bytecode = True  # keep blender/ free of __pycache__
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bsa_blender as B  # noqa: E402


def parse(argv):
    p = argparse.ArgumentParser(prog="render_video.py", description=__doc__.split("\n\n")[0])
    p.add_argument("--blend", required=True)
    p.add_argument("--out", help="output .mp4 (not with --no-video)")
    p.add_argument("--samples", type=int, help="Cycles samples per pixel (default: the file's)")
    p.add_argument("--denoise", action="store_true",
                   help="keep the file's denoising (OpenImageDenoise; slow on a CPU); off otherwise")
    p.add_argument("--resolution", help="WxH (default: the file's); even sides for H.264")
    p.add_argument("--seconds", type=float, help="render only the first S seconds of film")
    p.add_argument("--stills", help="folder for the contact sheet's stills")
    p.add_argument("--no-video", action="store_true", help="render the stills only")
    p.add_argument("--crf", default="MEDIUM",
                   help="H.264 quality: LOSSLESS PERC_LOSSLESS HIGH MEDIUM LOW VERYLOW LOWEST")
    return p.parse_args(argv)


def main():
    timer = B.Timer()
    args = parse(B.script_argv())
    if not args.no_video and not args.out:
        B.fail("--out is needed unless --no-video")
    if not os.path.isfile(args.blend):
        B.fail("%s does not exist: run `bsa blend` first" % args.blend)
    import bpy

    bpy.ops.wm.open_mainfile(filepath=os.path.abspath(args.blend))
    scene = bpy.context.scene
    if "bsa_t_frame" not in scene or scene.camera is None:
        B.fail("%s is not a .blend of `bsa blend` (no bsa_t_frame or no camera in scene %s)"
               % (args.blend, scene.name))
    r = scene.render
    if args.resolution:
        try:
            r.resolution_x, r.resolution_y = (int(v) for v in args.resolution.lower().split("x"))
        except ValueError:
            B.fail("--resolution must be WxH, got %r" % args.resolution)
    r.resolution_percentage = 100
    if args.samples:
        scene.cycles.samples = args.samples
        scene.eevee.taa_render_samples = args.samples
    if not args.denoise:
        scene.cycles.use_denoising = False
    fps = scene.render.fps / scene.render.fps_base
    a, b = scene.frame_start, scene.frame_end
    if args.seconds is not None:
        b = min(b, a + max(0, int(round(args.seconds * fps))))
    warnings = []

    stills = []
    if args.stills:
        os.makedirs(args.stills, exist_ok=True)
        sheet = json.loads(scene.get("bsa_contact_sheet", "[]"))
        for k, s in enumerate(sheet):
            path = os.path.abspath(os.path.join(args.stills, "still_%d.png" % k))
            scene.frame_set(int(s["frame"]))
            B.image_output(scene, path)
            t0 = timer()
            bpy.ops.render.render(write_still=True)
            stills.append({"label": s["label"], "frame": s["frame"], "png": path,
                           "render_seconds": round(timer() - t0, 3)})

    video = None
    t_render = 0.0
    if not args.no_video:
        if r.resolution_x % 2 or r.resolution_y % 2:
            B.fail("H.264 needs an even width and height, got %dx%d" % (r.resolution_x, r.resolution_y))
        scene.frame_start, scene.frame_end = a, b
        im = r.image_settings
        if hasattr(im, "media_type"):  # bpy 5.0: media_type BEFORE file_format
            im.media_type = "VIDEO"
        im.file_format = "FFMPEG"
        ff = r.ffmpeg
        ff.format = "MPEG4"
        ff.codec = "H264"
        ff.constant_rate_factor = args.crf
        ff.ffmpeg_preset = "GOOD"
        ff.gopsize = max(1, int(round(fps)))
        ff.audio_codec = "NONE"
        with B.scratch_dir("bsa_video_") as tmpdir:
            r.filepath = os.path.join(tmpdir, "video.mp4")
            r.use_file_extension = True
            t0 = timer()
            bpy.ops.render.render(animation=True)
            t_render = round(timer() - t0, 3)
            cands = [os.path.join(tmpdir, f) for f in os.listdir(tmpdir)]
            produced = max(cands, key=os.path.getsize) if cands else None
            if produced is None or os.path.getsize(produced) == 0:
                B.fail("Blender wrote no video (looked in %s)" % tmpdir)
            video = os.path.abspath(args.out)
            os.makedirs(os.path.dirname(video), exist_ok=True)
            shutil.move(produced, video)

    B.result({
        "video": video,
        "bytes": os.path.getsize(video) if video else 0,
        "frames": [a, b],
        "frame_count": b - a + 1,
        "fps": fps,
        "t_frame": scene["bsa_t_frame"],
        "width": r.resolution_x,
        "height": r.resolution_y,
        "samples": scene.cycles.samples,
        "engine": scene.render.engine,
        "camera": scene.camera.name,
        "stills": stills,
        "blender": bpy.app.version_string,
        "render_seconds": t_render,
        "seconds": timer(),
        "warnings": warnings,
    })


if __name__ == "__main__":
    main()
