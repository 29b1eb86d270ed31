#!/usr/bin/env bash
# Hostile input files (issue 25, items 1-4 and 10): special files instead of scenes,
# includes, meshes, textures and environment maps; texture chains deep enough to overflow a
# recursive reader; mesh files that abort or crash assimp; NaN, Inf and negative pixels;
# control bytes, invalid UTF-8 and byte order marks. Every case must end with a located
# error (exit 2) or load, never hang, abort or crash. Run by CTest:
#   bash inputs_tests.sh <path-to-caustic-binary> <source-dir>
# Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init inputs_tests "$@"
cd "$TMP" || exit 2

# run SECONDS ARGS...: caustic in $TMP with a time limit, so a read that never ends fails
# the test (exit 124) instead of hanging it; sets RC.
run() { local limit=$1; shift; harness_run "$TMP" "$limit" "$@"; }

# clean_stderr NAME: stderr holds no control byte but newlines, no DEL, and valid UTF-8.
clean_stderr() {
    if tr -d '\n' <"$ERR" | LC_ALL=C grep -q $'[\x01-\x1f\x7f]'; then
        fail "$1" "stderr holds raw control bytes"
    elif command -v iconv >/dev/null && ! iconv -f UTF-8 -t UTF-8 <"$ERR" >/dev/null 2>&1; then
        fail "$1" "stderr is not valid UTF-8"
    elif LC_ALL=C grep -q $'\xef\xbb\xbf' "$ERR"; then
        fail "$1" "stderr holds a raw byte order mark"
    else
        pass "$1"
    fi
}

# Scenes around one file reference each: SUB is replaced by the file name.
json_scene() { # json_scene OUT.json KIND NAME: KIND texture, mesh, env
    local body
    case $2 in
    texture) body='"textures": {"t": {"type": "image", "file": "'$3'"}},
 "materials": {"m": {"type": "diffuse", "albedo": "t"}},
 "shapes": [{"type": "sphere", "material": "m", "center": [0, 0, 0], "radius": 1, "emission": {"radiance": [1, 1, 1]}}]' ;;
    mesh) body='"materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
 "shapes": [{"type": "meshfile", "file": "'$3'", "material": "m"},
            {"type": "sphere", "material": "m", "center": [0, 0, 3], "radius": 1, "emission": {"radiance": [1, 1, 1]}}]' ;;
    env) body='"materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
 "environment": {"file": "'$3'"},
 "shapes": [{"type": "sphere", "material": "m", "center": [0, 0, 0], "radius": 1}]' ;;
    esac
    printf '{"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},\n "film": {"width": 8, "height": 8},\n %s}\n' "$body" >"$1"
}
pbrt_scene() { # pbrt_scene OUT.pbrt LINE: a minimal pbrt scene with LINE in its world block
    printf 'LookAt 0 0 -5  0 0 0  0 1 0\nCamera "perspective"\nFilm "rgb" "integer xresolution" 8 "integer yresolution" 8\nWorldBegin\nLightSource "point" "rgb I" [1 1 1]\nShape "sphere" "float radius" 1\n%s\n' "$2" >"$1"
}

# ------------------------------------------------------- 1. files that are not regular
if command -v mkfifo >/dev/null && mkfifo fifo.json fifo.pbrt fifo.png fifo.obj fifo.pfm fifo.ply 2>/dev/null; then
    have_fifo=1
else
    have_fifo=0
    echo "SKIP: FIFO cases (mkfifo unavailable)"
fi
for ext in json pbrt png obj pfm ply; do
    ln -s /dev/zero "zero.$ext"
    mkdir "dir.$ext"
