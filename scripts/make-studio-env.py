#!/usr/bin/env python3
"""Writes scenes/envmaps/studio.pfm: a synthetic equirectangular studio environment (a sky
gradient, a warm ground, two soft boxes and a small bright key light) for the example scenes.
Made here so the repository carries no third-party HDR image. Layout as in
docs/scene-format.md: +y up, top row straight up, phi = atan2(z, x) grows to the right."""
import math, struct, sys

W, H = 512, 256

def radiance(d):
    x, y, z = d
    if y >= 0.0:  # sky: horizon haze to a blue zenith
        t = y ** 0.5
        c = [0.95 * (1 - t) + 0.35 * t, 0.9 * (1 - t) + 0.5 * t, 0.85 * (1 - t) + 0.9 * t]
        c = [0.6 * v for v in c]
    else:  # ground: dark warm grey, brighter toward the horizon
        t = min(1.0, -y * 4.0)
        c = [v * (0.35 * (1 - t) + 0.12 * t) for v in (1.0, 0.85, 0.7)]
    def around(theta_deg, phi_deg):
        th, ph = math.radians(theta_deg), math.radians(phi_deg)
        return (math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph))
    # two soft boxes: angular rectangles ~30 x 20 degrees
    for phi_c, gain in ((-120.0, 6.0), (-40.0, 3.5)):
        th = math.degrees(math.acos(max(-1.0, min(1.0, y))))
        ph = math.degrees(math.atan2(z, x))
        dph = (ph - phi_c + 540.0) % 360.0 - 180.0
        if abs(dph) < 15.0 and abs(th - 60.0) < 10.0:
            c = [gain, gain * 0.97, gain * 0.93]
    # the key light: a 10-degree disc, bright enough for crisp shadows
    k = around(50.0, -60.0)
    if x * k[0] + y * k[1] + z * k[2] > math.cos(math.radians(5.0)):
        c = [60.0, 54.0, 45.0]
    return c

def main(path):
    rows = []
    for j in range(H):  # j = 0 is the top row
        theta = math.pi * (j + 0.5) / H
        row = []
        for i in range(W):
            phi = 2.0 * math.pi * (i + 0.5) / W
            d = (math.sin(theta) * math.cos(phi), math.cos(theta), math.sin(theta) * math.sin(phi))
            row.extend(radiance(d))
        rows.append(row)
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1.0\n" % (W, H))
        for row in reversed(rows):  # PFM stores the bottom row first
            f.write(struct.pack("<%df" % len(row), *row))

if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "scenes/envmaps/studio.pfm")
