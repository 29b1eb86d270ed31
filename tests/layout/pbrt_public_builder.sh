#!/usr/bin/env bash
# The pbrt loader builds its scene through the public builder alone (issue 24): nothing in
# src/scene/pbrt includes scene/scene.h, reaches into a Scene (ld->scene->field) or calls
# an internal scene_add_* / scene_set_* function. Prints each break; run by CTest:
#   bash pbrt_public_builder.sh <source-dir>
set -euo pipefail
src=${1:?usage: pbrt_public_builder.sh SOURCE_DIR}
dir=$src/src/scene/pbrt
fail=0
while IFS= read -r hit; do
  echo "FAIL: $hit"; fail=1
done < <(grep -nE '#include "scene/scene\.h"|scene->[a-z_]+|(^|[^_a-z])scene_(add|set|commit)[a-z_]*\(' \
           "$dir"/*.c "$dir"/*.h || true)
[ $fail -eq 0 ] && echo "PASS: src/scene/pbrt builds scenes through the cst_scene_* calls only"
exit $fail
