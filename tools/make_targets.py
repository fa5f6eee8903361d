#!/usr/bin/env python3
"""Make the 640 x 480 target pictures of the fly, tbc and thinker scenes.

    apt-get update && apt-get install -y fonts-noto-cjk fonts-rocknroll
    python3 -m venv .venv && .venv/bin/pip install pillow==13.0.0
    .venv/bin/python tools/make_targets.py            # writes the three targets
    .venv/bin/python tools/make_targets.py --preview  # also docs/images/targets.png

Run from anywhere; paths are relative to the repository root. See docs/targets.md for
the fonts (Debian packages fonts-noto-cjk and fonts-rocknroll) and licences.

Every target is rendered at SS x the final size with anti-aliasing, box-filtered down
(so a pixel's grey is its coverage) and thresholded at half coverage: the result is
binary (0 = shadow, 255 = background), 8-bit grayscale, with the shape's true outline
and no grey left for the solver's half-luminance threshold to be ambiguous about. The
shape's ink bounding box is scaled to a fixed share of the frame and centred. The output
depends only on the font files, tools/thinker.svg and the Pillow version.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

try:
    from PIL import Image, ImageDraw, ImageFont
except ImportError:
    sys.exit("make_targets.py needs Pillow: python3 -m venv .venv && "
             ".venv/bin/pip install pillow==13.0.0, then run it with .venv/bin/python")

ROOT = Path(__file__).resolve().parent.parent
W, H = 640, 480
SS = 4  # supersampling factor

NOTO_SANS_CJK_BOLD = "/usr/share/fonts/opentype/noto/NotoSansCJK-Bold.ttc"
NOTO_SC_INDEX = 2  # face 2 of the collection is "Noto Sans CJK SC" (simplified forms)
ROCKNROLL = "/usr/share/fonts/truetype/rocknroll/RocknRollOne-Regular.ttf"

# name -> how to draw it and how large: the ink bounding box is scaled so that its
# height is `height` x 480, unless its width would then exceed `width` x 640.
TARGETS = {
    "fly": dict(kind="text", text="\u98de", font=NOTO_SANS_CJK_BOLD, index=NOTO_SC_INDEX,
                height=0.70, width=0.80),
    "tbc": dict(kind="text", text="\u3064\u3065\u304f", font=ROCKNROLL, index=0,
                height=0.70, width=0.82),
    "thinker": dict(kind="svg", svg=ROOT / "tools" / "thinker.svg", height=0.74, width=0.80),
}


# ----------------------------------------------------------------------------- helpers
def binarize(img_ss: Image.Image) -> Image.Image:
    """SS x supersampled 'L' picture (0 = ink) -> binary picture at 1/SS the size."""
    small = img_ss.reduce(SS)  # box filter: grey = 255 * (1 - coverage)
    return small.point(lambda v: 0 if v < 128 else 255, mode="L")


def place(mask: Image.Image) -> Image.Image:
    """Crop a binary picture to its ink and centre it in a W x H white frame."""
    inverted = mask.point(lambda v: 255 - v)
    box = inverted.getbbox()
    if box is None:
        raise SystemExit("empty drawing")
    ink = mask.crop(box)
    out = Image.new("L", (W, H), 255)
    out.paste(ink, ((W - ink.width) // 2, (H - ink.height) // 2))
    return out


def fit_scale(w: float, h: float, spec: dict) -> float:
    return min(spec["height"] * H / h, spec["width"] * W / w)


# ------------------------------------------------------------------------------- text
def draw_text(text: str, font: ImageFont.FreeTypeFont) -> Image.Image:
    """The text in black on white with anti-aliasing, on a canvas with room around it."""
    l, t, r, b = font.getbbox(text)
    pad = 8 * SS
    canvas = Image.new("L", (r - l + 2 * pad, b - t + 2 * pad), 255)
    ImageDraw.Draw(canvas).text((pad - l, pad - t), text, font=font, fill=0)
    return canvas


def render_text(spec: dict) -> Image.Image:
    probe_size = 400.0
    probe = ImageFont.truetype(spec["font"], probe_size, index=spec["index"])
    x0, y0, x1, y1 = draw_text(spec["text"], probe).point(lambda v: 255 - v).getbbox()
    k = fit_scale(x1 - x0, y1 - y0, spec)  # final pixels per probe pixel
    font = ImageFont.truetype(spec["font"], probe_size * k * SS, index=spec["index"])
    return place(binarize(draw_text(spec["text"], font)))


# -------------------------------------------------------------------------------- SVG
# A small SVG reader, enough for tools/thinker.svg: <g>, <polygon>, <path> (M L H V C Q Z,
# absolute and relative), transform= (matrix, translate, scale, rotate), fill= black or
# white. Shapes are painted in document order: black adds shadow, white removes it.
Matrix = tuple[float, float, float, float, float, float]  # a b c d e f as in SVG
IDENTITY: Matrix = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
NUM = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def mul(m: Matrix, n: Matrix) -> Matrix:
    a, b, c, d, e, f = m
    A, B, C, D, E, F = n
    return (a * A + c * B, b * A + d * B, a * C + c * D, b * C + d * D,
            a * E + c * F + e, b * E + d * F + f)


def parse_transform(s: str | None) -> Matrix:
    m = IDENTITY
    for name, args in re.findall(r"(\w+)\s*\(([^)]*)\)", s or ""):
        v = [float(x) for x in NUM.findall(args)]
        if name == "matrix":
            t = tuple(v)
        elif name == "translate":
            t = (1, 0, 0, 1, v[0], v[1] if len(v) > 1 else 0)
        elif name == "scale":
            t = (v[0], 0, 0, v[1] if len(v) > 1 else v[0], 0, 0)
        elif name == "rotate":
            a = math.radians(v[0])
            t = (math.cos(a), math.sin(a), -math.sin(a), math.cos(a), 0, 0)
            if len(v) == 3:
                t = mul(mul((1, 0, 0, 1, v[1], v[2]), t), (1, 0, 0, 1, -v[1], -v[2]))
        else:
            raise SystemExit(f"unsupported transform {name}")
        m = mul(m, t)
    return m


def apply(m: Matrix, p: tuple[float, float]) -> tuple[float, float]:
    a, b, c, d, e, f = m
    return (a * p[0] + c * p[1] + e, b * p[0] + d * p[1] + f)


def bezier(p0, p1, p2, p3, n=24):
    for i in range(1, n + 1):
        t = i / n
        u = 1 - t
        yield (u**3 * p0[0] + 3 * u * u * t * p1[0] + 3 * u * t * t * p2[0] + t**3 * p3[0],
               u**3 * p0[1] + 3 * u * u * t * p1[1] + 3 * u * t * t * p2[1] + t**3 * p3[1])


def path_polygons(d: str) -> list[list[tuple[float, float]]]:
    tokens = re.findall(r"[MmLlHhVvCcQqZz]|" + NUM.pattern, d)
    polys: list[list[tuple[float, float]]] = []
    cur: list[tuple[float, float]] = []
    pos = (0.0, 0.0)
    start = pos
    cmd = None
    i = 0

    def nums(k):
        nonlocal i
        v = [float(x) for x in tokens[i:i + k]]
        i += k
        return v

    while i < len(tokens):
        if tokens[i].isalpha():
            cmd = tokens[i]
            i += 1
            if cmd in "Zz":
                if cur:
                    polys.append(cur)
                cur = []
                pos = start
                continue
        rel = cmd.islower()
        ox, oy = pos if rel else (0.0, 0.0)
        C = cmd.upper()
        if C == "M":
            x, y = nums(2)
            pos = start = (ox + x, oy + y)
            if cur:
                polys.append(cur)
            cur = [pos]
            cmd = "l" if rel else "L"  # further pairs are line-tos
        elif C == "L":
            x, y = nums(2)
            pos = (ox + x, oy + y)
            cur.append(pos)
        elif C == "H":
            (x,) = nums(1)
            pos = (ox + x, pos[1])
            cur.append(pos)
        elif C == "V":
            (y,) = nums(1)
            pos = (pos[0], oy + y)
            cur.append(pos)
        elif C == "C":
            v = nums(6)
            p1, p2, p3 = (ox + v[0], oy + v[1]), (ox + v[2], oy + v[3]), (ox + v[4], oy + v[5])
            cur.extend(bezier(pos, p1, p2, p3))
            pos = p3
        elif C == "Q":
            v = nums(4)
            q, p3 = (ox + v[0], oy + v[1]), (ox + v[2], oy + v[3])
            p1 = (pos[0] + 2 / 3 * (q[0] - pos[0]), pos[1] + 2 / 3 * (q[1] - pos[1]))
            p2 = (p3[0] + 2 / 3 * (q[0] - p3[0]), p3[1] + 2 / 3 * (q[1] - p3[1]))
            cur.extend(bezier(pos, p1, p2, p3))
            pos = p3
        else:
            raise SystemExit(f"unsupported path command {cmd}")
    if cur:
        polys.append(cur)
    return polys


def svg_shapes(path: Path) -> list[tuple[bool, list[tuple[float, float]]]]:
    """(is_black, polygon) in document order, in the SVG's user space."""
    shapes: list[tuple[bool, list[tuple[float, float]]]] = []

    def walk(el, m: Matrix, fill: str | None):
        tag = el.tag.rsplit("}", 1)[-1]
        m = mul(m, parse_transform(el.get("transform")))
        fill = el.get("fill", fill)
        if tag == "polygon":
            v = [float(x) for x in NUM.findall(el.get("points", ""))]
            polys = [list(zip(v[0::2], v[1::2]))]
        elif tag == "path":
            polys = path_polygons(el.get("d", ""))
        else:
            polys = []
        for poly in polys:
            if fill in (None, "black", "#000", "#000000"):
                black = True
            elif fill in ("white", "#fff", "#ffffff"):
                black = False
            else:
                raise SystemExit(f"unsupported fill {fill!r}")
            shapes.append((black, [apply(m, p) for p in poly]))
        if tag in ("svg", "g"):
            for child in el:
                walk(child, m, fill)

    walk(ET.parse(path).getroot(), IDENTITY, None)
    return shapes


