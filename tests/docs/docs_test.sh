#!/usr/bin/env bash
# The docs test (CTest "docs"): README.md and docs/*.md against the program. Every caustic
# command in their code blocks runs (at small sizes), every repository path they name
# exists, every JSON scene they show loads, and their Markdown has no unclosed code fence
# or split table. The rules, and the rare `# docs-test: not run (REASON)` marker, are in
# tests/docs/docs_check.py. Usage: docs_test.sh [CAUSTIC_BINARY] (default build/caustic).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
bin=${1:-$root/build/caustic}
[ -x "$bin" ] || { echo "docs test: no caustic binary at $bin" >&2; exit 1; }
exec python3 "$root/tests/docs/docs_check.py" "$root" "$bin"
