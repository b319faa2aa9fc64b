#!/usr/bin/env bash
# The Duckietown simulator's environment in one command: gym-duckietown (daffy) + fearguard, headless.
#
#   bash .ci/duckietown.sh [VENV]        (default: $DUCKIETOWN_VENV or .venv-duckietown in the repository)
#
# - Mesa's EGL and GLU (Debian packages) so pyglet renders without an X server.
# - duckietown-gym-daffy 6.1.34 + duckietown-world-daffy 6.4.3, pyglet 1.5.27 (the simulator uses
#   pyglet 1.x's GL API), networkx<3 and opencv-python as duckietown-world pins them; every other
#   version pinned by .ci/duckietown-constraints.txt (a freeze of a working environment).
# - fearguard itself with --no-deps: its own dependencies are listed here, and it accepts the
#   simulator's opencv-python instead of opencv-python-headless (both provide cv2).
# About 5 minutes on 2 cores the first time (a dozen small source packages are built); seconds after.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${1:-${DUCKIETOWN_VENV:-.venv-duckietown}}"
APT_PACKAGES="libegl1 libegl-mesa0 libgl1-mesa-dri libglu1-mesa"
if ! dpkg -s $APT_PACKAGES >/dev/null 2>&1; then
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $APT_PACKAGES >/dev/null
fi
[ -x "$VENV/bin/python" ] || python3 -m venv "$VENV"
PIP=("$VENV/bin/python" -m pip install -q --disable-pip-version-check -c .ci/duckietown-constraints.txt)
"${PIP[@]}" --upgrade pip
"${PIP[@]}" duckietown-gym-daffy==6.1.34 duckietown-world-daffy==6.4.3 pyglet==1.5.27 "networkx<3" opencv-python \
  numpy scipy "scikit-fuzzy==0.5.0" matplotlib filterpy rich packaging pytest hypothesis mcap  # mcap: run.mcap (--mcap)
"$VENV/bin/python" -m pip install -q --disable-pip-version-check --no-deps -e .
"$VENV/bin/python" -c "from fearguard.worlds.duckietown.world import _simulator; _simulator(); print('duckietown simulator ready')"