done
kinds="zero dir"
[ $have_fifo -eq 1 ] && kinds="fifo $kinds"
nonreg='is not a regular file|is a directory'
for k in $kinds; do
    run 10 info "$k.json"
    expect "info: a $k as the JSON scene is refused" 2 "$nonreg"
    run 10 info "$k.pbrt"
    expect "info: a $k as the pbrt scene is refused" 2 "$nonreg"
    pbrt_scene "inc_$k.pbrt" "Include \"$k.pbrt\""
    run 10 info "inc_$k.pbrt"
    expect "pbrt Include of a $k: located error" 2 "^caustic: error: inc_$k\\.pbrt:7:9: Include: $k\\.pbrt: is not a regular file"
    json_scene "tex_$k.json" texture "$k.png"
    run 10 info "tex_$k.json"
    expect "JSON image texture from a $k: located error" 2 "tex_$k\\.json:[0-9]+:[0-9]+: textures\\.t\\.file: $k\\.png: is not a regular file"
    json_scene "mesh_$k.json" mesh "$k.obj"
    run 10 info "mesh_$k.json"
    expect "JSON meshfile from a $k: located error" 2 "mesh_$k\\.json:[0-9]+:[0-9]+: shapes\\[0\\]\\.file: $k\\.obj: is not a regular file"
    json_scene "env_$k.json" env "$k.pfm"
    run 10 info "env_$k.json"
    expect "JSON environment map from a $k: located error" 2 "environment\\.file: $k\\.pfm: is not a regular file"
    pbrt_scene "ply_$k.pbrt" "Shape \"plymesh\" \"string filename\" \"$k.ply\""
    run 10 info "ply_$k.pbrt"
    expect "pbrt plymesh from a $k: located error" 2 "ply_$k\\.pbrt:7:[0-9]+: Shape \"plymesh\": $k\\.ply: is not a regular file"
done
if [ $have_fifo -eq 1 ]; then
    run 10 verify fifo.json --integrators path,path-nee --spp 2 --quiet
    expect "verify: a FIFO as the scene is refused" 2 "is not a regular file \\(a FIFO\\)"
    # a file the mesh references (assimp opens it through the same check)
    mkfifo fifo.bin
    printf '{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}], "buffers": [{"byteLength": 44, "uri": "fifo.bin"}], "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}], "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}, {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}' >fifobin.gltf
    json_scene mesh_fifobin.json mesh fifobin.gltf
    run 10 info mesh_fifobin.json
    expect "glTF buffer in a FIFO: refused, not waited for" 2 "fifo\\.bin: is not a regular file"
fi

# ------------------------------------------------------- 2. texture chains
# t0 -> t1 -> ... -> t(N-1): each checkerboard's "even" names the next texture.
chain() {
    awk -v n="$1" 'BEGIN {
        printf "{\"camera\": {\"position\": [0, 0, -5], \"look_at\": [0, 0, 0], \"up\": [0, 1, 0], \"fov\": 40},\n";
        printf " \"film\": {\"width\": 4, \"height\": 4}, \"sampler\": {\"spp\": 1},\n \"textures\": {\n";
        for (i = 0; i < n; i++) {
            nxt = (i + 1 < n) ? sprintf("\"t%d\"", i + 1) : "[0.5, 0.5, 0.5]";
            printf "  \"t%d\": {\"type\": \"checkerboard\", \"even\": %s, \"odd\": [0.1, 0.1, 0.1]}%s\n", i, nxt, (i + 1 < n) ? "," : "";
        }
        printf " },\n \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": \"t0\"}},\n";
        printf " \"shapes\": [{\"type\": \"sphere\", \"material\": \"m\", \"center\": [0, 0, 0], \"radius\": 1, \"emission\": {\"radiance\": [1, 1, 1]}}]}\n";
    }' >"$2"
}
for n in 10000 100000; do
    chain $n "chain$n.json"
    run 120 info "chain$n.json"
    expect "a checkerboard chain of $n textures loads (no stack overflow)" 0
done
run 120 render chain10000.json -o chain.png --quiet
expect "a checkerboard chain of 10000 textures renders" 0
printf '{"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
 "textures": {"a": {"type": "checkerboard", "even": "b", "odd": [0, 0, 0]},
              "b": {"type": "checkerboard", "even": [1, 1, 1], "odd": "a"}},
 "materials": {"m": {"type": "diffuse", "albedo": "a"}},
 "shapes": [{"type": "sphere", "material": "m", "center": [0, 0, 0], "radius": 1, "emission": {"radiance": [1, 1, 1]}}]}\n' >cycle.json
run 10 info cycle.json
expect "a checkerboard cycle is a located error" 2 'cycle\.json:3:[0-9]+: textures\.b\.odd: texture "a" contains itself'

# ------------------------------------------------------- 3. meshes that abort assimp
ply_header() { # ply_header FORMAT FACES
    printf 'ply\nformat %s 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n' "$1" "$2"
}
{ ply_header ascii 2; printf '0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n0\n'; } >face0.ply
{ ply_header ascii 2; printf '0 0 0\n1 0 0\n0 1 0\n0\n3 0 1 2\n'; } >face0first.ply
# binary: three vertices of 12 bytes, a triangle, then a face with count 0
{ ply_header binary_little_endian 2
  printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\077\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\077\0\0\0\0'
  printf '\003\0\0\0\0\001\0\0\0\002\0\0\0\000'; } >face0le.ply
{ ply_header binary_big_endian 2
  printf '\0\0\0\0\0\0\0\0\0\0\0\0\077\200\0\0\0\0\0\0\0\0\0\0\0\0\0\0\077\200\0\0\0\0\0\0'
  printf '\003\0\0\0\0\0\0\0\001\0\0\0\002\000'; } >face0be.ply
