#!/usr/bin/env python3
"""The docs test: README.md and docs/*.md against the program. Checks

1. Markdown structure: every code fence is closed (an unclosed one swallows the rest of the
   page), and no table is split by a blank line (the rows after it render as text).
2. Paths: every repository path the text names (scenes/..., docs/..., src/..., tests/...,
   scripts/..., bench/..., examples/..., cli/..., include/..., cmake/..., .ci/...) exists,
   and every relative Markdown link [text](file#anchor) names a file and a heading there.
3. Commands: every command invoking caustic in a ```sh/```bash/```shell/```console block,
   and every `$ `-prompted one in any block, runs as written with bash, from a scratch
   directory that links the repository's top-level entries, with `caustic`, `build/caustic`
   and `./build/caustic` resolving to a wrapper around the binary under test. The wrapper
   caps the work of `render` and `verify` (--width/--height 64, --spp 4 or 8, --time 2:
   lowered if larger or absent, never raised; `bench rays` without --accel: bvh only), so
   every command takes seconds. Setup steps
   chained before the first caustic call with && (install, cmake) are not run: CI has done
   them. Each caustic call must exit 0 (verify: 0 or 1, its verdict at these sizes means
   nothing), or the status a `# docs-test: exit N` comment on the command states.
   A command (or, on a comment line of its own at the top of a block, the whole block)
   marked `# docs-test: not run (REASON)` is not run; the marker is for commands that need
   data outside the repository (../shared) or are minutes long by design, and REASON must
   say which.
4. JSON scenes: every ```json block that is a whole scene (an object with "camera" or
   "shapes") loads with `caustic info`.
5. Names: every option in `caustic --help` and `caustic render --help` appears in
   docs/cli.md, and every name `--integrator`, `--filter`, `--sampler` and `--accel` accept
   (the list the CLI prints for an unknown one) appears as `name` in that option's row of
   the options table of docs/cli.md; the integrator names in docs/scene-format.md too.

Usage: docs_check.py REPO_ROOT CAUSTIC_BINARY. Exit 0 when everything passes, 1 otherwise,
with one line per problem naming file:line.
"""
import json
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time

MARK_SKIP = re.compile(r"#\s*docs-test:\s*not run\s*\((.+)\)")
MARK_EXIT = re.compile(r"#\s*docs-test:\s*exit\s+(\d+)")
SHELL_LANGS = {"sh", "bash", "shell", "console"}
PATH_RE = re.compile(
    r"(?<![\w./~$-])((?:scenes|docs|src|tests|scripts|bench|examples|cli|include|cmake|\.ci)/[\w./+-]*)")
CAUSTIC_TOKEN = re.compile(r"^(?:\S*/)?caustic$")
CMD_TIMEOUT = 60  # seconds per command; each should take a few
SLOW = 30         # reported as a problem above this (a loaded 2-core machine)

WRAPPER = r"""#!/usr/bin/env bash
# docs test wrapper: caps the work of render and verify, logs each call's exit status.
args=("$@")
cmd="${args[0]:-}"
cap() { # cap OPTION MAX: lower the option's value to MAX, or append it
  local opt=$1 max=$2 i found=0
  for ((i = 1; i < ${#args[@]}; i++)); do
    case "${args[i]}" in
      "$opt") found=1
              if [[ ${args[i+1]:-} =~ ^[0-9.]+$ ]] && awk "BEGIN{exit !(${args[i+1]} > $max)}"; then args[i+1]=$max; fi ;;
      "$opt="*) found=1; v=${args[i]#*=}
              if [[ $v =~ ^[0-9.]+$ ]] && awk "BEGIN{exit !($v > $max)}"; then args[i]="$opt=$max"; fi ;;
    esac
  done
  [ $found = 1 ] || args+=("$opt" "$max")
}
has() { local a; for a in "${args[@]}"; do [[ $a == "$1" || $a == "$1="* ]] && return 0; done; return 1; }
if ! has --help && ! has -h; then
  case "$cmd" in
    render|verify)
      if ! has --crop; then cap --width 64; cap --height 64; fi
      if [ "$cmd" = render ]; then cap --spp 4; else cap --spp 8; fi
      has --time && cap --time 2 ;;
    bench) has --accel || args+=(--accel bvh) ;; # each back end times itself for ~6 s
  esac
fi
"$CST_DOCS_BIN" "${args[@]}"
rc=$?
printf '%s\t%s\n' "$rc" "$*" >> "$CST_DOCS_LOG"
exit $rc
"""


