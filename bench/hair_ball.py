#!/usr/bin/env python3
"""The hair-scene stand-in of the curve benchmark (issue 28): pbrt-v4's hair-eumel-2.pbrt
(camera, volpath, hair material) with its missing curve file replaced by a ball of cylinder
curves (cubic Beziers from a sphere of radius 3, widths 0.04 to 0.01, splitdepth 3: 8 segments
per curve) and a constant environment. Deterministic (fixed seed); both renderers read it.

    python3 bench/hair_ball.py --curves 125000 --res 128 > /tmp/hair-1m.pbrt
"""
import argparse
import math
import random


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--curves", type=int, default=125000, help="curves (8 segments each)")
    ap.add_argument("--res", type=int, default=128, help="image width and height")
    ap.add_argument("--seed", type=int, default=28)
    a = ap.parse_args()
    rng = random.Random(a.seed)
    out = []
    w = out.append
    w('Integrator "volpath" "integer maxdepth" [ 32 ]\n')
    w("Transform [ -0.999887 0.00390257 0.0145262 -0 -0 0.965755 -0.259457 -0 0.0150413 "
      "0.259428 0.965645 -0 0.146624 -9.36998 28.765 1 ]\n")
    w('Sampler "halton" "integer pixelsamples" [ 16 ]\n')
    w('Film "rgb" "float iso" [ 400 ] "string filename" [ "hair-ball.exr" ]\n')
    w('    "integer yresolution" [ %d ] "integer xresolution" [ %d ] "float maxcomponentvalue" 50\n'
      % (a.res, a.res))
    w('Camera "perspective" "float fov" [ 32 ] "float focaldistance" 21\n')
    w("WorldBegin\n")
    w('LightSource "infinite" "rgb L" [ 1 1 1 ]\n')
    w('Material "hair" "float beta_m" 0.25 "float eumelanin" 2\n')
    w("AttributeBegin\n")
    w('CoordSysTransform "camera"\n')
    w("Translate 0 0 21\n")
    for _ in range(a.curves):
        # a uniform direction, then a hair leaving the sphere along it with a little curl
        z = rng.uniform(-1.0, 1.0)
        phi = rng.uniform(0.0, 2.0 * math.pi)
        s = math.sqrt(max(0.0, 1.0 - z * z))
        n = (s * math.cos(phi), s * math.sin(phi), z)
        pts = []
        for k, rad in enumerate((3.0, 3.35, 3.7, 4.0)):
            j = 0.0 if k == 0 else 0.25 * k
            pts.append(tuple(rad * n[i] + rng.uniform(-j, j) for i in range(3)))
        w('Shape "curve" "string type" "cylinder" "float width0" 0.04 "float width1" 0.01 "point3 P" [ %s ]\n'
          % " ".join("%.5f" % c for p in pts for c in p))
    w("AttributeEnd\n")
    print("".join(out), end="")


if __name__ == "__main__":
    main()
