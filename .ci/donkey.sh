#!/usr/bin/env bash
# Donkey Car integration in a real donkeycar Vehicle loop (docs/donkey.md). donkeycar 5.3.0 needs Python 3.11
# and numpy < 2, so it gets its own environment, with fearguard installed from the wheel built from this
# checkout (not an editable install): this is also CI's Python 3.11 + numpy 1.26 check of the project.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
env=.venv-donkey
rm -rf "$env" build/wheel
python3.11 -m venv "$env"
"$env/bin/python" -m pip install -q --upgrade pip
"$env/bin/python" -m pip wheel -q --no-deps . -w build/wheel
# docs/donkey.md's install command, exactly as written there, run in the folder holding the wheel with this
# environment's pip first on PATH (the doc's block follows its "snippet: skip — .ci/donkey.sh runs this block" marker)
doc_install=$(awk '/snippet: skip — .ci\/donkey.sh runs this block/ {found=1; next} found && /^```bash/ {inside=1; next} inside && /^```/ {exit} inside {print}' docs/donkey.md)
[ -n "$doc_install" ] || { echo "donkey.sh: no install block in docs/donkey.md"; exit 1; }
echo "docs/donkey.md: $doc_install"
(cd build/wheel && PATH="$PWD/../../$env/bin:$PATH" bash -euo pipefail -c "$doc_install")
"$env/bin/python" -m pip install -q "pytest>=8" "hypothesis>=6.100"
"$env/bin/python" - <<'PY'
import sys, numpy, fearguard, donkeycar
assert sys.version_info[:2] == (3, 11), sys.version
assert numpy.__version__.startswith("1.26"), numpy.__version__
assert "site-packages" in fearguard.__file__, f"fearguard imported from the checkout: {fearguard.__file__}"
print(f"python {sys.version.split()[0]}, numpy {numpy.__version__}, donkeycar {donkeycar.__version__}, fearguard from {fearguard.__file__}")
PY
# the Donkey loop, then a subset of the project's own tests against the installed wheel
"$env/bin/python" -m pytest -p no:cacheprovider -o addopts="" -q -s tests/integrations/test_donkey_loop.py
"$env/bin/python" -m pytest -p no:cacheprovider -o addopts="" -q tests -k "test_api or test_engine or test_supervisor or donkey_part"
# donkeycar's OpenCV is 4.x (the main environment has 5.x): the overlay's text boxes hold on both (issue 15)
"$env/bin/python" -c "import cv2; print('overlay tests on OpenCV', cv2.__version__)"
"$env/bin/python" -m pytest -p no:cacheprovider -o addopts="" -q tests/test_overlay.py
echo "donkey.sh: $((SECONDS - start)) s"