class Doc:
    def __init__(self, root, rel):
        self.rel = rel
        with open(os.path.join(root, rel), encoding="utf-8") as f:
            self.lines = f.read().split("\n")

    def blocks(self, problems):
        """(lang, first content line number, lines) of each fenced block; fence problems."""
        out, open_at, lang, body = [], None, "", []
        for n, line in enumerate(self.lines, 1):
            m = re.match(r"^ {0,3}(`{3,}|~{3,})\s*([^`\s]*)", line)
            if not m:
                if open_at is not None:
                    body.append(line)
                continue
            if open_at is None:
                open_at, lang, body = n, m.group(2).lower(), []
            elif m.group(2):
                problems.append(f"{self.rel}:{n}: a fence with an info string (```{m.group(2)}) "
                                f"inside the code block opened at line {open_at}: that block "
                                f"is not closed")
                out.append((lang, open_at + 1, body))
                open_at, lang, body = n, m.group(2).lower(), []
            else:
                out.append((lang, open_at + 1, body))
                open_at = None
        if open_at is not None:
            problems.append(f"{self.rel}:{open_at}: code block not closed before the end of the file")
            out.append((lang, open_at + 1, body))
        return out

    def split_tables(self, problems):
        in_code = False
        for i, line in enumerate(self.lines):
            if re.match(r"^ {0,3}(`{3,}|~{3,})", line):
                in_code = not in_code
            if in_code or line.strip():
                continue
            prev = self.lines[i - 1] if i > 0 else ""
            nxt = self.lines[i + 1] if i + 1 < len(self.lines) else ""
            after = self.lines[i + 2] if i + 2 < len(self.lines) else ""
            if (prev.startswith("|") and nxt.startswith("|")
                    and not re.match(r"^\|[\s:|-]+\|?\s*$", after)):
                problems.append(f"{self.rel}:{i + 1}: a blank line splits a table (the rows after "
                                f"it have no header and render as text)")


LINK_RE = re.compile(r"\]\(([^)\s]+)\)")


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    h = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return h.replace(" ", "-")


def anchors(root, rel):
    try:
        with open(os.path.join(root, rel), encoding="utf-8") as f:
            text = f.read()
    except OSError:
        return set()
    text = re.sub(r"(?ms)^ {0,3}```.*?^ {0,3}```", "", text)
    return {slug(m.group(1)) for m in re.finditer(r"(?m)^#{1,6}\s+(.*?)\s*#*\s*$", text)}


def check_links(root, rel, lines, problems):
    here = os.path.dirname(rel)
    for n, line in enumerate(lines, 1):
        for m in LINK_RE.finditer(line):
            target = m.group(1)
            if re.match(r"^[a-z]+:", target):
                continue  # http:, https:, mailto:
            path, _, anchor = target.partition("#")
            dest = os.path.normpath(os.path.join(here, path)) if path else rel
            if path and not os.path.exists(os.path.join(root, dest)):
                problems.append(f"{rel}:{n}: link to {target}: no such file")
            elif anchor and dest.endswith(".md") and anchor not in anchors(root, dest):
                problems.append(f"{rel}:{n}: link to {target}: no heading with that anchor in {dest}")


