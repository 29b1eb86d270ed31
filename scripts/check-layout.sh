#!/usr/bin/env bash
# Reports where the source tree's layout rules are broken, one "file:line: what" per line:
#   - a .c/.h file in src/, cli/, include/ or tests/ longer than 1,200 lines;
#   - a function (top-level definition, found by brace matching) longer than 150 lines;
#   - an #include "x/y.h" in src/ of a module in a higher layer than the including file's.
# Layers, high to low: cli 5, render 4, integrators 3, scene 2.5 (scene/pbrt, scene/json
# too), accel materials lights camera film textures media 2, geometry sampling io 1, math
# core 0. The public header caustic/caustic.h may be included anywhere.
# Exit 0 when there is nothing to report, 1 otherwise. Run from anywhere:
#   scripts/check-layout.sh
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 - "$@" <<'EOF'
import os, re, sys

MAX_FILE, MAX_FUNC = 1200, 150
LAYER = {"cli": 5, "render": 4, "integrators": 3, "scene": 2.5,
         "accel": 2, "materials": 2, "lights": 2, "camera": 2, "film": 2, "textures": 2, "media": 2,
         "geometry": 1, "sampling": 1, "io": 1, "math": 0, "core": 0}
PUBLIC = ("caustic/caustic.h", "caustic/caustic_compare.h", "caustic/caustic_shapes.h", "caustic/caustic_displace.h", "caustic/caustic_textures.h")

def sources(roots):
    for root in roots:
        for dp, dirs, files in os.walk(root):
            dirs.sort()
            for f in sorted(files):
                if f.endswith((".c", ".h")):
                    yield os.path.join(dp, f)

def blank(m):
    """Replaces a comment or literal by spaces, keeping its newlines (line numbers hold)."""
    return re.sub(r"[^\n]", " ", m.group(0))

def strip(text):
    return re.sub(r'/\*.*?\*/|//[^\n]*|"(?:\\.|[^"\\\n])*"|\'(?:\\.|[^\'\\\n])*\'', blank, text, flags=re.S)

def functions(code):
    """(name, first line, line count) of every top-level function definition."""
    depth, start, out = 0, 0, []
    header_end = 0  # where the text before the current top-level brace starts
    for i, c in enumerate(code):
        if c == "{":
            if depth == 0:
                head = code[header_end:i]
                m = re.search(r"(\w+)\s*\(([^;{}()]|\([^;{}]*\))*\)\s*$", head)
                if m and not re.search(r"=\s*$|\b(struct|union|enum)\b[^()]*$", head[:m.start()]) \
                        and m.group(1) not in ("if", "for", "while", "switch", "return", "sizeof"):
                    start = (header_end + m.start(1), m.group(1))
                else:
                    start = None
            depth += 1
        elif c == "}":
            depth -= 1
            if depth == 0:
                if start:
                    first = code.count("\n", 0, start[0]) + 1
                    last = code.count("\n", 0, i) + 1
                    out.append((start[1], first, last - first + 1))
                header_end = i + 1
        elif c in ";" and depth == 0:
            header_end = i + 1
        elif c == "#" and depth == 0:
            # skip a preprocessor line (and its continuations) at top level
            header_end = i + 1
    return out

def module_of(path):
    parts = path.split(os.sep)
    if parts[0] == "cli":
        return "cli"
    if parts[0] == "src" and len(parts) > 2:
        return parts[1]
    return None

problems = []
for path in sources(["src", "cli", "include", "tests"]):
    with open(path, encoding="utf-8", errors="replace") as fh:
        text = fh.read()
    lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
    if lines > MAX_FILE:
        problems.append(f"{path}:1: {lines} lines (limit {MAX_FILE})")
    code = strip(text)
    # preprocessor lines are not code for brace matching
    code = re.sub(r"(?m)^[ \t]*#(?:[^\n]*\\\n)*[^\n]*", blank, code)
    for name, first, count in functions(code):
        if count > MAX_FUNC:
            problems.append(f"{path}:{first}: function {name}() is {count} lines (limit {MAX_FUNC})")
    if not path.startswith("src" + os.sep):
        continue
    mod = module_of(path)
    here = LAYER.get(mod)
    for n, line in enumerate(text.split("\n"), 1):
        m = re.match(r'\s*#\s*include\s*"([^"]+)"', line)
        if not m or m.group(1) in PUBLIC:
            continue
        inc = m.group(1)
        target = inc.split("/")[0] if "/" in inc else mod
        there = LAYER.get(target)
        if here is None or there is None:
            problems.append(f'{path}:{n}: includes "{inc}": layer of {mod if here is None else target} unknown')
        elif there > here:
            problems.append(f'{path}:{n}: includes "{inc}" ({target}, layer {there:g}) from {mod} (layer {here:g})')

for p in problems:
    print(p)
print(f"check-layout: {len(problems)} problem(s)", file=sys.stderr)
sys.exit(1 if problems else 0)
EOF
