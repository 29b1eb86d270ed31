#!/usr/bin/env bash
# --display tev (cli/tev.c) against a loopback tev-protocol server (tev_server.c): the stream
# reassembles into the EXR the same render writes, bit for bit as float (tiles, exposure,
# several passes, SPPM's one image); a refused and a broken connection are one warning and
# the render goes on; bad --display values are located usage errors; caustic view streams
# what it saves; the server refuses malformed streams (its size checks). Usage:
# tev_tests.sh CAUSTIC SOURCE-DIR TEV_SERVER
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init tev_tests "$@"
SERVER=$(realpath "$3")

# serve NAME EXPECTED [--drop-after N]: the server in the background (SPID), its port in PORT,
# its stdout and stderr in $TMP/NAME.server.{out,err}.
serve() {
    local name=$1 expected=$2
    shift 2
    rm -f "$TMP/$name.port"
    "$SERVER" "$TMP/$name.port" "$expected" "$@" >"$TMP/$name.server.out" 2>"$TMP/$name.server.err" &
    SPID=$!
    for _ in $(seq 100); do
        [ -s "$TMP/$name.port" ] && break
        sleep 0.1
    done
    PORT=$(cat "$TMP/$name.port" 2>/dev/null)
}

# served NAME TESTNAME [ERE ...]: the server ended with 0 and its stdout matches every ERE.
served() {
    local name=$1 test=$2
    shift 2
    local src=0
    wait "$SPID" || src=$?
    local re ok=1
    for re in "$@"; do grep -Eq -- "$re" "$TMP/$name.server.out" || ok=0; done
    if [ "$src" -eq 0 ] && [ $ok -eq 1 ]; then
        pass "$test"
        sed 's/^/      /' "$TMP/$name.server.out"
    else
        fail "$test" "server exit $src" "server: $(cat "$TMP/$name.server.out" "$TMP/$name.server.err" | head -c 800)"
    fi
}

# The pixels as they converge: 8 spp in passes of 1, 2, 4, 1 (passes last about a second
# with a pass callback), each streamed, the last after the render.
dir=$TMP/passes
mkdir -p "$dir"
serve passes "$dir/out.exr"
harness_run "$dir" 120 render --width 64 --height 48 --spp 8 --threads 2 -q -o out.exr --display "tev:127.0.0.1:$PORT"
expect "render --display: exit 0, no warning" 0
check "render --display: nothing on stderr" test ! -s "$ERR"
served passes "render --display: the stream equals out.exr bit for bit, more than one image sent" \
    "equal bit for bit" "image 'out.exr' 64x48, 3 channels: .* 1 create, " "([2-9]|[1-9][0-9])\.00 images' worth"

# Several tiles, partial ones at the right and bottom edges (200 = 128 + 72, 150 = 128 + 22),
# and the exposure the EXR is written with.
dir=$TMP/tiles
mkdir -p "$dir"
serve tiles "$dir/out.exr"
harness_run "$dir" 120 render --width 200 --height 150 --spp 2 --threads 2 --exposure 1.5 -q -o out.exr \
    --display "tev:localhost:$PORT"
expect "render --display, 200x150 with --exposure 1.5: exit 0" 0
served tiles "render --display: four tiles per image, the exposure applied, equal bit for bit" \
    "equal bit for bit" "\(4 tiles each\)"

# SPPM's film holds its estimate only at the end: one image, the final one.
dir=$TMP/sppm
mkdir -p "$dir"
serve sppm "$dir/out.exr"
harness_run "$dir" 120 render --width 48 --height 48 --spp 4 --threads 2 --integrator sppm -q -o out.exr \
    --display "tev:127.0.0.1:$PORT"
expect "render --display --integrator sppm: exit 0" 0
served sppm "render --display sppm: the final image only, equal bit for bit" "equal bit for bit" "1\.00 images' worth"

# A tev that goes away mid-render: one warning, the render goes on and writes its image.
dir=$TMP/broken
mkdir -p "$dir"
serve broken "$dir/out.exr" --drop-after 2
harness_run "$dir" 120 render --width 160 --height 160 --spp 16 --threads 2 -q -o out.exr --display "tev:127.0.0.1:$PORT"
wait "$SPID"
expect "render --display, the connection dropped: one warning, exit 0" 0 \
    "warning: --display tev:127.0.0.1:$PORT: the connection broke: .*going on without the display"
check "render --display, the connection dropped: the warning once" test "$(grep -c warning "$ERR")" -eq 1
check "render --display, the connection dropped: the image is written" test -s "$dir/out.exr"

