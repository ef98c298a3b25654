"""twin: a digital twin of robot workcells.

    import twin
    cell = twin.open_cell("scenes/scara_pick.toml")    # the notebook API (twin/notebook.py)
"""

__version__ = "0.1.0"

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
