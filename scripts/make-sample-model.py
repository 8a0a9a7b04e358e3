#!/usr/bin/env python3
"""Write board/models/ceramic-bowl.glb: a small glazed ceramic bowl, glTF 2.0.

Why: the assimp test models Debian ships (the corpus docs/models.md uses) hold
no textured concave model, and the README's picture wants one that shadows
itself (its inside under its own rim) and casts its shadow on the floor. The
bowl is also a model to try the kiosk with (`probelight run --model ...`).

What: a surface of revolution (a recessed underside, a flat foot ring to stand
on, the outer wall, a rounded rim, the inner wall down to a flat-ish bottom),
12 cm across and 6 cm tall, in metres, glTF's Y up, its origin at the centre
of its foot. Smooth per-vertex normals (split only at the foot's creases),
TEXCOORD_0 with u around the axis and v along the profile (0 under the foot's
centre, 1 at the centre of the inside), and one metallic-roughness material:
a baseColorTexture (sRGB PNG: a cobalt glaze outside with a wavy cream band,
a brown iron rim, a cream glaze inside with cobalt bands and painted petals,
and an unglazed biscuit foot with glaze drips above it), metallicFactor 0,
and a metallicRoughnessTexture (G: roughness 0.35 on the glaze, 0.85 on the
bare clay; B: metallic 0), so roughnessFactor is 1.

Python 3 standard library only (zlib + struct write the PNGs), and
deterministic: the same bytes on every run. Usage:

    scripts/make-sample-model.py [OUT.glb]   # default board/models/ceramic-bowl.glb
"""

import json
import math
import os
import struct
import sys
import zlib

SEGMENTS = 64  # quads around the axis
TEX_SIZE = 256  # base colour and metallic-roughness textures, TEX_SIZE square
GLAZE_ROUGHNESS = 0.35
CLAY_ROUGHNESS = 0.85


# --- the profile -------------------------------------------------------------
# Points (r, y) in metres, r from the axis, y up from the ground. The profile
# is a list of smooth runs; runs meet at creases (their end points are
# duplicated with each run's own normal). Traversed from under the foot's
# centre outward, up the outside, over the rim and down the inside to the
# centre, so the surface's outward normal is the tangent turned by -90 degrees.

def bezier(p0, p1, p2, p3, n, first=True):
    pts = []
    for i in range(0 if first else 1, n + 1):
        t = i / n
        s = 1.0 - t
        pts.append((s * s * s * p0[0] + 3 * s * s * t * p1[0] + 3 * s * t * t * p2[0] + t * t * t * p3[0],
                    s * s * s * p0[1] + 3 * s * s * t * p1[1] + 3 * s * t * t * p2[1] + t * t * t * p3[1]))
    return pts


def line(a, b, n):
    return [(a[0] + (b[0] - a[0]) * i / n, a[1] + (b[1] - a[1]) * i / n) for i in range(n + 1)]


RIM_C = (0.0580, 0.0570)  # the rim's round: centre and radius
RIM_R = 0.0020


def profile_runs():
    underside = line((0.0, 0.0040), (0.0220, 0.0040), 3)
    foot_inner = line((0.0220, 0.0040), (0.0228, 0.0), 1)
    foot_ring = line((0.0228, 0.0), (0.0290, 0.0), 2)
    foot_outer = line((0.0290, 0.0), (0.0300, 0.0070), 1)
    # Outside: from the foot up to the rim, vertical where it meets the rim.
    outer = bezier((0.0300, 0.0070), (0.0500, 0.0085), (0.0600, 0.0300), (0.0600, 0.0570), 18)
    # The rim's round, a half circle from the outside over to the inside.
    rim = [(RIM_C[0] + RIM_R * math.cos(math.pi * i / 8), RIM_C[1] + RIM_R * math.sin(math.pi * i / 8))
           for i in range(1, 8)]
    # Inside: down from the rim, level where it reaches the axis.
    inner = bezier((0.0560, 0.0570), (0.0560, 0.0300), (0.0420, 0.0110), (0.0, 0.0110), 20)
    # The outer wall, the rim and the inner wall are one smooth run.
    wall = outer + rim + inner
    return [underside, foot_inner, foot_ring, foot_outer, wall]


