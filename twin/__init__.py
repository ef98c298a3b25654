"""twin: a digital twin of robot workcells."""

import os

__version__ = "0.1.0"

# Cameras render headless (twin/vision/camera.py): without a display, MuJoCo's EGL back
# end (Mesa llvmpipe on a machine without a GPU).  It must be chosen before mujoco is
# imported; MUJOCO_GL=osmesa (or glfw with a display) still overrides it.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")