def commands(lang, first, body):
    """(line number, command text, block-level skip reason) of the commands of a block."""
    shell = lang in SHELL_LANGS
    block_skip = None
    if shell:
        for line in body:
            if line.strip():
                m = MARK_SKIP.search(line)
                if line.strip().startswith("#") and m:
                    block_skip = m.group(1)
                break
    out, i = [], 0
    while i < len(body):
        line, n = body[i], first + i
        i += 1
        s = line.strip()
        if shell and s.startswith("$ "):
            s = s[2:]
        elif not shell:
            if not s.startswith("$ "):
                continue
            s = s[2:]
        if not s or s.startswith("#"):
            continue
        # One command may span lines: a trailing backslash, or a compound command (for ...
        # do ... done, quotes, here-documents) that bash does not yet find complete.
        while i < len(body) and (s.endswith("\\") or not complete(s)):
            nxt = body[i].strip()
            if not shell and nxt.startswith("$ "):
                nxt = nxt[2:]
            s = s[:-1] + " " + nxt if s.endswith("\\") else s + "\n" + nxt
            i += 1
        out.append((n, s, block_skip))
    return out


def complete(cmd):
    return subprocess.run(["bash", "-n", "-c", cmd], capture_output=True).returncode == 0


def invokes_caustic(cmd):
    try:
        toks = shlex.split(cmd, comments=True)
    except ValueError:
        toks = cmd.split()
    return any(CAUSTIC_TOKEN.match(t) for t in toks)


def strip_setup(cmd):
    """Drops the && steps before the first caustic call (install, configure, build)."""
    parts = cmd.split("&&")
    for k, p in enumerate(parts):
        if invokes_caustic(p):
            return "&&".join(parts[k:]).strip()
    return cmd


def make_sandbox(root, binary):
    sand = tempfile.mkdtemp(prefix="cst-docs-")
    work = os.path.join(sand, "repo")
    os.makedirs(os.path.join(work, "build"))
    for e in os.listdir(root):
        if e in (".git", "docs") or e.startswith("build"):
            continue
        os.symlink(os.path.join(root, e), os.path.join(work, e))
    # docs/ is real so outputs written there (-o docs/x.png) stay in the sandbox.
    os.makedirs(os.path.join(work, "docs"))
    for e in os.listdir(os.path.join(root, "docs")):
        if not e.endswith(".png"):
            os.symlink(os.path.join(root, "docs", e), os.path.join(work, "docs", e))
    bindir = os.path.join(sand, "bin")
    os.makedirs(bindir)
    for p in (os.path.join(bindir, "caustic"), os.path.join(work, "build", "caustic")):
        with open(p, "w") as f:
            f.write(WRAPPER)
        os.chmod(p, 0o755)
    env = dict(os.environ, PATH=bindir + os.pathsep + os.environ.get("PATH", ""),
               CST_DOCS_BIN=os.path.abspath(binary), CST_DOCS_LOG=os.path.join(sand, "calls.log"))
    return sand, work, env


def run_command(where, cmd, expect, work, env, problems, timings):
    log = env["CST_DOCS_LOG"]
    open(log, "w").close()
    t0 = time.monotonic()
    # A session of its own, so a command still running at the timeout is ended with all
    # its children (the caustic under the wrapper under bash).
    p = subprocess.Popen(["bash", "-c", cmd], cwd=work, env=env, stdin=subprocess.DEVNULL,
                         stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                         start_new_session=True)
    try:
        out = p.communicate(timeout=CMD_TIMEOUT)[0].strip()
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        problems.append(f"{where}: still running after {CMD_TIMEOUT} s: {cmd}")
        return
    r = p
    dt = time.monotonic() - t0
    timings.append((dt, where))
    calls = [l.split("\t", 1) for l in open(log).read().splitlines()]
    tail = "\n      ".join(out.splitlines()[-6:])
    if not calls:
        problems.append(f"{where}: caustic was never called (exit {r.returncode}): {cmd}\n      {tail}")
        return
    for rc, args in calls:
        rc = int(rc)
        verb = args.split()[0] if args.split() else ""
        ok = {expect} if expect is not None else ({0, 1} if verb == "verify" else {0})
        if rc not in ok:
            problems.append(f"{where}: `caustic {args}` exited {rc} (expected "
                            f"{' or '.join(map(str, sorted(ok)))}): {cmd}\n      {tail}")
    if dt > SLOW:
        problems.append(f"{where}: took {dt:.1f} s even with small sizes (limit {SLOW} s): {cmd}")