def run_normals(run):
    """Unit normals (nr, ny) of a smooth run: the tangent turned by -90 degrees."""
    normals = []
    for i in range(len(run)):
        a = run[max(i - 1, 0)]
        b = run[min(i + 1, len(run) - 1)]
        tr, ty = b[0] - a[0], b[1] - a[1]
        length = math.hypot(tr, ty)
        normals.append((ty / length, -tr / length))
    # On the axis the surface is level: its normal is straight down or up.
    for i in (0, len(run) - 1):
        if run[i][0] == 0.0:
            normals[i] = (0.0, 1.0 if normals[i][1] > 0 else -1.0)
    return normals


# --- the mesh ----------------------------------------------------------------

def build_mesh():
    runs = profile_runs()
    total = sum(math.dist(run[i], run[i + 1]) for run in runs for i in range(len(run) - 1))
    positions, normals, uvs, indices = [], [], [], []
    marks = {}  # v at named places of the profile, for the texture
    s = 0.0
    for k, run in enumerate(runs):
        run_n = run_normals(run)
        base_row = len(positions) // (SEGMENTS + 1)
        for i, ((r, y), (nr, ny)) in enumerate(zip(run, run_n)):
            if i > 0:
                s += math.dist(run[i - 1], run[i])
            v = s / total
            if k == 3 and i == len(run) - 1:
                marks["foot_top"] = v
            if k == 4 and (r, y) == (0.0600, 0.0570):
                marks["rim_outer"] = v
            if k == 4 and (r, y) == (0.0560, 0.0570):
                marks["rim_inner"] = v
            for j in range(SEGMENTS + 1):
                u = j / SEGMENTS
                a = 2.0 * math.pi * u
                c, sn = math.cos(a), -math.sin(a)
                if j == SEGMENTS:
                    c, sn = 1.0, 0.0  # the seam's two columns in the same place
                positions.append((r * c, y, r * sn))
                normals.append((nr * c, ny, nr * sn))
                uvs.append((u, v))
        rows = len(run)
        for i in range(rows - 1):
            for j in range(SEGMENTS):
                a = (base_row + i) * (SEGMENTS + 1) + j
                b = a + 1
                c = a + SEGMENTS + 1
                d = c + 1
                if run[i][0] == 0.0:  # a fan at the axis
                    tris = [(a, c, d)]
                elif run[i + 1][0] == 0.0:
                    tris = [(a, c, b)]
                else:
                    tris = [(a, c, d), (a, d, b)]
                for t in tris:
                    indices.append(orient(t, positions, normals))
    marks["total_m"] = total
    return positions, normals, uvs, indices, marks


def orient(tri, positions, normals):
    """The triangle wound counter-clockwise seen from the side its normals face."""
    p0, p1, p2 = (positions[i] for i in tri)
    e1 = [p1[k] - p0[k] for k in range(3)]
    e2 = [p2[k] - p0[k] for k in range(3)]
    cross = (e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0])
    n = [sum(normals[i][k] for i in tri) for k in range(3)]
    if sum(cross[k] * n[k] for k in range(3)) < 0.0:
        return (tri[0], tri[2], tri[1])
    return tri


# --- the textures ------------------------------------------------------------

def srgb_to_linear(c):
    c /= 255.0
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def linear_to_srgb8(c):
    c = min(max(c, 0.0), 1.0)
    c = c * 12.92 if c <= 0.0031308 else 1.055 * c ** (1.0 / 2.4) - 0.055
    return int(round(c * 255.0))


def lin(rgb):
    return tuple(srgb_to_linear(float(x)) for x in rgb)


CLAY = lin((214, 196, 168))  # unglazed biscuit
COBALT = lin((34, 62, 128))  # the outer glaze
COBALT_DEEP = lin((22, 40, 96))  # painted lines
CREAM = lin((240, 232, 212))  # the inner glaze, and the band outside
IRON = lin((122, 70, 38))  # the rim
OCHRE = lin((196, 132, 44))  # the painted petals


def hash01(i, j):
    """A deterministic pseudo-random number in [0, 1) for the texel (i, j)."""
    h = (i * 73856093) ^ (j * 19349663) ^ 0x5BD1E995
    h = (h ^ (h >> 13)) * 0x85EBCA6B & 0xFFFFFFFF
    h ^= h >> 16
    return (h & 0xFFFF) / 65536.0


def smooth_step(edge, width, x):
    """0 below edge - width/2, 1 above edge + width/2, smooth between."""
    t = min(max((x - edge) / width + 0.5, 0.0), 1.0)
    return t * t * (3.0 - 2.0 * t)


def band(v, centre, half, aa):
    return smooth_step(centre - half, aa, v) * (1.0 - smooth_step(centre + half, aa, v))


