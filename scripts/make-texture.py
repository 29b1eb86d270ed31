#!/usr/bin/env python3
"""Writes scenes/textures/bands.png, the 256x256 image texture of scenes/textured.json:
coloured latitude bands with a grid of meridians, generated here (no third-party image)."""
import colorsys
import math
import os
import struct
import zlib

W = H = 256


def pixel(x, y):
    u, v = (x + 0.5) / W, (y + 0.5) / H
    hue = (v * 3.0 + 0.15 * math.sin(2.0 * math.pi * 4.0 * u)) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.65, 0.9)
    if (x % 32) < 2 or (y % 32) < 2:  # grid lines
        r, g, b = 0.95, 0.95, 0.92
    return bytes(int(round(255 * c)) for c in (r, g, b))


def chunk(kind, data):
    c = kind + data
    return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c) & 0xFFFFFFFF)


def main():
    raw = b"".join(b"\x00" + b"".join(pixel(x, y) for x in range(W)) for y in range(H))
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "textures", "bands.png")
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out, "wb") as f:
        f.write(png)


if __name__ == "__main__":
    main()