def check_names(root, binary, problems):
    def text(rel):
        with open(os.path.join(root, rel), encoding="utf-8") as f:
            return f.read()
    cli_md, scene_md = text("docs/cli.md"), text("docs/scene-format.md")
    helps = ""
    for args in (["--help"], ["render", "--help"]):
        r = subprocess.run([binary] + args, capture_output=True, text=True, timeout=30)
        helps += r.stdout
    for opt in sorted(set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", helps))):
        if not re.search(r"(?<![\w-])" + re.escape(opt) + r"(?![\w-])", cli_md):
            problems.append(f"docs/cli.md: {opt} (in caustic --help) is not documented")
    for opt in ("integrator", "filter", "sampler", "accel"):
        r = subprocess.run([binary, "render", f"--{opt}", "no-such-name"], capture_output=True,
                           text=True, timeout=30)
        m = re.search(r"\(valid: ([^)]*)\)", r.stderr)
        if not m:
            print(f"docs test: note: no list of valid --{opt} names in: {r.stderr.strip()}")
            continue
        # In cli.md, the option's row of the options table when there is one.
        row = next((l for l in cli_md.splitlines() if l.startswith(f"| `--{opt} ")), cli_md)
        for name in (n.strip() for n in m.group(1).split(",")):
            docs = [("docs/cli.md", row)] + ([("docs/scene-format.md", scene_md)]
                                              if opt == "integrator" else [])
            for rel, t in docs:
                if f"`{name}`" not in t and f'`"{name}"`' not in t:
                    problems.append(f"{rel}: --{opt} {name} (accepted by caustic) is not documented")


def main():
    root, binary = os.path.abspath(sys.argv[1]), sys.argv[2]
    docs = ["README.md"] + sorted("docs/" + f for f in os.listdir(os.path.join(root, "docs"))
                                  if f.endswith(".md"))
    problems, skipped, timings = [], [], []
    check_names(root, binary, problems)
    sand, work, env = make_sandbox(root, binary)
    ran = 0
    try:
        for rel in docs:
            doc = Doc(root, rel)
            doc.split_tables(problems)
            check_links(root, rel, doc.lines, problems)
            in_code = False
            for n, line in enumerate(doc.lines, 1):
                for m in PATH_RE.finditer(line):
                    p = m.group(1).rstrip(".")
                    if not os.path.exists(os.path.join(root, p)):
                        problems.append(f"{rel}:{n}: {p}: no such file or directory in the repository")
            for bi, (lang, first, body) in enumerate(doc.blocks(problems)):
                if lang == "json":
                    try:
                        obj = json.loads("\n".join(body))
                    except ValueError:
                        obj = None  # a fragment of a scene, not a scene
                    if isinstance(obj, dict) and ("camera" in obj or "shapes" in obj):
                        path = os.path.join(work, f"docs-block-{rel.replace('/', '-')}-{first}.json")
                        with open(path, "w") as f:
                            f.write("\n".join(body))
                        run_command(f"{rel}:{first}", f"caustic info {shlex.quote(path)}", None,
                                    work, env, problems, timings)
                        ran += 1
                for n, cmd, block_skip in commands(lang, first, body):
                    if not invokes_caustic(cmd):
                        continue
                    m = MARK_SKIP.search(cmd)
                    reason = m.group(1) if m else block_skip
                    if reason:
                        skipped.append(f"{rel}:{n}: not run ({reason}): {cmd}")
                        continue
                    m = MARK_EXIT.search(cmd)
                    run_command(f"{rel}:{n}", strip_setup(cmd), int(m.group(1)) if m else None,
                                work, env, problems, timings)
                    ran += 1
    finally:
        shutil.rmtree(sand, ignore_errors=True)
    for s in skipped:
        print(s.replace("\n", "; "))
    total = sum(t for t, _ in timings)
    print(f"docs test: {ran} commands and scenes run in {total:.1f} s, {len(skipped)} marked not run")
    if timings:
        t, w = max(timings)
        print(f"docs test: slowest {t:.1f} s at {w}")
    for p in problems:
        print("FAIL " + p)
    print(f"docs test: {len(problems)} problem(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