def mix(a, b, t):
    return tuple(x + (y - x) * t for x, y in zip(a, b))


def surface(u, v, m):
    """(linear RGB, glaze coverage in [0, 1]) at texture coordinates (u, v)."""
    aa = 1.5 / TEX_SIZE
    foot, rim_o, rim_i = m["foot_top"], m["rim_outer"], m["rim_inner"]
    tau = 2.0 * math.pi
    # Where the glaze ends above the foot: an uneven edge with 7 drips.
    drip = max(0.0, math.sin(tau * (7.0 * u + 0.1))) ** 4
    edge = foot + 0.030 + 0.004 * math.sin(tau * 3.0 * u) - 0.022 * drip
    glaze = smooth_step(edge, aa, v)
    # Outside: cobalt, a wavy cream band with a deep blue line in it, two
    # thin cream stripes, and the glaze pooling darker just above its edge.
    outer_span = rim_o - foot
    c = COBALT
    c = mix(c, COBALT_DEEP, 0.6 * band(v, edge + 0.012, 0.010, aa))
    wave_c = foot + 0.56 * outer_span + 0.032 * math.sin(tau * 6.0 * u)
    c = mix(c, CREAM, band(v, wave_c, 0.017, aa))
    c = mix(c, COBALT_DEEP, band(v, wave_c, 0.0035, aa))
    for centre in (foot + 0.30 * outer_span, foot + 0.82 * outer_span):
        c = mix(c, CREAM, band(v, centre, 0.004, aa))
    # Inside: cream, with two cobalt bands under the rim, a ring of ochre
    # petals outlined in cobalt half-way down and a cobalt ring and dot at
    # the bottom's centre.
    inner = mix(CREAM, COBALT, band(v, rim_i + 0.028, 0.014, aa))
    inner = mix(inner, COBALT, band(v, rim_i + 0.060, 0.004, aa))
    # Petals: 10 around, each an ellipse in (angle, v) pointing at the centre.
    pu = (u * 10.0) % 1.0 - 0.5
    pv = (v - (rim_i + 0.17)) / 0.075
    d = math.hypot(pu / 0.36, pv)
    inner = mix(inner, COBALT, 1.0 - smooth_step(1.0, 0.06, d))
    inner = mix(inner, OCHRE, 1.0 - smooth_step(0.80, 0.06, d))
    inner = mix(inner, COBALT, band(v, 0.955, 0.005, aa))
    inner = mix(inner, COBALT, smooth_step(0.985, aa, v))
    c = mix(c, inner, smooth_step(rim_i, aa, v))
    # The rim: iron brown over the round, a little onto each wall.
    c = mix(c, IRON, band(v, 0.5 * (rim_o + rim_i), 0.5 * (rim_i - rim_o) + 0.006, aa))
    return mix(CLAY, c, glaze), glaze


def make_textures(m):
    """The base colour (sRGB RGB8) and metallic-roughness (linear RGB8) images."""
    n = TEX_SIZE
    base = bytearray()
    mr = bytearray()
    offsets = ((0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75))
    rough_g = (int(round(GLAZE_ROUGHNESS * 255)), int(round(CLAY_ROUGHNESS * 255)))
    for row in range(n):
        for col in range(n):
            acc = [0.0, 0.0, 0.0]
            cover = 0.0
            for ox, oy in offsets:
                rgb, g = surface((col + ox) / n, (row + oy) / n, m)
                for k in range(3):
                    acc[k] += rgb[k] / 4.0
                cover += g / 4.0
            # A faint speckle in the bare clay (iron spots in the body).
            speck = 1.0 - 0.10 * (1.0 - cover) * (hash01(row, col) > 0.93)
            base += bytes(linear_to_srgb8(acc[k] * speck) for k in range(3))
            g = int(round(rough_g[0] * cover + rough_g[1] * (1.0 - cover)))
            mr += bytes((255, g, 0))  # R unused (occlusion), G roughness, B metallic
    return png_rgb8(n, n, base), png_rgb8(n, n, mr)


def png_rgb8(width, height, pixels):
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    stride = width * 3
    raw = bytearray()
    prev = bytes(stride)
    for y in range(height):
        line_ = pixels[y * stride:(y + 1) * stride]
        # Filter each row with Up (2) or Sub (1), whichever leaves smaller residuals.
        up = bytes((line_[i] - prev[i]) & 0xFF for i in range(stride))
        sub = bytes((line_[i] - (line_[i - 3] if i >= 3 else 0)) & 0xFF for i in range(stride))
        cost = lambda row: sum(b if b < 128 else 256 - b for b in row)
        kind, data = (2, up) if cost(up) <= cost(sub) else (1, sub)
        raw.append(kind)
        raw += data
        prev = line_
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
            + chunk(b"IEND", b""))