# pbrt-v4 skips a face of other than 3 or 4 vertices with a warning, and so do we (these
# aborted assimp 5.2 before PLY files went to our own reader, io/ply.c).
for f in face0 face0first face0le face0be; do
    json_scene "mesh_$f.json" mesh "$f.ply"
    run 20 info "mesh_$f.json"
    expect "JSON meshfile, PLY face with 0 vertices ($f): skipped with a warning, not abort" 0 \
        "warning: .*$f\\.ply: 1 faces of other than 3 or 4 vertices skipped \\(the first has 0\\)"
done
pbrt_scene ply0.pbrt 'Shape "plymesh" "string filename" "face0.ply"'
run 20 info ply0.pbrt
expect "pbrt plymesh, PLY face with 0 vertices: skipped with a located warning" 0 \
    'ply0\.pbrt:7:[0-9]+: Shape "plymesh": "face0\.ply": 1 faces of other than 3 or 4 vertices skipped'
{ ply_header ascii 1; printf '0 0 0\n1 0 0\n0 1 0\n0\n'; } >onlyface0.ply
pbrt_scene plyonly0.pbrt 'Shape "plymesh" "string filename" "onlyface0.ply"'
run 20 info plyonly0.pbrt
expect "pbrt plymesh, PLY with no usable face: located error" 2 \
    'plyonly0\.pbrt:7:[0-9]+: Shape "plymesh": .*onlyface0\.ply: no triangles in the file'
# Our PLY reader (io/ply.c) on lying, truncated and compressed files (issue 26): exit 2
# with the file and the place (header line, ASCII line, binary byte offset).
{ ply_header binary_little_endian 2
  printf '\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\077\0\0\0\0\0\0\0\0\0\0\0\0\0\0\200\077\0\0\0\0'
  printf '\003\0\0\0\0\001\0\0\0\002\0\0\0\003\0\0\0\0\001\0\0\0\011\0\0\0'; } >badindex.ply
{ ply_header binary_little_endian 2; printf '\0\0\0\0\0\0'; } >cut.ply
{ ply_header ascii 900000000; printf '0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n'; } >lying.ply
printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty list uchar float x2\nproperty quux y\nend_header\n' >garbage.ply
pbrt_scene badindex.pbrt 'Shape "plymesh" "string filename" "badindex.ply"'
run 20 info badindex.pbrt
expect "pbrt plymesh, PLY index out of range: located error" 2 \
    'badindex\.pbrt:7:[0-9]+: Shape "plymesh": .*badindex\.ply: byte [0-9]+: malformed PLY data: face 2 of 2 \(starting at byte [0-9]+\): vertex index 9 .* out of range'
for f in cut lying garbage; do json_scene "mesh_$f.json" mesh "$f.ply"; done
run 20 info mesh_cut.json
expect "JSON meshfile, truncated binary PLY: located error" 2 \
    'mesh_cut\.json:[0-9]+:[0-9]+: shapes\[0\]\.file: .*cut\.ply: byte [0-9]+: malformed PLY data: element "vertex" declares 3 records of at least 12 bytes each, but only 6 bytes are left'
run 20 info mesh_lying.json
expect "JSON meshfile, face count larger than the data: located error, no allocation" 2 \
    'lying\.ply: byte [0-9]+: malformed PLY data: element "face" declares 900000000 records'
run 20 info mesh_garbage.json
expect "JSON meshfile, PLY header garbage: located error" 2 'garbage\.ply:6: malformed PLY header: unknown property type "quux"'
# gzip: a .ply.gz plymesh, a corrupt one, a .pbrt.gz Include
{ ply_header ascii 1; printf '0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n'; } | gzip -9n >tri.ply.gz
head -c 40 tri.ply.gz >cutgz.ply.gz
pbrt_scene gz.pbrt 'Shape "plymesh" "string filename" "tri.ply.gz"'
run 20 info gz.pbrt
expect "pbrt plymesh of a .ply.gz loads" 0
grep -q "^triangles: *1$" "$OUT" && pass "pbrt plymesh of a .ply.gz: its triangle" || fail "pbrt plymesh of a .ply.gz: its triangle" "$(cat "$OUT")"
pbrt_scene cutgz.pbrt 'Shape "plymesh" "string filename" "cutgz.ply.gz"'
run 20 info cutgz.pbrt
expect "pbrt plymesh of a truncated .ply.gz: located error" 2 \
    'cutgz\.pbrt:7:[0-9]+: Shape "plymesh": .*cutgz\.ply\.gz: the gzip data ends early'
