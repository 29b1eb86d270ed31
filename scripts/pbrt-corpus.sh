#!/usr/bin/env bash
# The pbrt-v4 scene-corpus check: every scene of ../shared/scenes/pbrt-v4 rendered small by
# caustic and by pbrt-v4, compared with `caustic compare`, one Markdown row per scene. Not
# part of CI (minutes to hours). The work is in pbrt-corpus.py; see --help. Typical:
#   scripts/pbrt-corpus.sh --doc docs/pbrt-compat.md     # regenerate the table in place
exec python3 "$(dirname "$0")/pbrt-corpus.py" "$@"
