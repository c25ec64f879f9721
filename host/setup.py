# SPDX-License-Identifier: Apache-2.0
"""The build's one job beyond pyproject.toml: put the protocol's single sources of truth into
the package, and its version: firmware/protocol/pma_proto.dbc, firmware/app/params.toml and the
repository's VERSION (the firmware's version, which pmactl shares) are copied into
pmactl/data/ of the wheel (build_py) and of the sdist (sdist), so an installed pmactl stands
alone, and nothing in host/ is a copy or a symbolic link that can go stale (or arrive as a
text file on a checkout without symlinks). Building from an sdist, which has no firmware/
beside it, takes the copies the sdist carries."""
from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

HERE = Path(__file__).resolve().parent
DATA = {"pma_proto.dbc": "firmware/protocol/pma_proto.dbc", "params.toml": "firmware/app/params.toml",
        "VERSION": "VERSION"}


def source(name: str) -> Path:
    """The firmware's file in the repository, else the copy in an unpacked sdist."""
    repo = HERE.parent / DATA[name]
    if repo.is_file():
        return repo
    packed = HERE / "src" / "pmactl" / "data" / name
    if packed.is_file():
        return packed
    raise SystemExit(f"pmactl build: {DATA[name]} not found (build from the repository's host/ "
                     f"folder, or from pmactl's sdist)")


def copy_data(package_dir: Path) -> None:
    out = package_dir / "pmactl" / "data"
    out.mkdir(parents=True, exist_ok=True)
    for name in DATA:
        target = out / name
        src = source(name)
        if target.resolve() != src.resolve():
            if target.is_symlink() or target.exists():
                target.unlink()
            shutil.copyfile(src, target)


class BuildPy(build_py):
    def run(self) -> None:
        super().run()
        if not self.dry_run:
            copy_data(Path(self.build_lib))


class Sdist(sdist):
    def make_release_tree(self, base_dir: str, files: list[str]) -> None:
        super().make_release_tree(base_dir, files)
        copy_data(Path(base_dir) / "src")


setup(version=source("VERSION").read_text().strip(),
      cmdclass={"build_py": BuildPy, "sdist": Sdist})
