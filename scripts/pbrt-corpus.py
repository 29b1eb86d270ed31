#!/usr/bin/env python3
# The pbrt-v4 scene-corpus check (run through scripts/pbrt-corpus.sh): renders every scene of
# the collection with caustic and with pbrt-v4 at a small size and equal spp, and writes one
# Markdown table row per scene (load result, warnings, times, peak memory, caustic compare).
"""Usage: scripts/pbrt-corpus.sh [options]   (see --help)

Each scene is copied (a tree of symbolic links to the original folder, so relative paths
resolve, plus a copy of the scene file whose Film asks for the small size) under the cache,
rendered by both renderers under a per-render time limit, and compared with
`caustic compare`. pbrt-v4's images are cached by scene, size and spp (they do not change
with caustic); caustic's by the SHA-256 of its binary. A run that is interrupted resumes
where it stopped: every finished render leaves a JSON record, which a re-run reads instead
of rendering again (--fresh forgets caustic's records of this binary).
"""
import argparse
import datetime
import gzip
import hashlib
import json
import os
import platform
import re
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Files a scene refers to, by extension (Include/Import, shapes, textures, lights, BSDFs,
# media): what "assets missing" checks.
ASSET_RE = re.compile(r'"([^"\s]+\.(?:pbrt|pbrt\.gz|ply|ply\.gz|obj|exr|png|pfm|tga|jpg|jpeg|hdr|'
                      r'bsdf|nvdb|vdb|spd|raw|bin))"', re.IGNORECASE)
INCLUDE_RE = re.compile(r'^\s*(Include|Import)\s+"([^"]+)"')


def strip_comment(line):
    """The line without a '#' comment (pbrt has no '#' inside the strings we rewrite)."""
    i = line.find('#')
    return line if i < 0 else line[:i]


def referenced_files(path, seen=None, base=None):
    """(missing, present) asset paths of a scene file and of the files it includes. Relative
    names resolve against the main scene file's directory, included files' names too (pbrt-v4's
    rule, and caustic's)."""
    seen = seen if seen is not None else set()
    base = base or os.path.dirname(path)
    missing, present = [], []
    if path in seen:
        return missing, present
    seen.add(path)
    try:
        opener = gzip.open if path.endswith('.gz') else open
        with opener(path, 'rt', errors='replace') as f:
            text = f.read()
    except OSError:
        return [path], present
    in_film = False  # the Film's "filename" is an output, not an asset
    for line in text.splitlines():
        line = strip_comment(line)
        d = re.match(r'\s*([A-Z][A-Za-z]*)\b', line)
        if d:
            in_film = d.group(1) == 'Film'
        if in_film:
            continue
        for m in ASSET_RE.finditer(line):
            ref = m.group(1)
            full = os.path.normpath(os.path.join(base, ref))
            (present if os.path.exists(full) else missing).append(full)
        inc = INCLUDE_RE.match(line)
        if inc:
            full = os.path.normpath(os.path.join(base, inc.group(2)))
            if os.path.exists(full) and full.endswith('.pbrt'):
                m2, p2 = referenced_files(full, seen, base)
                missing += m2
                present += p2
    return sorted(set(missing)), sorted(set(present))


def find_scenes(scenes_dir):
    """Every .pbrt file with a WorldBegin (scene files, not the files they include)."""
    out = []
    for d, _, files in os.walk(scenes_dir):
        for f in files:
            if f.endswith('.pbrt') and '.corpus-' not in f:
                p = os.path.join(d, f)
                with open(p, errors='replace') as fh:
                    if any(strip_comment(l).strip().startswith('WorldBegin') for l in fh):
                        out.append(p)
    return sorted(out)


def mirror_tree(src, dst):
    """dst mirrors src with symbolic links to its files (real directories, so we can add files)."""
    for d, dirs, files in os.walk(src):
        rel = os.path.relpath(d, src)
        os.makedirs(os.path.join(dst, rel), exist_ok=True)
        for f in files:
            link = os.path.join(dst, rel, f)
            if not os.path.lexists(link):
                os.symlink(os.path.join(d, f), link)


# Stand-ins for files the collection leaves out (its MANIFEST's suggestion): both renderers
# get the same one, which changes what the image shows, not whether they agree. Files of
# kinds with no cheap stand-in (measured .bsdf, .nvdb grids) leave the scene "assets missing".
STANDIN_PLY = ('ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n'
               'property float z\nelement face 1\nproperty list uchar int vertex_indices\n'
               'end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n')


def png_grey(path, v=128, n=4):
    """An n x n grey 8-bit PNG (written with zlib: no image library needed)."""
    import struct
    import zlib
    def chunk(t, d):
        return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    raw = b''.join(b'\x00' + bytes([v, v, v]) * n for _ in range(n))
    data = (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', n, n, 8, 2, 0, 0, 0)) +
            chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
    with open(path, 'wb') as f:
        f.write(data)


def exr_grey(args, cache):
    """A 16 x 16 EXR of constant 0.5 (square: pbrt-v4's equal-area environment maps are),
    rendered once by pbrt-v4 itself from an environment-only scene. None if that fails."""
    path = os.path.join(cache, 'standin-grey.exr')
    if os.path.exists(path):
        return path
    scene = os.path.join(cache, 'standin-grey.pbrt')
    with open(scene, 'w') as f:
        f.write('Film "rgb" "integer xresolution" [ 16 ] "integer yresolution" [ 16 ]\n'
                'Sampler "independent" "integer pixelsamples" [ 1 ]\n'
                'Camera "orthographic"\nWorldBegin\nLightSource "infinite" "rgb L" [ 0.5 0.5 0.5 ]\n')
    subprocess.call([args.pbrt, '--quiet', '--nthreads', '1', scene, '--outfile', path],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return path if os.path.exists(path) else None


def make_standins(args, missing, scene_dir, mirror_dir):
    """Creates stand-ins in the mirror for the missing files it can; returns (stood in,
    still missing) as paths relative to the scene's folder."""
    done, left = [], []
    for m in missing:
        rel = os.path.relpath(m, scene_dir)
        dst = os.path.join(mirror_dir, rel)
        low = rel.lower()
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        if os.path.exists(dst):
            done.append(rel)
        elif low.endswith('.ply'):
            with open(dst, 'w') as f:
                f.write(STANDIN_PLY)
            done.append(rel)
        elif low.endswith('.ply.gz'):
            with gzip.open(dst, 'wt') as f:
                f.write(STANDIN_PLY)
            done.append(rel)
        elif low.endswith('.pbrt'):
            open(dst, 'w').close()
            done.append(rel)
        elif low.endswith('.pbrt.gz'):
            with gzip.open(dst, 'wt') as f:
                f.write('\n')
            done.append(rel)
        elif low.endswith('.png'):
            png_grey(dst)
            done.append(rel)
        elif low.endswith('.exr') and exr_grey(args, args.cache):
            shutil.copyfile(exr_grey(args, args.cache), dst)
            done.append(rel)
        else:
            left.append(rel)
    return done, left


def film_resolution(lines):
    """(x, y) of the Film statement (pbrt's defaults 1280 x 720 where it sets none), and
    whether there is one. The statement runs from "Film" to the next line that starts with
    a directive (a capitalised word)."""
    body, inside, found = [], False, False
    for line in lines:
        code = strip_comment(line).strip()
        if re.match(r'[A-Z][A-Za-z]*\b', code):
            inside = code.startswith('Film')
            found = found or inside
        if inside:
            body.append(code)
    body = ' '.join(body)
    def val(name, dflt):
        mm = re.search(r'"integer\s+%s"\s*\[?\s*(\d+)' % name, body)
        return int(mm.group(1)) if mm else dflt
    return val('xresolution', 1280), val('yresolution', 720), found


def small_copy(scene, mirror_scene, size):
    """Writes <scene>.corpus-<size>.pbrt beside the mirrored scene: the same file with the
    Film's resolution scaled so the longer side is `size` (aspect kept). Returns its path
    and the (width, height)."""
    with open(scene, errors='replace') as f:
        lines = f.read().split('\n')
    xr, yr, has_film = film_resolution(lines)
    s = size / max(xr, yr)
    w, h = max(1, round(xr * s)), max(1, round(yr * s))
    out = []
    for line in lines:
        code, comment = line, ''
        i = line.find('#')
        if i >= 0:
            code, comment = line[:i], line[i:]
        code = re.sub(r'("integer\s+xresolution"\s*\[?\s*)\d+', r'\g<1>%d' % w, code)
        code = re.sub(r'("integer\s+yresolution"\s*\[?\s*)\d+', r'\g<1>%d' % h, code)
        out.append(code + comment)
    text = '\n'.join(out)
    if not has_film:  # no Film statement: pbrt's default film at the small size
        text = re.sub(r'^(\s*WorldBegin)', 'Film "rgb" "integer xresolution" [ %d ] '
                      '"integer yresolution" [ %d ]\n\\1' % (w, h), text, count=1, flags=re.M)
    else:
        # a Film without xresolution/yresolution takes pbrt's 1280 x 720: add them
        for name, v in (('xresolution', w), ('yresolution', h)):
            if not re.search(r'"integer\s+%s"' % name, '\n'.join(strip_comment(l) for l in out)):
                text = re.sub(r'^(\s*Film\s+"[^"]*")', r'\1 "integer %s" [ %d ]' % (name, v), text,
                              count=1, flags=re.M)
    base = os.path.splitext(mirror_scene)[0]
    path = '%s.corpus-%d.pbrt' % (base, size)
    with open(path, 'w') as f:
        f.write(text)
    return path, w, h


def run_timed(cmd, cwd, timeout, log_path):
    """Runs cmd under /usr/bin/time -v and timeout; returns (rc, wall seconds, peak RSS MiB)."""
    tv = log_path + '.time'
    full = ['timeout', '--kill-after=10', str(timeout)]
    if shutil.which('/usr/bin/time'):
        full = ['/usr/bin/time', '-v', '-o', tv] + full
    t0 = time.monotonic()
    with open(log_path, 'w') as log:
        rc = subprocess.call(full + cmd, cwd=cwd, stdout=log, stderr=subprocess.STDOUT,
                             stdin=subprocess.DEVNULL)
    secs = time.monotonic() - t0
    peak = None
    try:
        with open(tv) as f:
            for line in f:
                if 'Maximum resident set size' in line:
                    peak = int(line.split(':')[1]) / 1024.0
    except OSError:
        pass
    return rc, secs, peak


def warning_kinds(log_text):
    """Counts of caustic's warnings by kind: the message after its file:line:col, up to the
    first ':', ';' or '(' (e.g. 'Shape "loopsubdiv"', 'material "coateddiffuse" approximated
    by caustic's plastic'), or up to 'is not supported' for an ignored parameter; the names
    a scene gives (materials, textures, media) become "…". caustic's own "N more warnings
    not shown" adds N to a kind of that name."""
    kinds = {}
    for line in log_text.splitlines():
        if not line.startswith('caustic: warning:'):
            continue
        msg = line[len('caustic: warning:'):].strip()
        more = re.match(r'(\d+) more warnings? not shown', msg)
        if more:
            kinds['(not shown)'] = kinds.get('(not shown)', 0) + int(more.group(1))
            continue
        msg = re.sub(r'^[^\s:]+:\d+:\d+:\s*', '', msg)
        param = re.match(r'(.*?): (parameter "[^"]*" is not supported)', msg)
        kind = param.group(1) + ': ' + param.group(2) if param else re.split(r'[:;(]', msg, maxsplit=1)[0]
        kind = re.sub(r'^((?:MakeNamedMaterial|MakeNamedMedium|NamedMaterial|Texture|ObjectBegin|ObjectInstance)\s+)'
                      r'"[^"]*"?', '\\1"…"', kind.strip())[:80]
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


def last_error(log_text):
    for line in reversed(log_text.splitlines()):
        if 'error' in line.lower():
            line = re.sub(r'\x1b\[[0-9;]*m', '', line).strip()
            return re.sub(r'^caustic: error: ', '', line)
    lines = [l for l in log_text.splitlines() if l.strip()]
    return lines[-1].strip() if lines else ''


def render_caustic(args, small, out_exr, rec_path, cwd):
    if os.path.exists(rec_path):
        with open(rec_path) as f:
            rec = json.load(f)
        try:  # the kinds as this version of the script sorts them
            with open(rec_path + '.log', errors='replace') as f:
                rec['warnings'] = warning_kinds(f.read())
        except OSError:
            pass
        return rec
    log = rec_path + '.log'
    summary = rec_path + '.summary.json'
    cmd = [args.caustic, 'render', small, '--spp', str(args.spp), '--threads', str(args.threads),
           '-o', out_exr, '--json=' + summary]
    rc, secs, peak = run_timed(cmd, cwd, args.timeout, log)
    with open(log, errors='replace') as f:
        text = f.read()
    rec = {'rc': rc, 'wall': secs, 'peak_mib': peak, 'warnings': warning_kinds(text)}
    if rc == 124 or rc == 137:
        rec['status'] = 'timeout (%d s)' % args.timeout
    elif rc != 0:
        rec['status'] = 'failed'
        rec['error'] = last_error(text)
    else:
        rec['status'] = 'ok'
        try:
            with open(summary) as f:
                s = json.load(f)
            rec['load'] = s['seconds']['load']
            rec['accel'] = s['seconds']['accel']
            rec['render'] = s['seconds']['render']
        except (OSError, ValueError, KeyError):
            pass
    with open(rec_path, 'w') as f:
        json.dump(rec, f)
    return rec


def render_pbrt(args, small, out_exr, rec_path, cwd):
    if os.path.exists(rec_path):
        with open(rec_path) as f:
            return json.load(f)
    log = rec_path + '.log'
    cmd = [args.pbrt, '--nthreads', str(args.threads), '--spp', str(args.spp), '--quiet', small,
           '--outfile', out_exr]
    rc, secs, peak = run_timed(cmd, cwd, args.timeout, log)
    with open(log, errors='replace') as f:
        text = f.read()
    rec = {'rc': rc, 'wall': secs, 'peak_mib': peak}
    if rc == 124 or rc == 137:
        rec['status'] = 'timeout (%d s)' % args.timeout
    elif rc != 0 or not os.path.exists(out_exr):
        rec['status'] = 'failed'
        rec['error'] = last_error(text)
    else:
        rec['status'] = 'ok'
    with open(rec_path, 'w') as f:
        json.dump(rec, f)
    return rec


def compare(args, a, b, cwd):
    """caustic compare A B --json: caustic's render against pbrt-v4's."""
    p = subprocess.run([args.caustic, 'compare', a, b, '--json'], cwd=cwd, capture_output=True,
                       text=True, timeout=600)
    if p.returncode != 0:
        return {'error': (p.stderr.strip().splitlines() or ['exit %d' % p.returncode])[-1]}
    try:
        return json.loads(p.stdout)
    except ValueError:
        return {'error': 'unreadable compare output'}


def fmt(v, spec='%.3g'):
    return '–' if v is None else spec % v


TREE_PREFIX = ''  # the mirror's path, cut from messages so that they name the scene's own files


def esc(s):
    if TREE_PREFIX:
        s = s.replace(TREE_PREFIX, '')
    return s.replace('|', '\\|').replace('\n', ' ')


def row(scene_rel, r):
    c, p, cmp_ = r.get('caustic') or {}, r.get('pbrt') or {}, r.get('compare') or {}
    def some(xs):
        return '%d (%s%s)' % (len(xs), ', '.join(os.path.basename(x) for x in xs[:2]), ', …' if len(xs) > 2 else '')
    assets = []
    if r.get('standins'):
        assets.append('stand-ins ' + some(r['standins']))
    if r.get('missing'):
        assets.append('missing ' + some(r['missing']))
    assets = '; '.join(assets) or 'ok'
    if c.get('status') == 'ok':
        load = 'ok'
    elif c:
        load = '%s: %s' % (c.get('status'), c.get('error', ''))
    else:
        load = '–'
    warn = c.get('warnings') or {}
    nwarn = sum(warn.values())
    top = sorted(warn.items(), key=lambda kv: (-kv[1], kv[0]))
    kinds = '; '.join('%s ×%d' % (k, n) for k, n in top[:8])
    if len(top) > 8:
        kinds += '; %d more kinds' % (len(top) - 8)
    wcell = '%d%s' % (nwarn, (': ' + kinds) if kinds else '') if c else '–'
    pcell = 'ok %.1f s, %s MiB' % (p['wall'], fmt(p.get('peak_mib'), '%.0f')) if p.get('status') == 'ok' else (
        '%s: %s' % (p.get('status'), p.get('error', '')) if p else r.get('pbrt_skipped', '–'))
    if 'error' in cmp_:
        means = reldiff = relmse = flip = esc(cmp_['error'])[:80]
    elif cmp_:
        ch = cmp_.get('channels', [])
        means = ' / '.join('%s vs %s' % (fmt(x.get('mean_a')), fmt(x.get('mean_b'))) for x in ch)
        reldiff = ' / '.join(fmt(x.get('rel_diff'), '%+.3f') for x in ch)
        relmse = fmt(cmp_.get('relmse'))
        fl = cmp_.get('flip') or {}
        flip = '%s (%s)' % (fmt(fl.get('mean'), '%.3f'), fl.get('kind', '?'))
    else:
        means = reldiff = relmse = flip = '–'
    cells = [scene_rel, assets, load, wcell, fmt(c.get('load'), '%.2f'), fmt(c.get('peak_mib'), '%.0f'),
             fmt(c.get('render'), '%.2f'), pcell, means, reldiff, relmse, flip]
    return '| ' + ' | '.join(esc(str(x)) for x in cells) + ' |'


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    shared = os.path.join(ROOT, '..', 'shared')
    if not os.path.isdir(shared):
        shared = '/work/shared'
    ap.add_argument('--caustic', default=os.path.join(ROOT, 'build', 'caustic'))
    ap.add_argument('--pbrt', default=os.path.join(shared, 'tools', 'pbrt-v4', 'pbrt'))
    ap.add_argument('--scenes', default=os.path.join(shared, 'scenes', 'pbrt-v4'))
    ap.add_argument('--cache', default='/work/corpus-ref', help='outside the repository (default %(default)s)')
    ap.add_argument('--spp', type=int, default=16)
    ap.add_argument('--size', type=int, default=128, help='longer image side in pixels (default %(default)s)')
    ap.add_argument('--timeout', type=int, default=300, help='seconds per render (default %(default)s)')
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--only', default='', help='regular expression on the scene path')
    ap.add_argument('--no-standins', action='store_true', help='no stand-ins for missing files')
    ap.add_argument('--cache-key', default='', help="reuse caustic's renders cached under this key")
    ap.add_argument('--fresh', action='store_true', help="re-render caustic's images of this binary")
    ap.add_argument('--doc', default='', help='replace the table between the corpus markers of this Markdown file')
    args = ap.parse_args()

    if not os.path.isdir(args.scenes):
        print('pbrt-corpus: skipped: no scene collection at %s' % args.scenes, file=sys.stderr)
        return 0
    for tool in (args.caustic, args.pbrt):
        if not os.access(tool, os.X_OK):
            print('pbrt-corpus: %s is not an executable' % tool, file=sys.stderr)
            return 2
    args.caustic = os.path.abspath(args.caustic)
    with open(args.caustic, 'rb') as f:
        bin_sha = hashlib.sha256(f.read()).hexdigest()[:12]
    # caustic's renders are cached per binary; --cache-key reuses another binary's renders
    # (e.g. after a change that cannot alter images), and the table says whose they are.
    bin_sha = args.cache_key or bin_sha
    tree = os.path.join(args.cache, 'tree')
    pdir = os.path.join(args.cache, 'pbrt-%d-%dspp' % (args.size, args.spp))
    cdir = os.path.join(args.cache, 'caustic-%s-%d-%dspp' % (bin_sha, args.size, args.spp))
    if args.fresh and os.path.isdir(cdir):
        shutil.rmtree(cdir)
    for d in (tree, pdir, cdir):
        os.makedirs(d, exist_ok=True)
    global TREE_PREFIX
    TREE_PREFIX = tree + '/'

    scenes = [s for s in find_scenes(args.scenes) if re.search(args.only, os.path.relpath(s, args.scenes))]
    rows = []
    for scene in scenes:
        rel = os.path.relpath(scene, args.scenes)
        key = rel.replace('/', '__').replace('.pbrt', '')
        top = rel.split('/')[0]
        mirror_tree(os.path.join(args.scenes, top), os.path.join(tree, top))
        small, w, h = small_copy(scene, os.path.join(tree, rel), args.size)
        missing, _ = referenced_files(scene)
        r = {}
        if missing and not args.no_standins:
            r['standins'], missing = make_standins(args, missing, os.path.join(args.scenes, top),
                                                   os.path.join(tree, top))
        r['missing'] = [os.path.relpath(m, os.path.join(args.scenes, top)) if os.path.isabs(m) else m
                        for m in missing]
        print('pbrt-corpus: %s (%dx%d)%s' % (rel, w, h, ' assets missing' if missing else ''),
              file=sys.stderr, flush=True)
        cwd = os.path.dirname(small)
        c_exr = os.path.join(cdir, key + '.exr')
        r['caustic'] = render_caustic(args, small, c_exr, os.path.join(cdir, key + '.json'), cwd)
        if missing:
            r['pbrt_skipped'] = 'not run: assets missing'
        else:
            p_exr = os.path.join(pdir, key + '.exr')
            r['pbrt'] = render_pbrt(args, small, p_exr, os.path.join(pdir, key + '.json'), cwd)
            if r['caustic'].get('status') == 'ok' and r['pbrt'].get('status') == 'ok':
                r['compare'] = compare(args, c_exr, p_exr, cwd)
        rows.append((rel, r))

    commit = subprocess.run(['git', '-C', ROOT, 'rev-parse', '--short=12', 'HEAD'], capture_output=True,
                            text=True).stdout.strip() or '?'
    cpu = '?'
    try:
        with open('/proc/cpuinfo') as f:
            cpu = next(l.split(':', 1)[1].strip() for l in f if l.startswith('model name'))
    except (OSError, StopIteration):
        pass
    head = [
        '<!-- corpus-table: generated by scripts/pbrt-corpus.sh; do not edit by hand -->',
        '',
        'Command: `scripts/pbrt-corpus.sh --size %d --spp %d --timeout %d --threads %d%s`  ' % (
            args.size, args.spp, args.timeout, args.threads, ' --only %s' % args.only if args.only else ''),
        'Date: %s; machine: %s, %d cores (%s); caustic commit %s (renders by the binary of sha256 %s…); pbrt-v4 %s.' % (
            datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC'), cpu, os.cpu_count() or 0,
            platform.platform(), commit, bin_sha, args.pbrt),
        '',
        'Columns: assets (files the scene names that are not in the collection, see its MANIFEST: '
        'stand-ins where cheap, the same for both renderers: a one-triangle PLY, a grey PNG or '
        'EXR, an empty included .pbrt; "missing" where none, and pbrt-v4 is then not run); '
        "caustic's load result; its warnings (count, then by kind); its load and render seconds "
        '(`--json` summary) and peak resident memory (`/usr/bin/time -v`, MiB); pbrt-v4 (wall '
        'seconds and peak memory); `caustic compare caustic.exr pbrt.exr`: the mean per channel (R / G / B, caustic '
        'vs pbrt), the relative difference of the means, relMSE and mean FLIP (HDR-FLIP for these '
        'EXR images). Both render the same small copy of the scene (longer side %d px) at %d spp, '
        'each under a %d s limit.' % (args.size, args.spp, args.timeout),
        '',
        '| scene | assets | caustic load | warnings | load s | peak MiB | render s | pbrt-v4 | means R / G / B | rel. diff | relMSE | FLIP |',
        '|---|---|---|---|---|---|---|---|---|---|---|---|',
    ]
    table = '\n'.join(head + [row(rel, r) for rel, r in rows]) + '\n\n<!-- corpus-table end -->'
    if args.doc:
        with open(args.doc) as f:
            doc = f.read()
        m = re.search(r'<!-- corpus-table: .*?<!-- corpus-table end -->', doc, re.S)
        if not m:
            print('pbrt-corpus: %s has no corpus-table markers' % args.doc, file=sys.stderr)
            return 2
        tmp = args.doc + '.tmp'
        with open(tmp, 'w') as f:
            f.write(doc[:m.start()] + table + doc[m.end():])
        os.replace(tmp, args.doc)
    else:
        print(table)
    return 0


if __name__ == '__main__':
    sys.exit(main())
