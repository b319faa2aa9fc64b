#!/usr/bin/env bash
# The MetaDrive simulator's environment in one command: metadrive-simulator 0.4.3 + fearguard, headless on Mesa.
#
#   bash .ci/metadrive.sh [VENV]        (default: $METADRIVE_VENV or .venv-metadrive in the repository)
#
# - Mesa's EGL (Debian packages, only if missing) so Panda3D renders without an X server (p3headlessgl).
# - metadrive-simulator 0.4.3 from the package index with panda3d 1.10.13 / panda3d-gltf 0.13 as it pins them, numpy < 2
#   (MetaDrive 0.4.3 predates numpy 2), opencv-python as MetaDrive asks for it; every other version pinned by
#   .ci/metadrive-constraints.txt (a freeze of a working environment).
# - fearguard itself with --no-deps: its own dependencies are listed here (it accepts opencv-python for cv2).
# - MetaDrive's asset tree: the wheel ships none and would download it from GitHub on first import, which these
#   machines cannot reach. The tree in ../shared/metadrive/assets (or $METADRIVE_ASSETS) is linked into the
#   installed package as metadrive/assets (its version.txt says 0.4.3, so MetaDrive does not try to pull).
# A few minutes the first time (mostly downloads); seconds after.
set -euo pipefail
cd "$(dirname "$0")/.."
VENV="${1:-${METADRIVE_VENV:-.venv-metadrive}}"
ASSETS="${METADRIVE_ASSETS:-../shared/metadrive/assets}"
[ -f "$ASSETS/version.txt" ] || { echo "metadrive.sh: MetaDrive's asset tree is missing (looked in ../shared/metadrive/assets and $ASSETS); set METADRIVE_ASSETS" >&2; exit 2; }
ASSETS="$(cd "$ASSETS" && pwd)"
missing=""
for pkg in libegl1 libegl-mesa0 libgl1-mesa-dri; do dpkg -s "$pkg" >/dev/null 2>&1 || missing="$missing $pkg"; done
if [ -n "$missing" ]; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing >/dev/null
fi
test -x "$VENV/bin/python" || python3 -m venv "$VENV"
pip_install() { "$VENV/bin/python" -m pip install -q --disable-pip-version-check "$@"; }
pip_install -c .ci/metadrive-constraints.txt --upgrade pip
pip_install -c .ci/metadrive-constraints.txt metadrive-simulator==0.4.3 "numpy<2" opencv-python \
  scipy "scikit-fuzzy==0.5.0" networkx packaging filterpy matplotlib rich av pytest hypothesis \
  mcap "dask[distributed]>=2026.8.0,<2027"  # mcap: run.mcap (--mcap); dask: metadrive-suite --jobs / --scheduler
pip_install --no-deps -e .
SITE="$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
if [ "$(readlink "$SITE/metadrive/assets" 2>/dev/null)" != "$ASSETS" ]; then
  rm -rf "$SITE/metadrive/assets"
  ln -s "$ASSETS" "$SITE/metadrive/assets"
fi
"$VENV/bin/python" -c "import dask.distributed, mcap; from fearguard.worlds.metadrive.world import simulator; simulator(); print('metadrive simulator ready (with Dask and mcap)')"