printf 'Shape "plymesh" "string filename" "tri.ply.gz"\n' | gzip -9n >inc.pbrt.gz
pbrt_scene incgz.pbrt 'Include "inc.pbrt.gz"'
run 20 info incgz.pbrt
expect "pbrt Include of a .pbrt.gz loads" 0
printf 'not gzip' >fake.pbrt.gz
pbrt_scene fakegz.pbrt 'Import "fake.pbrt.gz"'
run 20 info fakegz.pbrt
expect "pbrt Import of a .pbrt.gz that is not gzip: located error" 2 \
    'fakegz\.pbrt:7:[0-9]+: Import: .*fake\.pbrt\.gz: not gzip data'
# assimp 5.2 takes any file whose first three bytes are "ply" for a PLY: a first line that
# is not "ply" alone made it spin or read out of bounds (fuzz_mesh, docs/fuzzing.md).
printf 'plyply\nformat binary_little' >plyply.ply
printf 'plyformat ascii 1.0\nelement vertex 3\nend_header\n' >plyformat.obj
for f in plyply.ply plyformat.obj; do
    json_scene "mesh_${f%.*}.json" mesh "$f"
    run 20 info "mesh_${f%.*}.json"
    expect "mesh file starting \"ply\" without the line \"ply\" ($f): error, no hang" 2 \
        "$f:1: malformed PLY header: expected \"ply\""
done
# glTF: one triangle (three positions, three uint16 indices) in an embedded buffer;
# MODE and COUNT are the primitive's mode and its index count.
gltf() { # gltf OUT MODE COUNT [NODES]
    local nodes=${4:-'[{"mesh": 0}]'}
    printf '{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": %s,
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": %d}]}],
 "buffers": [{"byteLength": 44, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAABAAIAAAA="}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
               {"bufferView": 1, "componentType": 5123, "count": %d, "type": "SCALAR"}]}\n' "$nodes" "$2" "$3" >"$1"
}
gltf ok.gltf 4 3
json_scene mesh_ok.json mesh ok.gltf
run 20 info mesh_ok.json
expect "glTF: a valid triangle still loads" 0
gltf loop1.gltf 2 1     # assimp: ai_assert in glTF2Importer.cpp:812, abort
gltf fan2.gltf 6 2      # assimp: writes a face past an empty array
gltf strip2.gltf 5 2
gltf lstrip1.gltf 3 1   # assimp: writes a face past an empty array
deep=$(awk 'BEGIN { printf "["; for (i = 0; i < 20000; i++) printf "{\"children\": [%d]}, ", i + 1; printf "{\"mesh\": 0}]" }')
gltf deep.gltf 4 3 "$deep" # assimp: stack overflow in its node recursion
for f in loop1:LINE_LOOP fan2:TRIANGLE_FAN strip2:TRIANGLE_STRIP lstrip1:LINE_STRIP deep:'nested more than'; do
    name=${f%%:*}
    json_scene "mesh_$name.json" mesh "$name.gltf"
    run 20 info "mesh_$name.json"
    expect "glTF $name: error, not abort or crash" 2 "shapes\\[0\\]\\.file: $name\\.gltf: (malformed|unsupported) glTF file: .*${f#*:}"
done
# GLB whose JSON chunk claims 1e9 bytes (assimp allocates and reads for ~20 s)
{ printf 'glTF\002\0\0\0\100\0\0\0'; printf '\000\312\232\073JSON'; printf '{"asset": {"version": "2.0"}}   '; } >huge.glb
json_scene mesh_huge.json mesh huge.glb
run 10 info mesh_huge.json
expect "GLB with a JSON chunk longer than the file: quick error" 2 "huge\\.glb: malformed glTF file: a JSON chunk of 1000000000 bytes"

