#!/usr/bin/env bash
# Installs the built tree into a temporary prefix and imports the Python module from there, with
# nothing of the build tree on the path: the module must be self-contained (the library is linked
# statically) and its .pyi stub must sit beside it.
set -euo pipefail
build_dir=$1
python_dir=$2
python=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
site="$work/prefix/$python_dir"
test -f "$site/errfield.pyi" || { echo "no errfield.pyi in $site"; exit 1; }
cd "$work"
PYTHONPATH="$site" "$python" - "$site" <<'PY'
import os, sys
import numpy as np
import errfield
site = sys.argv[1]
assert os.path.realpath(errfield.__file__).startswith(os.path.realpath(site)), errfield.__file__
v = errfield.variogram(np.array([[0.0], [1.0], [3.0]]), np.array([0.0, 1.0, 3.0]), [0.0, 1.5, 2.5, 3.5])
# pairs at lags 1, 2, 3: gamma = d^2 / 2
assert list(v.pairs) == [1, 1, 1], v.pairs
assert np.array_equal(v.gamma, [0.5, 2.0, 4.5]), v.gamma
print("installed errfield", errfield.__version__, "at", errfield.__file__)
PY
