#!/usr/bin/env bash
# Image textures decoded by stb_image and, for JPEG, libjpeg-turbo (docs/fuzzing.md, fixed
# findings 2, 3, 4 and 8): the reproducers of tests/fuzz/crashes/fuzz_image/ must each end
# with a clear error (exit 2) within a second, never an overflow, a multi-second load of
# zeros or a texture in an undocumented format; the seed images of every documented format
# must still load. Run by CTest:
#   bash stb_tests.sh <path-to-caustic-binary> <source-dir>
# Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init stb_tests "$@"
CRASHES=$SRC/tests/fuzz/crashes/fuzz_image
SEEDS=$SRC/tests/fuzz/corpus/fuzz_image
cd "$TMP" || exit 2

# AddressSanitizer reserves terabytes of address space for its shadow memory at start-up,
# so under an ASan build (.ci/run's second pass) the 1 GB limit would abort every run: there
# the limit is left off, and the 3 s timeout still catches a decode that should not happen.
if nm -D "$BIN" 2>/dev/null | grep -q __asan_init || ldd "$BIN" 2>/dev/null | grep -q libasan; then
    VLIMIT=unlimited
else
    VLIMIT=1048576
fi

# check NAME FILE EXT RC [ERE] (this script's own, in place of the harness's): `caustic info` on a scene whose emission texture is FILE
# (copied as t.EXT) exits RC within 3 s (a refusal must not decode anything; 1 GB of
# address space is far more than these 8 x 8 scenes need), stderr matching ERE.
check() {
    local name=$1 file=$2 ext=$3 want=$4 re=${5:-}
    cp "$file" "t.$ext"
    printf '{"camera": {"position": [0, 0, -5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
 "film": {"width": 8, "height": 8},
 "textures": {"t": {"type": "image", "file": "t.%s"}},
 "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
 "shapes": [{"type": "sphere", "material": "m", "center": [0, 0, 0], "radius": 1, "emission": {"radiance": "t"}}]}\n' \
        "$ext" >scene.json
    (ulimit -v "$VLIMIT"; timeout -k 2 3 "$BIN" info scene.json) >/dev/null 2>"$ERR" </dev/null
    local rc=$?
    if [ $rc -ne "$want" ]; then
        local why=""
        [ $rc -eq 124 ] && why=" (still loading after 3 s)"
        [ $rc -ge 128 ] && [ $rc -ne 124 ] && why=" (killed by signal $((rc - 128)))"
        fail "$name" "exit code $rc$why, expected $want"
    elif [ -n "$re" ] && ! grep -Eq -- "$re" "$ERR"; then
        fail "$name" "stderr does not match /$re/"
    else
        pass "$name"
    fi
}

# Finding 2: a JPEG Huffman table of more than 256 codes (stb 2.27 writes past its table).
dht="scene\\.json:[0-9]+:[0-9]+: textures\\.t\\.file: .*t\\.jpg: corrupt JPEG: the Huffman table \\(DHT segment at byte [0-9]+\\) declares 257 codes; at most 256 are possible"
check "JPEG DHT of 257 codes" "$CRASHES/jpeg-dht-257-codes" jpg 2 "$dht"
check "JPEG DHT of 257 codes, FF FF D8 start and padding" "$CRASHES/jpeg-dht-ff-fill-start" jpg 2 "$dht"
check "JPEG DHT of 257 codes after the scan" "$CRASHES/jpeg-dht-after-scan" jpg 2 "$dht"
# Found by fuzz_image: a scan decoding with an AC table no DHT defines; stb 2.27 reads its
# uninitialised decoder as the table (valgrind: uses of uninitialised values; an assertion
# under the fuzzer; on main the error message changes with MALLOC_PERTURB_).
check "JPEG scan with an undefined Huffman table" "$CRASHES/jpeg-undefined-huffman-table" jpg 2 \
    "t\\.jpg: corrupt JPEG: the scan at byte 542 decodes with AC Huffman table 0, which no DHT segment before it defines"
# Found by fuzz_image: a corrupt scan on which stb 2.27's bit reader shifted by 33 bits
# (UBSan, stb_image.h:2065; main loaded it with wrong texels, exit 0). JPEG goes through
# libjpeg-turbo now (src/io/jpeg.c), whose corrupt-data warnings are errors.
libjpeg="t\\.jpg: cannot decode the JPEG \\(libjpeg-turbo, at or after byte [0-9]+\\): "
check "JPEG whose scan stb's bit reader over-shifted on" "$CRASHES/jpeg-stb-code-bits" jpg 2 \
    "${libjpeg}Corrupt JPEG data: 14 extraneous bytes before marker 0xdb"
