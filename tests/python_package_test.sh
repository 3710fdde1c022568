#!/usr/bin/env bash
# The Python package as users install it (ctest python_package; docs/python.md#installing):
#   1. pip install --no-build-isolation . into a fresh venv that sees Debian's numpy, setuptools and
#      wheel, offline (--no-index); ATMO_BUILD_DIR points setup.py at this build, so the module is
#      not compiled again. Then it imports from another folder and renders.
#   2. cmake --install --component python into an empty prefix: the package lands in
#      PREFIX/ATMO_PYTHON_INSTALL_DIR and imports from there.
# Both check the typing files and that dir(atmo) shows the public names only.
#   python_package_test.sh SOURCE_DIR BINARY_DIR WORK PYTHON PYTHON_INSTALL_DIR
set -euo pipefail
source_dir=$1 binary_dir=$2 work=$3 python=$4 install_dir=$5
rm -rf "$work"
mkdir -p "$work/elsewhere"

check='
import os, sys, atmo
expected = sys.argv[1]
assert os.path.realpath(atmo.__file__).startswith(os.path.realpath(expected)), (atmo.__file__, expected)
folder = os.path.dirname(atmo.__file__)
for name in ("py.typed", "_atmo.pyi"):
    assert os.path.exists(os.path.join(folder, name)), name
assert not {"np", "os", "json", "dataclass"} & set(dir(atmo)), dir(atmo)
assert set(atmo.__all__) <= set(dir(atmo))
image = atmo.Model("hillaire").render(16, 8, target="blender")
assert image.shape == (8, 16, 3) and image.min() >= 0.0 and image.max() > 0.0
print("atmo", atmo.__version__, "from", folder)
'

# 1. pip
"$python" -m venv --system-site-packages "$work/venv"
ATMO_BUILD_DIR="$binary_dir" "$work/venv/bin/pip" install --no-build-isolation --no-index --no-deps \
  --disable-pip-version-check --quiet "$source_dir"
(cd "$work/elsewhere" && "$work/venv/bin/python" -c "$check" "$work/venv")

# 2. cmake --install
cmake --install "$binary_dir" --component python --prefix "$work/prefix" >/dev/null
(cd "$work/elsewhere" && PYTHONPATH="$work/prefix/$install_dir" "$python" -c "$check" "$work/prefix")
