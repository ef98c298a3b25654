"""Build step that puts the repository's models/, scenes/ and programs/ into the wheel.

They stay top-level folders in the repository (other work adds files there and every
command in the docs names them so); the wheel carries copies under twin/data/, where
twin.resources finds them through importlib.resources.  Everything else is declared in
pyproject.toml.
"""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
DATA_FOLDERS = ("models", "scenes", "programs")   # twin.resources.FOLDERS


class BuildPyWithData(build_py):
    def run(self) -> None:
        super().run()
        if self.editable_mode:   # an editable install reads the folders where they are
            return
        for name in DATA_FOLDERS:
            self.copy_tree(str(ROOT / name), str(Path(self.build_lib) / "twin" / "data" / name))


setup(cmdclass={"build_py": BuildPyWithData})