def render_svg(spec: dict) -> Image.Image:
    shapes = svg_shapes(spec["svg"])
    pts = [p for black, poly in shapes if black for p in poly]
    x0, x1 = min(p[0] for p in pts), max(p[0] for p in pts)
    y0, y1 = min(p[1] for p in pts), max(p[1] for p in pts)
    k = fit_scale(x1 - x0, y1 - y0, spec) * SS
    pad = 8 * SS
    canvas = Image.new("L", (math.ceil((x1 - x0) * k) + 2 * pad,
                             math.ceil((y1 - y0) * k) + 2 * pad), 255)
    draw = ImageDraw.Draw(canvas)
    for black, poly in shapes:
        draw.polygon([((x - x0) * k + pad, (y - y0) * k + pad) for x, y in poly],
                     fill=0 if black else 255)
    return place(binarize(canvas))


# ------------------------------------------------------------------------------- main
def stats(img: Image.Image) -> tuple[int, tuple[int, int, int, int]]:
    count = img.histogram()[0]
    x0, y0, x1, y1 = img.point(lambda v: 255 - v).getbbox()
    return count, (x0, y0, x1 - 1, y1 - 1)


def preview(images: list[Image.Image], path: Path) -> None:
    """The targets side by side at half size, with a grey frame around each."""
    w, h, gap = W // 2, H // 2, 8
    sheet = Image.new("L", (len(images) * (w + gap) + gap, h + 2 * gap), 160)
    for i, img in enumerate(images):
        sheet.paste(img.resize((w, h), Image.Resampling.BOX), (gap + i * (w + gap), gap))
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(path, optimize=True)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", default=list(TARGETS), help="targets to make")
    ap.add_argument("--preview", action="store_true",
                    help="also write docs/images/targets.png (all three, half size)")
    args = ap.parse_args()
    for spec in TARGETS.values():
        if "font" in spec and not Path(spec["font"]).is_file():
            sys.exit(f"missing font {spec['font']}: "
                     "apt-get install -y fonts-noto-cjk fonts-rocknroll")
    made = []
    for name in args.names:
        spec = TARGETS[name]
        img = render_text(spec) if spec["kind"] == "text" else render_svg(spec)
        out = ROOT / "scenes" / name / "target.png"
        out.parent.mkdir(parents=True, exist_ok=True)
        img.save(out, optimize=True)
        count, (x0, y0, x1, y1) = stats(img)
        print(f"{out.relative_to(ROOT)}: {count} shadow pixels ({100 * count / (W * H):.1f}%), "
              f"bbox x {x0}..{x1} y {y0}..{y1} ({x1 - x0 + 1} x {y1 - y0 + 1})")
        made.append(img)
    if args.preview:
        if len(made) != len(TARGETS):
            made = [Image.open(ROOT / "scenes" / n / "target.png") for n in TARGETS]
        preview(made, ROOT / "docs" / "images" / "targets.png")
        print("docs/images/targets.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