# --- the GLB -----------------------------------------------------------------

def pad4(data, fill):
    return data + fill * (-len(data) % 4)


def make_glb(positions, normals, uvs, indices, base_png, mr_png):
    blob = bytearray()
    views = []

    def add_view(data, target=None):
        offset = len(blob)
        blob.extend(data)
        blob.extend(b"\x00" * (-len(blob) % 4))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        views.append(view)
        return len(views) - 1

    flat = lambda rows: [x for row in rows for x in row]
    pos_view = add_view(struct.pack("<%df" % (3 * len(positions)), *flat(positions)), 34962)
    nrm_view = add_view(struct.pack("<%df" % (3 * len(normals)), *flat(normals)), 34962)
    uv_view = add_view(struct.pack("<%df" % (2 * len(uvs)), *flat(uvs)), 34962)
    wide = len(positions) > 65535
    idx_view = add_view(struct.pack("<%d%s" % (3 * len(indices), "I" if wide else "H"), *flat(indices)), 34963)
    base_view = add_view(base_png)
    mr_view = add_view(mr_png)

    # min and max of the floats as stored (float32), as the spec asks.
    stored = struct.unpack("<%df" % (3 * len(positions)), struct.pack("<%df" % (3 * len(positions)), *flat(positions)))
    pmin = [min(stored[k::3]) for k in range(3)]
    pmax = [max(stored[k::3]) for k in range(3)]

    gltf = {
        "asset": {"version": "2.0", "generator": "probelight scripts/make-sample-model.py"},
        "scene": 0,
        "scenes": [{"name": "ceramic bowl", "nodes": [0]}],
        "nodes": [{"name": "bowl", "mesh": 0}],
        "meshes": [{
            "name": "bowl",
            "primitives": [{
                "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                "indices": 3,
                "material": 0,
                "mode": 4,
            }],
        }],
        "materials": [{
            "name": "glazed ceramic",
            "pbrMetallicRoughness": {
                "baseColorTexture": {"index": 0},
                "metallicFactor": 0.0,
                "roughnessFactor": 1.0,
                "metallicRoughnessTexture": {"index": 1},
            },
        }],
        "textures": [{"sampler": 0, "source": 0}, {"sampler": 0, "source": 1}],
        # Repeat around the bowl (u), clamp along the profile (v): its two
        # ends, under the foot and inside the bottom, must not bleed together.
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 33071}],
        "images": [
            {"name": "base colour", "bufferView": base_view, "mimeType": "image/png"},
            {"name": "metallic roughness", "bufferView": mr_view, "mimeType": "image/png"},
        ],
        "accessors": [
            {"bufferView": pos_view, "componentType": 5126, "count": len(positions), "type": "VEC3",
             "min": pmin, "max": pmax},
            {"bufferView": nrm_view, "componentType": 5126, "count": len(normals), "type": "VEC3"},
            {"bufferView": uv_view, "componentType": 5126, "count": len(uvs), "type": "VEC2"},
            {"bufferView": idx_view, "componentType": 5125 if wide else 5123, "count": 3 * len(indices),
             "type": "SCALAR"},
        ],
        "bufferViews": views,
        "buffers": [{"byteLength": len(blob)}],
    }
    js = pad4(json.dumps(gltf, separators=(",", ":")).encode("utf-8"), b" ")
    bin_ = pad4(bytes(blob), b"\x00")
    total = 12 + 8 + len(js) + 8 + len(bin_)
    return (struct.pack("<4sII", b"glTF", 2, total)
            + struct.pack("<I4s", len(js), b"JSON") + js
            + struct.pack("<I4s", len(bin_), b"BIN\x00") + bin_)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "board", "models", "ceramic-bowl.glb")
    positions, normals, uvs, indices, marks = build_mesh()
    base_png, mr_png = make_textures(marks)
    glb = make_glb(positions, normals, uvs, indices, base_png, mr_png)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "wb") as f:
        f.write(glb)
    print("%s: %d bytes, %d vertices, %d triangles, textures %d + %d bytes"
          % (out, len(glb), len(positions), len(indices), len(base_png), len(mr_png)))


if __name__ == "__main__":
    main()
