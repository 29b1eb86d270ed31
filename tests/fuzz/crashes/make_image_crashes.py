#!/usr/bin/env python3
"""Writes the stb_image reproducers of tests/fuzz/crashes/fuzz_image/ (docs/fuzzing.md,
fixed findings 2-4), byte by byte, from the seed tests/fuzz/corpus/fuzz_image/jpeg-rgb.
Run from the repository root: python3 tests/fuzz/crashes/make_image_crashes.py
The other files there (bmp-short-info-header, png-chunk-2gb, jpeg-undefined-huffman-table)
are fuzz_image's own artifacts, committed as found."""
import struct

OUT = "tests/fuzz/crashes/fuzz_image/"
jpeg = open("tests/fuzz/corpus/fuzz_image/jpeg-rgb", "rb").read()
assert jpeg[:2] == b"\xff\xd8" and jpeg[-2:] == b"\xff\xd9"


def write(name, data):
    with open(OUT + name, "wb") as f:
        f.write(data)


# A DHT segment of one DC table whose 16 code counts add up to 257 (lengths 9 to 16, so
# stb 2.27's code-length check passes): stbi__build_huffman writes size[257], one past the
# array, and code[256]. The seed's own DHT, later, redefines the table, so stb 2.27 then
# decodes the image as if nothing happened.
counts = [0] * 8 + [32] * 7 + [33]
table = bytes([0x00]) + bytes(counts) + bytes(range(256)) + b"\x00"
bad_dht = b"\xff\xc4" + struct.pack(">H", 2 + len(table)) + table
app0_end = 2 + 2 + struct.unpack(">H", jpeg[4:6])[0]  # SOI, then the APP0 segment
write("jpeg-dht-257-codes", jpeg[:app0_end] + bad_dht + jpeg[app0_end:])
# stb takes 0xFF 0xFF 0xD8 for the start of a JPEG too, and padding bytes between segments.
write("jpeg-dht-ff-fill-start", b"\xff" + jpeg[:app0_end] + b"\x00\x00" + bad_dht + jpeg[app0_end:])
# After the scan, before EOI: stb reads the table after decoding the pixels.
write("jpeg-dht-after-scan", jpeg[:-2] + bad_dht + jpeg[-2:])

# The fuzzer's 94-byte RLE TGA declaring 26192 x 13066 pixels: stb 2.27 fills what is
# missing with zeros, 153 s and 5 GB for `caustic info` (release build) on main.
hdr = struct.pack("<BBBHHBHHHHBB", 0, 0, 10, 0, 0, 0, 0, 0, 26192, 13066, 24, 0)
write("tga-rle-26192x13066", hdr + bytes([0xff, 1, 2, 3]) * 19)
# Within the pixel limit but far too short: 4096 x 4096 RLE pixels in 94 bytes (2 s and
# 270 MB on main), and an uncompressed one whose rows stb leaves uninitialised.
hdr = struct.pack("<BBBHHBHHHHBB", 0, 0, 10, 0, 0, 0, 0, 0, 4096, 4096, 24, 0)
write("tga-rle-truncated", hdr + bytes([0xff, 1, 2, 3]) * 19)
hdr = struct.pack("<BBBHHBHHHHBB", 0, 0, 2, 0, 0, 0, 0, 0, 1000, 1000, 24, 0)
write("tga-raw-truncated", hdr + bytes(76))

# Formats stb reads but caustic does not document.
write("ppm-2x2", b"P6\n2 2\n255\n" + bytes([200, 100, 50] * 4))
write("pnm-size-overflow", b"P6\n99999999999 1\n255\n" + bytes(6))  # stb_image.h:7487, UBSan
write("gif-1x1", b"GIF89a\x01\x00\x01\x00\x80\x00\x00\x00\x00\x00\xff\xff\xff"
      b"\x2c\x00\x00\x00\x00\x01\x00\x01\x00\x00\x02\x02\x44\x01\x00\x3b")

# Declared sizes the file cannot hold in other formats: a flat Radiance HDR (stb reads
# missing pixels into an uninitialised buffer), an uncompressed BMP, a PNG past deflate's
# 1032:1.
write("hdr-flat-truncated", b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4096 +X 4\n" + bytes([128, 64, 32, 129]) * 2)
bmp_info = struct.pack("<IiiHHIIiiII", 40, 4096, 4096, 1, 24, 0, 0, 2835, 2835, 0, 0)
write("bmp-truncated", b"BM" + struct.pack("<IHHI", 54 + 12, 0, 0, 54) + bmp_info + bytes(12))
import zlib


def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


write("png-16384-tiny", b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 16384, 16384, 8, 2, 0, 0, 0))
      + chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b""))
