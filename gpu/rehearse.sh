#!/usr/bin/env bash
# The GPU bundle end to end on this machine, as a device machine would take it (docs/guide/gpu.md):
# a copy of the working tree without .git, a fresh Python 3.12 with only the packages the device
# image has (numpy, scipy, pytest, pytest-xdist, rich, Pillow), the parts installed one call at a
# time into a stash, the packages imported, and the check run from them on the CPU at toy sizes.
set -euo pipefail
cd "$(dirname "$0")/.."
# the device's Python: $PY312, python3.12 on the PATH, or one that pyenv installed
for c in ${PY312:-} python3.12 $(ls -d "$(pyenv root 2>/dev/null || echo /nonexistent)"/versions/3.12*/bin/python3.12 2>/dev/null); do
  if "$c" -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null; then PY312=$c; break; fi
  PY312=
done
[ -n "${PY312:-}" ] || { echo "error: gpu-rehearse needs Python 3.12 (the device's): set PY312" >&2; exit 2; }
R=${REHEARSE_DIR:-/tmp/restir-rehearse}
rm -rf "$R" && mkdir -p "$R/tree"
git ls-files -z --cached --others --exclude-standard | xargs -0 cp --parents -t "$R/tree"
cp -r .gpu-bundle/part* "$R/tree/"
"$PY312" -m venv "$R/venv"
"$R/venv/bin/pip" install -q numpy scipy pytest pytest-xdist rich pillow
cd "$R/tree"
parts=$(ls -d part* | sort -V)
last=$(echo "$parts" | tail -1)
for p in $parts; do
  mkdir -p .gpu-bundle && mv "$p" .gpu-bundle/
  "$R/venv/bin/python" gpu/install.py ".gpu-bundle/$p" --stash "$R/stash"
  [ "$p" = "$last" ] || rm -rf ".gpu-bundle/$p"   # a later call carries only its own part
done
export PYTHONPATH="$R/stash/site"
"$R/venv/bin/python" -c "import warp, pyoidn, OpenEXR, flip_evaluator, plyfile; warp.init(); print('imported: warp', warp.__version__)"
"$R/venv/bin/python" gpu/check.py --device cpu --quick --out "$R/out" --scenes "$R/stash/scenes" \
  --cpu-runs "$R/stash/cpu_runs.npz"
echo "rehearsal passed: $R/out/gpu_check.md"
