#!/usr/bin/env python3
"""Writes a small pbrt-v4 scene whose float image textures tell pbrt-v4's channel rule
(MIPMap::Filter<Float>) from a first-channel rule, with its PNGs, into DIR; with --compare
A.pfm B.pfm, prints the mean of each third of two renders (columns) and their ratios.

  python3 scripts/pbrt-float-textures.py /tmp/ft
  build/caustic render /tmp/ft/float-textures.pbrt -o /tmp/ft/caustic.pfm --spp 256
  ../shared/tools/pbrt-v4/pbrt --spp 256 /tmp/ft/float-textures.pbrt --outfile /tmp/ft/pbrt.pfm
  python3 scripts/pbrt-float-textures.py --compare /tmp/ft/caustic.pfm /tmp/ft/pbrt.pfm

With --exr DIR, the left quad's alpha comes from an RGBA OpenEXR of halves (the same values)
instead of the PNG: pbrt-v4 keeps an EXR's A as it keeps a PNG's.

Three quads in front of a grey wall under a white sky (docs/pbrt-compat.md, "Float image
textures"): left, a white quad cut out by the alpha of an RGBA PNG (red 1 everywhere, alpha
0, 0.5 and 1 in columns); middle and right, a mix of two greys whose amount is an RGB PNG
(red 0, green and blue in a checker) read bilinear (the mean of R, G, B) and point (red).
A first-channel rule renders the left quad opaque and both mixes at tex1."""
import os
import struct
import sys
import zlib


def write_png(path, w, h, channels, pixels):
    """8-bit PNG, colour type 0 (grey), 2 (RGB) or 6 (RGBA), from a flat list of bytes."""
    ctype = {1: 0, 3: 2, 4: 6}[channels]
    rows = b"".join(b"\x00" + bytes(pixels[y * w * channels:(y + 1) * w * channels]) for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, ctype, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows)))
        f.write(chunk(b"IEND", b""))


def write_exr_half_rgba(path, w, h, pixels):
    """Uncompressed scanline OpenEXR, channels A, B, G, R as halves (OpenEXR file layout),
    from a flat list of (r, g, b, a) values exactly representable as halves."""
    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data

    chans = b"".join(c.encode() + b"\0" + struct.pack("<iBBBBii", 1, 0, 0, 0, 0, 1, 1) for c in "ABGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    head = (struct.pack("<ii", 20000630, 2) + attr("channels", "chlist", chans) +
            attr("compression", "compression", b"\0") + attr("dataWindow", "box2i", box) +
            attr("displayWindow", "box2i", box) + attr("lineOrder", "lineOrder", b"\0") +
            attr("pixelAspectRatio", "float", struct.pack("<f", 1.0)) +
            attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0)) +
            attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    line = 4 * 2 * w
    first = len(head) + 8 * h
    out = head + b"".join(struct.pack("<Q", first + y * (8 + line)) for y in range(h))
    for y in range(h):
        row = pixels[y * w:(y + 1) * w]
        out += struct.pack("<ii", y, line)
        for k in (3, 2, 1, 0):  # A, B, G, R: alphabetical
            out += b"".join(struct.pack("<e", px[k]) for px in row)
    with open(path, "wb") as f:
        f.write(out)


QUAD = ('Shape "trianglemesh" "point3 P" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] "integer indices" [0 1 2 0 2 3]\n'
        '    "point2 uv" [0 0  1 0  1 1  0 1]')

SCENE = """# caustic scripts/pbrt-float-textures.py: pbrt-v4's float image texture channel rule
LookAt 0 0 7  0 0 0  0 1 0
Camera "perspective" "float fov" 40
Film "rgb" "integer xresolution" 192 "integer yresolution" 64 "string filename" "pbrt.exr"
Sampler "zsobol" "integer pixelsamples" 64
WorldBegin
LightSource "infinite" "rgb L" [1 1 1]
Texture "cut" "float" "imagemap" "string filename" "rgba.png" "string encoding" "linear"
Texture "amt_bilinear" "float" "imagemap" "string filename" "rgb.png" "string encoding" "linear"
Texture "amt_point" "float" "imagemap" "string filename" "rgb.png" "string encoding" "linear" "string filter" "point"
Texture "mix_bilinear" "spectrum" "mix" "texture amount" "amt_bilinear" "rgb tex1" [0.05 0.05 0.05] "rgb tex2" [0.9 0.9 0.9]
Texture "mix_point" "spectrum" "mix" "texture amount" "amt_point" "rgb tex1" [0.05 0.05 0.05] "rgb tex2" [0.9 0.9 0.9]
AttributeBegin
  Material "diffuse" "rgb reflectance" [0.3 0.3 0.3]
  Shape "trianglemesh" "point3 P" [-20 -20 -3  20 -20 -3  20 20 -3  -20 20 -3] "integer indices" [0 1 2 0 2 3]
AttributeEnd
AttributeBegin
  Translate 2.3 0 0  # pbrt's LookAt is left-handed: world +x is the image's left
  Material "diffuse" "rgb reflectance" [0.8 0.8 0.8]
  {quad} "texture alpha" "cut"
AttributeEnd
AttributeBegin
  Material "diffuse" "texture reflectance" "mix_bilinear"
  {quad}
AttributeEnd
AttributeBegin
  Translate -2.3 0 0
  Material "diffuse" "texture reflectance" "mix_point"
  {quad}
AttributeEnd
"""


def make(d, exr=False):
    os.makedirs(d, exist_ok=True)
    n = 6
    rgba, rgb = [], []
    for y in range(n):
        for x in range(n):
            rgba += [255, 255, 255, (0, 128, 255)[x % 3]]
            rgb += [0, 255, 255] if (x + y) % 2 == 0 else [0, 64, 0]
    write_png(os.path.join(d, "rgba.png"), n, n, 4, rgba)
    write_png(os.path.join(d, "rgb.png"), n, n, 3, rgb)
    scene = SCENE.format(quad=QUAD)
    if exr:
        px = [(1.0, 1.0, 1.0, (0.0, 0.5, 1.0)[x % 3]) for y in range(n) for x in range(n)]
        write_exr_half_rgba(os.path.join(d, "rgba.exr"), n, n, px)
        scene = scene.replace('"rgba.png" "string encoding" "linear"', '"rgba.exr"')
    with open(os.path.join(d, "float-textures.pbrt"), "w") as f:
        f.write(scene)


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        ch = 3 if kind == b"PF" else 1
        data = f.read(w * h * ch * 4)
    vals = struct.unpack(("<" if scale < 0 else ">") + "f" * (w * h * ch), data)
    return w, h, ch, vals


def thirds(path):
    w, h, ch, v = read_pfm(path)
    sums = [0.0, 0.0, 0.0]
    for y in range(h):
        for x in range(w):
            i = (y * w + x) * ch
            sums[min(2, 3 * x // w)] += sum(v[i:i + ch]) / ch
    return [s / (h * w / 3) for s in sums]


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--compare":
        a, b = thirds(sys.argv[2]), thirds(sys.argv[3])
        for name, x, y in zip(("left (alpha)", "middle (bilinear)", "right (point)"), a, b):
            print(f"{name:18s} {x:.5f} {y:.5f} ratio {x / y:.4f}")
    elif len(sys.argv) == 2:
        make(sys.argv[1])
    elif len(sys.argv) == 3 and sys.argv[1] == "--exr":
        make(sys.argv[2], exr=True)
    else:
        sys.exit(__doc__)
