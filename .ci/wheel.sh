#!/usr/bin/env bash
# README's car install, tested: the wheel built from this checkout, installed alone in a fresh environment (no extras,
# no editable install, nothing from the checkout on the path), then `fearguard demo` and a replay of a real video.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
env=.venv-wheel
rm -rf "$env" build/wheel-car
python3 -m venv "$env"
"$env/bin/python" -m pip install -q --upgrade pip
"$env/bin/python" -m pip wheel -q --no-deps . -w build/wheel-car
"$env/bin/python" -m pip install -q build/wheel-car/fearguard-*.whl
cd build  # away from src/: fearguard must come from the environment's site-packages
"../$env/bin/python" -c "import fearguard; assert 'site-packages' in fearguard.__file__, fearguard.__file__; print('fearguard from', fearguard.__file__)"
"../$env/bin/fearguard" demo | tail -3
if [ -f ../../shared/data/road/video/solidWhiteRight.mp4 ]; then
  "../$env/bin/fearguard" replay ../../shared/data/road/video/solidWhiteRight.mp4 --to 20f --no-plots --out wheel-replay | tail -2
fi
echo "wheel.sh: $((SECONDS - start)) s"
