"""twin: a digital twin of robot workcells.

    import twin
    cell = twin.open_cell("scenes/scara_pick.toml")    # the notebook API (twin/notebook.py)
"""

import os

__version__ = "0.1.0"

# Cameras render headless (twin/vision/camera.py): without a display, MuJoCo's EGL back
# end (Mesa llvmpipe on a machine without a GPU).  It must be chosen before mujoco is
# imported; MUJOCO_GL=osmesa (or glfw with a display) still overrides it.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

__all__ = ["open_cell", "run_program", "__version__"]


def __getattr__(name: str):
    # Loaded on first use: `import twin` (the CLI's --version, the pytest plugin) stays light.
    if name == "open_cell":
        from .notebook import open_cell
        return open_cell
    if name == "run_program":
        from .runner import run_program
        return run_program
    raise AttributeError(f"module 'twin' has no attribute {name!r}")