# A JPEG cut inside its scan: libjpeg's "premature end" warning (it would fill the rest with
# grey, as stb filled it with zeros) is an error.
head -c 620 "$SEEDS/jpeg-rgb" >cut.jpg
check "JPEG cut inside its scan" cut.jpg jpg 2 "${libjpeg}Premature end of JPEG file"
# Bytes inside a segment are not markers: an APP1 holding FF C4 and a "table" of 16 x 255
# codes is skipped as stb skips it, and the image loads.
seed=$SEEDS/jpeg-rgb
{ head -c 20 "$seed"; printf '\377\341\000\027\377\304\000\023\000'; head -c 16 /dev/zero | tr '\0' '\377'; tail -c +21 "$seed"; } >fake-dht.jpg
check "JPEG with FF C4 inside an APP1 segment loads" fake-dht.jpg jpg 0

# Finding 3: declared sizes above the pixel limit or beyond what the file holds.
check "94-byte RLE TGA of 26192 x 13066: pixel limit" "$CRASHES/tga-rle-26192x13066" tga 2 \
    "t\\.tga: the TGA declares 26192 x 13066 pixels; images are limited to 268435456 pixels"
check "94-byte RLE TGA of 4096 x 4096: truncated" "$CRASHES/tga-rle-truncated" tga 2 \
    "t\\.tga: truncated or corrupt TGA: 4096 x 4096 pixels need at least [0-9]+ bytes, the file has 94"
check "94-byte raw TGA of 1000 x 1000: truncated" "$CRASHES/tga-raw-truncated" tga 2 \
    "t\\.tga: truncated or corrupt TGA: 1000 x 1000 pixels need at least 3000018 bytes, the file has 94"
check "flat HDR of 4 x 4096 in 56 bytes: truncated" "$CRASHES/hdr-flat-truncated" hdr 2 \
    "t\\.hdr: truncated or corrupt Radiance HDR: 4 x 4096 pixels"
check "BMP of 4096 x 4096 in 66 bytes: truncated" "$CRASHES/bmp-truncated" bmp 2 \
    "t\\.bmp: truncated or corrupt BMP: 4096 x 4096 pixels"
# Found by fuzz_image in the pre-check itself (it read the bit depth past a 28-byte file).
check "BMP whose info header is cut short" "$CRASHES/bmp-short-info-header" bmp 2 \
    "t\\.bmp: truncated or corrupt BMP: 3 x 2 pixels need at least [0-9]+ bytes, the file has 28"
# Found by fuzz_image: an IDAT chunk declaring 1 GB in a 214-byte file, for which stb 2.27
# allocates 2 GB before it reads (an out-of-memory under the fuzzer, "outofmem" here on main).
check "PNG chunk longer than the file" "$CRASHES/png-chunk-2gb" png 2 \
    "t\\.png: truncated or corrupt PNG: the chunk at byte 103 declares 1073741882 bytes of data, the file has 111"
check "PNG of 16384 x 16384 in 69 bytes: past deflate's 1032:1" "$CRASHES/png-16384-tiny" png 2 \
    "t\\.png: truncated or corrupt PNG: 16384 x 16384 pixels"
# Found by fuzz_image: a 285-byte EXR declaring 100728835 x 2 pixels in one ZIP chunk of 72
# bytes; main allocated its 2.4 GB of floats before decoding (the fuzzer's out-of-memory;
# under this test's 1 GB limit, main's "out of memory" message).
check "EXR chunk too small for its pixels" "$CRASHES/exr-zip-chunk-2gb" exr 2 \
    "t\\.exr: truncated or corrupt OpenEXR: the chunk at line 0 stores 72 bytes for 2417492040 bytes of pixels"

# Finding 4: formats stb reads but caustic does not document.
formats="texture images must be PNG, JPEG, BMP, TGA, Radiance HDR, OpenEXR or PFM files"
check "PPM texture refused" "$CRASHES/ppm-2x2" ppm 2 "t\\.ppm: a PNM \\(PGM/PPM/PBM\\) file; $formats"
check "PNM header number over 2^31 refused" "$CRASHES/pnm-size-overflow" ppm 2 "t\\.ppm: a PNM \\(PGM/PPM/PBM\\) file; $formats"
check "GIF texture refused" "$CRASHES/gif-1x1" gif 2 "t\\.gif: a GIF file; $formats"
printf 'hello' >text.txt
check "unknown content refused" text.txt png 2 "t\\.png: not a PNG, JPEG, BMP, TGA, Radiance HDR, OpenEXR or PFM file"

# The documented formats still load (the fuzzer's seeds: 3 x 2 pixels each).
for s in png-rgb8 png-rgba16 png-gray1 png-palette jpeg-rgb jpeg-progressive jpeg-grey-restart jpeg-cmyk jpeg-arithmetic bmp-rgb24 tga-rgb tga-rle hdr-flat exr-rgb pfm-rgb; do
    check "seed $s loads" "$SEEDS/$s" img 0
done

harness_finish