# Nobody listening (the last server's port, now closed): one warning, the render goes on.
dir=$TMP/refused
harness_run "$dir" 60 render --width 16 --height 16 --spp 1 -q -o out.exr --display "tev:127.0.0.1:$PORT"
expect "render --display, connection refused: one warning, exit 0" 0 \
    "warning: --display tev:127.0.0.1:$PORT: cannot connect: Connection refused; going on without the display"
check "render --display, connection refused: the warning once" test "$(grep -c warning "$ERR")" -eq 1
check "render --display, connection refused: the image is written" test -s "$dir/out.exr"

# Bad values: located usage errors before anything is loaded.
for bad in "tv" "tev:" "tev:host" "tev::14158" "tev:host:0" "tev:host:65536" "tev:host:12x"; do
    harness_run "$TMP/bad" 20 render --display "$bad" -q -o out.png
    expect "render --display '$bad': exit 2 with what was expected" 2 "--display: .*expected"
done
harness_run "$TMP/bad" 20 info --display tev
expect "info --display: an option of render and view only, exit 2" 2 "--display is an option of 'render' and 'view'"

# The server itself refuses what does not fit: each malformed stream is a protocol error
# (exit 3) with the reason, never a read past a packet or an image.
malformed() {
    local name=$1 want=$2
    serve "bad-$name" "$TMP/none.exr"
    python3 - "$PORT" "$name" <<'EOF2'
import socket, struct, sys
def pkt(t, body): return struct.pack('<I', 5 + len(body)) + bytes([t]) + body
names = b'R\x00G\x00B\x00'
create = pkt(4, b'\x01img\x00' + struct.pack('<iii', 4, 4, 3) + names)
def update(x, y, w, h, offs, strides, floats):
    return pkt(6, b'\x00img\x00' + struct.pack('<i', 3) + names + struct.pack('<iiii', x, y, w, h)
               + struct.pack('<qqq', *offs) + struct.pack('<qqq', *strides) + b'\x00' * (4 * floats))
streams = {
    'type': pkt(9, b''),
    'length': struct.pack('<I', 0x7fffffff) + b'\x04',
    'truncated': create[:-3],
    'outside': create + update(3, 3, 2, 2, (0, 1, 2), (3, 3, 3), 12),
    'stride': create + update(0, 0, 2, 2, (0, 1, 2), (3, 3, 1 << 62), 12),
    'short': create + update(0, 0, 2, 2, (0, 1, 2), (3, 3, 3), 11),
    'noimage': update(0, 0, 1, 1, (0, 1, 2), (3, 3, 3), 3),
    'size': pkt(4, b'\x01img\x00' + struct.pack('<iii', 1 << 20, 1 << 20, 3) + names),
}
s = socket.create_connection(('127.0.0.1', int(sys.argv[1])))
s.sendall(streams[sys.argv[2]])
s.close()
EOF2
    local src=0
    wait "$SPID" || src=$?
    if [ "$src" -eq 3 ] && grep -Eq -- "protocol error: .*$want" "$TMP/bad-$name.server.err"; then
        pass "tev_server refuses a stream with $name ($want)"
    else
        fail "tev_server refuses a stream with $name" "exit $src" "$(cat "$TMP/bad-$name.server.err")"
    fi
}
malformed type "a packet type"
malformed length "packet length out of range"
malformed truncated "ends inside"
malformed outside "not inside the image"
malformed stride "reach past the pixel data"
malformed short "reach past the pixel data"
malformed noimage "no image of that name"
malformed size "width or height out of range"

# caustic view streams the image it shows: after its last pass the stream equals its save.
if "$BIN" --version | grep -Eq '^sdl2: +yes'; then
    harness_display
    dir=$TMP/view
    mkdir -p "$dir"
    printf 'wait-spp 3\nsave view.exr\nquit\n' >"$dir/script.txt"
    serve view "$dir/view.exr"
    (cd "$dir" && ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 timeout -k 5 300 "${RUNNER[@]}" \
        "$BIN" view --width 64 --height 64 --threads 2 --spp 3 --script script.txt \
        --display "tev:127.0.0.1:$PORT" >"$OUT" 2>"$ERR" </dev/null)
    RC=$?
    HARNESS_EXPECT_STDOUT=1 expect "view --display: the script runs" 0 "saved view.exr"
    served view "view --display: the stream ends on the saved image, bit for bit" "equal bit for bit" \
        "image 'caustic view' 64x64"
else
    skip "view --display: this caustic was built without SDL2"
fi

harness_finish
