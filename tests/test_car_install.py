"""`pip install fearguard` is enough for the car: no matplotlib, no rich, no scikit-fuzzy import needed to drive.

Each probe runs in a fresh interpreter where those packages cannot be imported (as on a car without the
desktop extra), and drives a guard, a Donkey part and the CLI's help.
"""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

BLOCK = "import sys\nfor name in ('matplotlib', 'rich', 'skfuzzy'):\n    sys.modules[name] = None  # importing it raises ImportError\n"


def run(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", BLOCK + code], capture_output=True, text=True, timeout=300)


def test_the_car_drives_without_the_desktop_extra_or_scikit_fuzzy():
    probe = """
import numpy as np, fearguard as fg
from types import SimpleNamespace
from fearguard.integrations.donkey import FearGuardPart
guard = fg.FearGuard(lambda frame: 0.0, vehicle=fg.VehicleLimits(has_ultrasonic=False, has_qr_localisation=False))
frame = np.full((120, 160, 3), 100, np.uint8)
for i in range(3):
    cmd = guard.step(fg.Observation(t_s=0.05 * (i + 1), speed_mps=1.0, frame=frame))
part = FearGuardPart.from_cfg(SimpleNamespace(IMAGE_W=160, IMAGE_H=120, FEARGUARD_MAX_SPEED_MPS=2.0))
out = part.run(frame, 0.0, 0.5)
print(cmd.mode.name, out[3])
"""
    done = run(probe)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split()[1] in ("NORMAL", "CAUTION", "EMERGENCY")


def test_the_cli_help_runs_without_the_desktop_extra():
    done = run("from fearguard.cli import main\ntry:\n    main(['--help'])\nexcept SystemExit as exc:\n    print('exit', exc.code)")
    assert done.returncode == 0, done.stderr
    assert "exit 0" in done.stdout


def test_plots_and_progress_bars_are_the_desktop_extra_and_test_installs_everything():
    project = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    core = " ".join(project["dependencies"])
    assert "matplotlib" not in core and "rich" not in core
    extras = project["optional-dependencies"]
    assert any(d.startswith("matplotlib") for d in extras["desktop"]) and any(d.startswith("rich") for d in extras["desktop"])
    assert any("desktop" in d for d in extras["test"]) and any("testing" in d for d in extras["test"])


def test_a_plot_without_the_desktop_extra_says_how_to_install_it(tmp_path):
    done = run(f"from fearguard.cli import main\nprint('exit', main(['rules', 'plot', '--out', {str(tmp_path)!r}]))")
    assert "exit 2" in done.stdout, done.stdout + done.stderr
    assert "fearguard[desktop]" in done.stderr + done.stdout