# ------------------------------------------------------- 4. NaN, Inf, negative pixels
# A 2 x 2 PFM (rows bottom to top), every value 0.5 except channel G of pixel (1, 0) (top
# row, so the file's last row).
pfm() { # pfm OUT BYTES-OF-THE-ODD-FLOAT
    local h='\0\0\0\077'
    { printf 'PF\n2 2\n-1.0\n'
      printf "$h$h$h$h$h$h"            # bottom row
      printf "$h$h$h$h$1$h"; } >"$2"  # top row: pixel (1, 0) channel G
}
pfm '\0\0\300\177' nan.pfm
pfm '\0\0\200\177' inf.pfm
pfm '\0\0\200\277' neg.pfm
for v in nan:nan inf:inf neg:-1; do
    f=${v%%:*} val=${v#*:}
    want="$f\\.pfm: pixel \\(1, 0\\) channel G is $val; expected a finite value >= 0"
    json_scene "env_$f.json" env "$f.pfm"
    run 10 info "env_$f.json"
    expect "JSON environment map with a $f pixel: error with its position" 2 "env_$f\\.json:[0-9]+:[0-9]+: environment\\.file: $want"
    json_scene "tex_$f.json" texture "$f.pfm"
    run 10 info "tex_$f.json"
    expect "JSON texture with a $f pixel: error with its position" 2 "textures\\.t\\.file: $want"
    pbrt_scene "env_$f.pbrt" "LightSource \"infinite\" \"string filename\" \"$f.pfm\""
    run 10 info "env_$f.pbrt"
    expect "pbrt infinite light with a $f pixel: error with its position" 2 "env_$f\\.pbrt:7:[0-9]+: LightSource \"infinite\": $want"
    pbrt_scene "tex_$f.pbrt" "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"$f.pfm\""
    run 10 info "tex_$f.pbrt"
    expect "pbrt imagemap with a $f pixel: error with its position" 2 "tex_$f\\.pbrt:7:[0-9]+: .*$want"
done

# ------------------------------------------------------- 10. raw bytes in messages, BOMs
bom=$'\xef\xbb\xbf'
{ printf '%s' "$bom"; cat "$SRC/scenes/cornell-box.pbrt"; } >bom.pbrt
run 30 info bom.pbrt
expect "pbrt: a leading UTF-8 BOM is skipped" 0
{ printf '%s' "$bom"; cat "$SRC/scenes/cornell-box.json"; } >bom.json
run 30 info bom.json
expect "JSON: a leading UTF-8 BOM is skipped" 0
{ printf '%s' "$bom"; printf 'LookAt 0 0 -5  0 0 0  0 1 0\nCamera "perspective"\nWorldBegin\nInclude "\033[31mred\xff.pbrt"\n'; } >esc.pbrt
run 10 info esc.pbrt
expect "pbrt: BOM + an escape sequence in an Include: located at the Include" 2 'esc\.pbrt:4:9: Include: \\x1B\[31mred\\xFF\.pbrt: cannot open'
clean_stderr "pbrt: no raw bytes echoed from an Include name"
printf 'WorldBegin\nShape "\033[31mx\xfe\xc2\x9b"\n' >esc2.pbrt
run 10 info esc2.pbrt
expect "pbrt: unknown shape with control bytes and invalid UTF-8" 2 'esc2\.pbrt:2:7: unknown shape'
clean_stderr "pbrt: no raw bytes echoed from a shape name"
printf '{"materials": {"\033[31mred": {"type": "diffuse"}}}\n' >raw.json
run 10 info raw.json
expect "JSON: a raw control byte in a string is a parse error" 2 'raw\.json:1:'
clean_stderr "JSON: no raw bytes echoed from a parse error"
printf '{"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
 "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
 "shapes": [{"type": "sphere", "material": "\\u001b[31m\\u202e\\ufeffm", "center": [0, 0, 0], "radius": 1}]}\n' >name.json
run 10 info name.json
expect "JSON: an undefined material named with escapes" 2 'name\.json:3:[0-9]+: shapes\[0\]\.material'
clean_stderr "JSON: no raw bytes echoed from a name"
json_scene path.json texture $'\\u001b[31m\\u202ex.png'
run 10 info path.json
expect "JSON: a texture path with control characters" 2 'textures\.t\.file: .*cannot open'
clean_stderr "JSON: no raw bytes echoed from a path"
printf '\xff\xfe{\0}\0' >utf16.json
run 10 info utf16.json
expect "JSON: UTF-16 is named as such" 2 'utf16\.json:1:1: the text is UTF-16'
printf '\xfe\xff\0W' >utf16.pbrt
run 10 info utf16.pbrt
expect "pbrt: UTF-16 is named as such" 2 'utf16\.pbrt:1:1: the file is UTF-16'

harness_finish
