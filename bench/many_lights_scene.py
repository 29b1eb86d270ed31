#!/usr/bin/env python3
"""Writes bench/many-lights.json: a floor and a wall under 200 small one-sided quad lights
and 20 small emitting spheres of random colours (fixed seed), the light-BVH benchmark
scene of docs/benchmarks.md. Usage: python3 bench/many_lights_scene.py > bench/many-lights.json"""
import json
import random

rng = random.Random(2018)
shapes = [
    {"type": "quad", "material": "white",
     "vertices": [[-10, 0, -10], [-10, 0, 10], [10, 0, 10], [10, 0, -10]]},
    {"type": "quad", "material": "white",
     "vertices": [[-10, 0, 10], [-10, 10, 10], [10, 10, 10], [10, 0, 10]]},
    {"type": "sphere", "material": "white", "center": [-2, 1, 2], "radius": 1},
    {"type": "sphere", "material": "white", "center": [3, 1.5, 4], "radius": 1.5},
]
r3 = lambda v: round(v, 3)
for _ in range(200):
    x, z = 16 * rng.random() - 8, 16 * rng.random() - 8
    h, q = 0.5 + 4 * rng.random(), 0.1 + 0.2 * rng.random()
    a = 20 + 80 * rng.random()
    # (v1 - v0) x (v2 - v0) points down: each light faces the floor
    shapes.append({"type": "quad", "material": "black",
                   "vertices": [[r3(x), r3(h), r3(z)], [r3(x + q), r3(h), r3(z)],
                                [r3(x + q), r3(h), r3(z + q)], [r3(x), r3(h), r3(z + q)]],
                   "emission": {"radiance": [r3(a * rng.random()) for _ in range(3)]}})
for _ in range(20):
    c = [r3(16 * rng.random() - 8), r3(0.5 + 5 * rng.random()), r3(16 * rng.random() - 8)]
    shapes.append({"type": "sphere", "material": "black", "center": c,
                   "radius": r3(0.05 + 0.1 * rng.random()), "emission": {"radiance": [10, 8, 6]}})
scene = {
    "film": {"width": 256, "height": 192, "filter": "box", "output": "many-lights.png"},
    "camera": {"type": "pinhole", "position": [0, 6, -14], "look_at": [0, 1, 2], "up": [0, 1, 0],
               "fov": 55},
    "integrator": {"type": "path", "max_depth": 5},
    "sampler": {"spp": 16, "seed": 1},
    "materials": {"white": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
                  "black": {"type": "diffuse", "albedo": [0, 0, 0]}},
    "shapes": shapes,
}
print(json.dumps(scene, indent=1))
