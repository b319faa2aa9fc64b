"""MetaDrive 0.4.3 on a CPU: every setting and wrap that makes it render headless on Mesa (llvmpipe), in one place.

Out of the box MetaDrive either fails at start-up or takes minutes per frame on a software rasteriser
(../shared/metadrive/README.md measured why). Applied once, after ``import metadrive`` and before an
environment is created, without editing installed files:

- **no multisampling**: MetaDrive asks Panda3D for 8× (class-level prc data), simplepbr for 16× and the RGB
  camera's FilterManager for 16×; llvmpipe offers at most 4× and a refused buffer crashes the set-up with
  ``'NoneType' object has no attribute 'set_shader'`` (4× renders, but the first frame took 400 s). Panda3D's
  ``multisamples 0`` / ``framebuffer-multisample 0``, simplepbr's ``msaa_samples`` forced to 0, and every
  FilterManager buffer's multisamples set to 0;
- **EGL without an X server**: ``load-display p3headlessgl``; ``audio-library-name null``;
- **the road texture**: MetaDrive paints road and lane lines from a float semantic map of (region × px/m)²; at its
  defaults (1024 m × 22 px/m) that is 2 GB, uploaded for minutes. ``map_region_size = MAP_REGION_M`` (512) and
  ``PIXELS_PER_M`` (11: lines stay ≥ 1 px) give 5632² (127 MB), and the painted region is centred on the map
  (MetaDrive centres it on (0, 0), where the map starts: a long map would lose its markings at the far end);
- **anisotropic filtering and shadows off** (each about 2× the frame time here, README; the shadow pass measured
  1.35 → 1.05 s a step on a loaded machine): after the reset every texture's anisotropic degree is set to 1, the
  PSSM shadow buffer is switched off and the terrain shader told so (``after_reset``). Without it the road reads
  lighter (grey ~145 against ~120 in the road region at noon): MetaDrive's shadow pass darkened the whole road;
- ``multi_thread_render=False`` (``ENGINE_SETTINGS``); cameras from 160×120 up (a 64×48 camera hung);
- **no SIGINT handler per frame**: Panda3D's task manager swaps in its own SIGINT handler around every step, which
  Python allows only on the main thread — a drive in a Dask worker (``metadrive-suite --jobs``; tasks run on a worker
  thread) failed at the first reset with "signal only works in main thread" — and which, on the main thread, turned
  Ctrl-C into a KeyboardInterrupt after the frame instead of fearguard's own graceful stop (``drive/interrupt.py``).
  ``direct.task.Task.signal = None`` is Panda3D's own switch for platforms without signals;
- **a child-safe environment** (``repair_child_environment``): MetaDrive's asset loader sets ``PYTHONUTF8=on`` in the
  process environment when an engine starts; Python accepts only 0 or 1 there, so every process started afterwards
  died at start-up ("invalid PYTHONUTF8 environment variable value") — the Dask workers of a suite started in a
  process that had driven before (CI's test session). It becomes 1, the UTF-8 mode MetaDrive meant.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import io
import logging
import os
from typing import Any

from fearguard.errors import SimulatorMissing  # defined in errors.py, importable here

MAP_REGION_M = 512  # [m] side of the painted terrain region (a power of two, MetaDrive's rule)
PIXELS_PER_M = 11  # [px/m] of the semantic map that paints road and lines (MetaDrive: 22); lines stay >= 1 px wide
MIN_CAMERA_PX = (160, 120)  # [px] smaller cameras hung on Mesa

# MetaDrive config keys the headless render needs (merged into every world's config)
ENGINE_SETTINGS: dict[str, Any] = {
    "use_render": False,
    "multi_thread_render": False,
    "map_region_size": MAP_REGION_M,
    "show_interface": False,
    "interface_panel": [],
    "show_logo": False,
    "show_fps": False,
    "show_coordinates": False,
    "log_level": logging.ERROR,
}


_PATCHED = False


def simulator() -> Any:
    """Import MetaDrive (headless, patched for Mesa) once; a clear error if it is not installed. Returns the module."""
    global _PATCHED
    if importlib.util.find_spec("metadrive") is None:
        raise SimulatorMissing("MetaDrive is not installed in this Python environment; create its environment with "
                               "`bash .ci/metadrive.sh` and run fearguard from it (.venv-metadrive/bin/fearguard)")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):  # pygame's banner
        metadrive = importlib.import_module("metadrive")
    if _PATCHED:
        return metadrive
    from direct.filter.FilterManager import FilterManager
    from direct.task import Task
    from metadrive.engine.core import engine_core, terrain
    from panda3d.core import loadPrcFileData

    for line in ("load-display p3headlessgl", "aux-display p3headlessgl", "audio-library-name null", "framebuffer-multisample 0",
                 "multisamples 0", "texture-anisotropic-degree 1", "sync-video 0"):
        loadPrcFileData("fearguard-headless", line)

    pbr_init = engine_core.init

    def init_without_msaa(*args: Any, **kwargs: Any) -> Any:
        kwargs["msaa_samples"] = 0
        return pbr_init(*args, **kwargs)

    engine_core.init = init_without_msaa

    create_buffer = FilterManager.createBuffer

    def buffer_without_msaa(self: Any, name: str, xsize: int, ysize: int, texgroup: Any, depthbits: bool = True,
                            fbprops: Any = None) -> Any:
        if fbprops is not None:
            fbprops.set_multisamples(0)
        return create_buffer(self, name, xsize, ysize, texgroup, depthbits, fbprops)

    FilterManager.createBuffer = buffer_without_msaa

    Task.signal = None  # Panda3D's "no signals here" switch: its per-frame SIGINT handler (main thread only) is skipped
    terrain.TerrainProperty.get_semantic_map_pixel_per_meter = classmethod(lambda cls: PIXELS_PER_M)
    for name in ("metadrive", "panda3d"):
        logging.getLogger(name).setLevel(logging.ERROR)
    _PATCHED = True
    return metadrive


def repair_child_environment() -> None:
    """``PYTHONUTF8=on`` (MetaDrive's, at engine start) → ``1``: Python rejects "on" in every child process."""
    if os.environ.get("PYTHONUTF8") == "on":
        os.environ["PYTHONUTF8"] = "1"


def after_reset(engine: Any) -> None:
    """What can only be switched off once the scene exists: anisotropic filtering of every texture, and the shadows.

    MetaDrive sets anisotropic degree 16 on the terrain's and the sky's textures, held by its objects and the terrain
    shader (a C++ method cannot be wrapped), so they are found and set to 1 here; the PSSM shadow buffer renders the
    scene's depth every frame and is switched off, and the terrain shader told so.
    """
    from panda3d.core import Texture

    textures = list(engine.render.findAllTextures())
    for owner in (getattr(engine, "terrain", None), getattr(engine, "sky_box", None)):
        textures += [value for value in vars(owner).values() if isinstance(value, Texture)] if owner is not None else []
    for texture in textures:
        texture.setAnisotropicDegree(1)
    pssm = getattr(engine, "pssm", None)
    if pssm is not None and getattr(pssm, "buffer", None) is not None:
        pssm.buffer.set_active(False)
        engine.render.set_shader_input("use_pssm", False)
