#!/usr/bin/env bash
# Rebuilds the committed seed corpora of tests/fuzz/corpus/<target>/ from the repository's
# scenes and tiny generated images (a few pixels each, so the fuzzer's mutations stay
# cheap). Usage: tests/fuzz/make_corpus.sh CAUSTIC_BINARY (any build; it writes the EXR
# seeds). Needs python3 and a C compiler with stb_image_write.h (libstb-dev) and libjpeg
# (libjpeg62-turbo-dev) for JPEG.
set -euo pipefail
cd "$(dirname "$0")/../.."
caustic=$(realpath "${1:?usage: tests/fuzz/make_corpus.sh CAUSTIC_BINARY}")
out=tests/fuzz/corpus
rm -rf "$out"
mkdir -p "$out"/{fuzz_scene_json,fuzz_pbrt,fuzz_mesh,fuzz_image,fuzz_ply,fuzz_bsdf}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# JSON scenes: every shipped scene (the loader's file references fail cleanly in the
# fuzzer's directory, which exercises the error paths; the rest of each file still counts).
for f in scenes/*.json; do cp "$f" "$out/fuzz_scene_json/$(basename "$f" .json)"; done

# pbrt: the shipped scene and the pbrt test inputs small enough to mutate.
cp scenes/cornell-box.pbrt "$out/fuzz_pbrt/cornell-box"
python3 - "$out/fuzz_pbrt" <<'PY'
import sys, os
d = sys.argv[1]
seeds = {
 "instances": 'LookAt 0 0 5 0 0 0 0 1 0\nCamera "perspective" "float fov" 45\nFilm "rgb" "integer xresolution" 8 "integer yresolution" 8\nWorldBegin\nObjectBegin "a"\nShape "sphere" "float radius" 1\nObjectEnd\nAttributeBegin\nTranslate 1 0 0\nObjectInstance "a"\nAttributeEnd\nLightSource "infinite" "rgb L" [1 1 1]\n',
 "curves": 'LookAt 0 0 5 0 0 0 0 1 0\nCamera "perspective"\nFilm "rgb" "integer xresolution" 8 "integer yresolution" 8\nWorldBegin\nMaterial "hair" "float eumelanin" 1\nShape "curve" "point3 P" [0 0 0 1 1 0 2 0 0 3 1 0] "float width0" 0.1 "float width1" 0.02 "string type" "cylinder" "integer splitdepth" 2\nShape "curve" "string basis" "bspline" "integer degree" 2 "point3 P" [0 0 0 1 1 0 2 0 0 3 1 0] "string type" "ribbon" "normal N" [0 0 1 0 1 1 1 0 0]\nScale 2 1 1\nShape "curve" "point3 P" [0 0 0 1 0 0 2 0 0] "integer degree" 2 "float width" 0.05\n',
 "trianglemesh": 'Camera "perspective"\nWorldBegin\nMaterial "conductor" "float roughness" 0.2\nAttributeBegin\nAreaLightSource "diffuse" "blackbody L" 5500\nShape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2] "point2 uv" [0 0 1 0 0 1]\nAttributeEnd\nShape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0]\n',
 "alpha-mapping": 'LookAt 0 0 5 0 0 0 0 1 0\nCamera "perspective"\nWorldBegin\nTexture "m" "float" "checkerboard" "float uscale" 4 "float tex1" 0 "float tex2" 1\nTranslate 1 2 3\nTexture "p" "spectrum" "checkerboard" "string mapping" "planar" "vector3 v1" [1 0 0] "vector3 v2" [0 0 1] "float udelta" 0.5\nTexture "s" "spectrum" "checkerboard" "string mapping" "spherical"\nMaterial "diffuse" "texture reflectance" "p"\nShape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "integer indices" [0 1 2] "texture alpha" "m"\nMaterial "diffuse" "texture reflectance" "s"\nShape "sphere" "float alpha" 0.5\nAttributeBegin\nAreaLightSource "diffuse" "rgb L" [1 1 1]\nShape "bilinearmesh" "point3 P" [0 0 2 1 0 2 0 1 2 1 1 2] "float alpha" 0\nAttributeEnd\n',
 "textures": 'Camera "orthographic" "float screenwindow" [-1 1 -1 1]\nSampler "halton" "integer pixelsamples" 4\nIntegrator "volpath" "integer maxdepth" 3\nWorldBegin\nTexture "c" "spectrum" "checkerboard" "float uscale" 4 "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]\nTexture "s" "float" "scale" "float scale" 0.5 "float tex" 0.3\nMakeNamedMaterial "m" "string type" "coateddiffuse" "texture reflectance" "c" "texture roughness" "s"\nNamedMaterial "m"\nShape "disk" "float radius" 2\nLightSource "spot" "point3 from" [0 0 3] "point3 to" [0 0 0] "float coneangle" 30 "spectrum I" "stdillum-D65"\nLightSource "distant" "point3 to" [0 0 -1] "rgb L" [0.5 0.5 0.5]\n',
}
for k, v in seeds.items():
    open(os.path.join(d, k), "w").write(v)
PY

# Meshes: the shipped OBJ (small) and hand-made PLY in every encoding; OBJ with materials.
cp scenes/meshes/torus-on-plinth.obj "$out/fuzz_mesh/torus-on-plinth-obj"
python3 - "$out/fuzz_mesh" <<'PY'
import sys, os, struct
d = sys.argv[1]
verts = [(0,0,0),(1,0,0),(1,1,0),(0,1,0)]
faces = [(0,1,2),(0,2,3)]
def header(fmt, extra_v="", face="property list uchar int vertex_indices"):
    return ("ply\nformat %s 1.0\ncomment seed\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n%s"
            "element face 2\n%s\nend_header\n" % (fmt, extra_v, face)).encode()
asc = header("ascii") + b"".join(b"%g %g %g\n" % v for v in verts) + b"".join(b"3 %d %d %d\n" % f for f in faces)
open(os.path.join(d, "quad-ascii-ply"), "wb").write(asc)
for fmt, e in (("binary_little_endian", "<"), ("binary_big_endian", ">")):
    body = b"".join(struct.pack(e + "3f", *v) for v in verts) + b"".join(struct.pack(e + "B3i", 3, *f) for f in faces)
    open(os.path.join(d, "quad-%s-ply" % fmt), "wb").write(header(fmt) + body)
nrm = header("binary_little_endian", "property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n",
             "property list uchar uint vertex_indices")
body = b"".join(struct.pack("<8f", *v, 0, 0, 1, v[0], v[1]) for v in verts) + b"".join(struct.pack("<B3I", 3, *f) for f in faces)
open(os.path.join(d, "quad-normals-uv-ply"), "wb").write(nrm + body)
open(os.path.join(d, "quad-obj"), "w").write(
    "# quad with normals, uvs and a missing mtllib\nmtllib none.mtl\no quad\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n"
    "g a\nusemtl red\nf 1/1/1 2/2/1 3/3/1 4/4/1\ng b\nusemtl glass\nf -4//1 -2//1 -1//1\nl 1 2\np 3\n")
PY

# Images: a few pixels in every format and variant the readers take.
python3 - "$out/fuzz_image" <<'PY'
import sys, os, struct, zlib
d = sys.argv[1]
w, h = 3, 2
def png(name, bit_depth, color_type, rows, extra=b""):
    def chunk(t, data):
        return struct.pack(">I", len(data)) + t + data + struct.pack(">I", zlib.crc32(t + data) & 0xffffffff)
    raw = b"".join(b"\0" + r for r in rows)
    data = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, bit_depth, color_type, 0, 0, 0))
            + extra + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))
    open(os.path.join(d, name), "wb").write(data)
png("png-rgb8", 8, 2, [bytes(range(y * 9, y * 9 + 9)) for y in range(h)])
png("png-rgba16", 16, 6, [bytes(range(y * 24, y * 24 + 24)) for y in range(h)])
png("png-gray8", 8, 0, [bytes([10, 128, 250]) for y in range(h)])
png("png-gray1", 1, 0, [b"\xa0" for y in range(h)])
def plte_chunk():
    data = bytes([255, 0, 0, 0, 255, 0, 0, 0, 255])
    t = b"PLTE"
    return struct.pack(">I", len(data)) + t + data + struct.pack(">I", zlib.crc32(t + data) & 0xffffffff)
png("png-palette", 8, 3, [bytes([0, 1, 2]) for y in range(h)], plte_chunk())
# PFM: colour little-endian, grey big-endian.
px = [0.1 * i for i in range(w * h * 3)]
open(os.path.join(d, "pfm-rgb"), "wb").write(b"PF\n%d %d\n-1.0\n" % (w, h) + struct.pack("<%df" % len(px), *px))
open(os.path.join(d, "pfm-grey"), "wb").write(b"Pf\n%d %d\n1.0\n" % (w, h) + struct.pack(">%df" % (w * h), *px[:w * h]))
# Radiance HDR: flat (uncompressed) RGBE scanlines.
hdr = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (h, w) + bytes([128, 64, 32, 129] * (w * h))
open(os.path.join(d, "hdr-flat"), "wb").write(hdr)
# BMP, 24-bit bottom-up.
row = bytes([0, 0, 255, 0, 255, 0, 255, 0, 0]) + b"\0" * 3
bmp_px = row * h
bmp = b"BM" + struct.pack("<IHHI", 54 + len(bmp_px), 0, 0, 54) + struct.pack("<IiiHHIIiiII", 40, w, h, 1, 24, 0, len(bmp_px), 2835, 2835, 0, 0) + bmp_px
open(os.path.join(d, "bmp-rgb24"), "wb").write(bmp)
# TGA, uncompressed true colour and RLE.
tga_hdr = lambda kind: struct.pack("<BBBHHBHHHHBB", 0, 0, kind, 0, 0, 0, 0, 0, w, h, 24, 0)
open(os.path.join(d, "tga-rgb"), "wb").write(tga_hdr(2) + bytes(range(w * h * 3)))
open(os.path.join(d, "tga-rle"), "wb").write(tga_hdr(10) + bytes([0x80 | (w * h - 1), 10, 20, 30]))
PY
# PLY reader (fuzz_ply): a triangle and a quad with normals, uvs under pbrt-v4's four
# names, face_indices, list properties and an extra element to skip; plain, gzip, and
# 'Z' + text (the target gzips it itself).
python3 - "$out/fuzz_ply" <<'PY'
import sys, os, struct, gzip
d = sys.argv[1]
verts = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0.5)]
def mk(fmt, uv=("u", "v"), quad=True, extra=False):
    h = "ply\nformat %s 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float %s\nproperty float %s\n" % (fmt, uv[0], uv[1])
    if extra: h += "property list uchar int junk\n"
    h += "element face 2\nproperty list uchar int vertex_indices\nproperty int face_indices\n"
    if extra: h += "element edge 1\nproperty int a\nproperty list ushort double b\n"
    h += "end_header\n"
    faces = [(0, 1, 3), (0, 1, 2, 3)] if quad else [(0, 1, 2), (0, 2, 3)]
    if fmt == "ascii":
        b = h
        for v in verts: b += "%g %g %g 0 0 1 %g %g%s\n" % (v[0], v[1], v[2], v[0], v[1], " 2 7 8" if extra else "")
        for i, f in enumerate(faces): b += "%d %s %d\n" % (len(f), " ".join(map(str, f)), i)
        if extra: b += "5 1 2.5\n"
        return b.encode()
    e = "<" if fmt == "binary_little_endian" else ">"
    b = h.encode()
    for v in verts:
        b += struct.pack(e + "8f", v[0], v[1], v[2], 0, 0, 1, v[0], v[1])
        if extra: b += struct.pack(e + "B2i", 2, 7, 8)
    for i, f in enumerate(faces): b += struct.pack(e + "B%di" % len(f), len(f), *f) + struct.pack(e + "i", i)
    if extra: b += struct.pack(e + "iHd", 5, 1, 2.5)
    return b
open(os.path.join(d, "ascii"), "wb").write(mk("ascii"))
open(os.path.join(d, "le"), "wb").write(mk("binary_little_endian", ("s", "t")))
open(os.path.join(d, "be"), "wb").write(mk("binary_big_endian", ("texture_u", "texture_v"), extra=True))
open(os.path.join(d, "ascii-extra"), "wb").write(mk("ascii", ("texture_s", "texture_t"), quad=False, extra=True))
open(os.path.join(d, "le-gz"), "wb").write(gzip.compress(mk("binary_little_endian"), mtime=0))
open(os.path.join(d, "Z-ascii"), "wb").write(b"Z" + mk("ascii", extra=True))
PY
# EXR: the renderer's own writer, plain and with AOV channels.
"$caustic" render --width 3 --height 2 --spp 1 -q -o "$tmp/a.exr"
"$caustic" render --width 2 --height 2 --spp 1 -q --aov albedo,depth -o "$tmp/b.exr"
cp "$tmp/a.exr" "$out/fuzz_image/exr-rgb"
cp "$tmp/b.exr" "$out/fuzz_image/exr-aov"
# JPEG: a baseline file from stb_image_write.
cat > "$tmp/jpg.c" <<'C'
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
int main(int argc, char **argv)
{
    unsigned char px[4 * 4 * 3];
    for (int i = 0; i < 48; i++) px[i] = (unsigned char)(i * 5);
    return !(argc > 1 && stbi_write_jpg(argv[1], 4, 4, 3, px, 50));
}
C
cc -o "$tmp/jpg" "$tmp/jpg.c" -lm
"$tmp/jpg" "$out/fuzz_image/jpeg-rgb"
# Measured BSDFs (fuzz_bsdf): RGL tensor files (.bsdf) of a few nodes each, spectral and
# RGB, isotropic (2 phi_i) and anisotropic (3 phi_i spanning 2 pi), a GGX NDF and its
# projected area, constant vndf, luminance and reflectance.
python3 - "$out/fuzz_bsdf" <<'PY'
import sys, os, struct, math
d = sys.argv[1]
def tensor(fields):
    # fields: (name, dtype code, shape, bytes); header, then the data in field order
    head = 18 + sum(2 + len(n) + 2 + 1 + 8 + 8 * len(s) for n, _, s, _ in fields)
    out = bytearray(b"tensor_file\0" + bytes([1, 0]) + struct.pack("<I", len(fields)))
    off = head
    for n, t, s, b in fields:
        out += struct.pack("<H", len(n)) + n.encode() + struct.pack("<HBQ", len(s), t, off)
        out += b"".join(struct.pack("<Q", x) for x in s)
        off += len(b)
    for _, _, _, b in fields:
        out += b
    return bytes(out)
def f32(v): return b"".join(struct.pack("<f", x) for x in v)
def seed(rgb, nt, nphi, res, nl):
    th = [ (i / (nt - 1)) ** 2 * math.pi / 2 for i in range(nt)]
    ph = [-math.pi + 2 * math.pi * i / (nphi - 1) for i in range(nphi)]
    a = 0.3
    ndf = []
    for y in range(4):
        for x in range(4):
            t = (x / 3) ** 2 * math.pi / 2
            c = math.cos(t)
            ndf.append(a * a / (math.pi * (1 - c * c + a * a * c * c) ** 2))
    sig = [0.5 * (math.cos((x / 3) ** 2 * math.pi / 2) + math.sqrt(math.cos((x / 3) ** 2 * math.pi / 2) ** 2 +
           a * a * math.sin((x / 3) ** 2 * math.pi / 2) ** 2)) for y in range(4) for x in range(4)]
    g = nphi * nt * res * res
    f = [("theta_i", 10, [nt], f32(th)), ("phi_i", 10, [nphi], f32(ph)), ("ndf", 10, [4, 4], f32(ndf)),
         ("sigma", 10, [4, 4], f32(sig)), ("vndf", 10, [nphi, nt, res, res], f32([1.0] * g)),
         ("luminance", 10, [nphi, nt, res, res], f32([1.0] * g)), ("description", 1, [4], b"seed"),
         ("jacobian", 1, [1], b"\1")]
    if rgb:
        f.append(("rgb", 10, [nphi, nt, 3, res, res], f32([0.5] * g * 3)))
    else:
        f.append(("spectra", 10, [nphi, nt, nl, res, res], f32([0.5] * g * nl)))
        f.append(("wavelengths", 10, [nl], f32([400 + 300 * i / max(nl - 1, 1) for i in range(nl)])))
    return tensor(f)
open(os.path.join(d, "iso-spectral"), "wb").write(seed(False, 3, 2, 3, 2))
open(os.path.join(d, "iso-rgb"), "wb").write(seed(True, 2, 2, 2, 0))
open(os.path.join(d, "aniso-spectral"), "wb").write(seed(False, 2, 3, 2, 3))
PY
# JPEG through libjpeg's compressor (the decoder's paths stb's writer does not reach):
# progressive 4:2:0, grey with a restart interval, Adobe CMYK, arithmetic coding; 8 x 8.
cat > "$tmp/ljpg.c" <<'C'
#include <stdio.h>
#include <jpeglib.h>
int main(int argc, char **argv)
{
    static const char *const kinds[4] = {"progressive", "grey-restart", "cmyk", "arithmetic"};
    for (int k = 0; k < 4; k++) {
        char name[512];
        snprintf(name, sizeof name, "%s/jpeg-%s", argv[1], kinds[k]);
        FILE *f = fopen(name, "wb");
        if (!f) return 1;
        struct jpeg_compress_struct c;
        struct jpeg_error_mgr e;
        c.err = jpeg_std_error(&e);
        jpeg_create_compress(&c);
        jpeg_stdio_dest(&c, f);
        c.image_width = c.image_height = 8;
        c.input_components = k == 1 ? 1 : k == 2 ? 4 : 3;
        c.in_color_space = k == 1 ? JCS_GRAYSCALE : k == 2 ? JCS_CMYK : JCS_RGB;
        jpeg_set_defaults(&c);
        jpeg_set_quality(&c, 50, TRUE);
        if (k == 0) jpeg_simple_progression(&c);
        if (k == 1) c.restart_interval = 1;
        if (k == 3) c.arith_code = TRUE;
        jpeg_start_compress(&c, TRUE);
        unsigned char row[8 * 4];
        while (c.next_scanline < 8) {
            for (int i = 0; i < 32; i++) row[i] = (unsigned char)(i * 7 + c.next_scanline * 20);
            JSAMPROW r = row;
            jpeg_write_scanlines(&c, &r, 1);
        }
        jpeg_finish_compress(&c);
        jpeg_destroy_compress(&c);
        fclose(f);
    }
    return 0;
}
C
cc -o "$tmp/ljpg" "$tmp/ljpg.c" -ljpeg
"$tmp/ljpg" "$out/fuzz_image"
du -sh "$out"; ls "$out"/*
