#!/usr/bin/env bash
# gymnasium shield on the real highway-env (src/fearguard/integrations/gym.py): its own environment (pygame-ce,
# gymnasium, pandas stay off the car's), fearguard installed from the wheel built from this checkout.
set -euo pipefail
cd "$(dirname "$0")/.."
start=$SECONDS
env=.venv-highway
rm -rf "$env" build/wheel-highway
python3 -m venv "$env"
"$env/bin/python" -m pip install -q --upgrade pip
"$env/bin/python" -m pip wheel -q --no-deps . -w build/wheel-highway
"$env/bin/python" -m pip install -q "highway-env==1.12.1" "gymnasium==1.4.0" build/wheel-highway/fearguard-*.whl "pytest>=8" "hypothesis>=6.100"
"$env/bin/python" -m pytest -p no:cacheprovider -o addopts="" -q -s tests/integrations/test_gym_shield.py
"$env/bin/python" -m pytest -p no:cacheprovider -o addopts="" -q tests/test_doc_snippets.py -k highway_env  # README's and docs/gym.md's blocks
echo "highway.sh: $((SECONDS - start)) s"
