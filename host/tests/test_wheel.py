# SPDX-License-Identifier: Apache-2.0
"""A wheel that stands alone: built with pip from host/ (and from a copy of the repository's
files with no symbolic link anywhere), installed into a fresh virtual environment outside
the repository, it runs `pmactl --version` and decodes a frame with the DBC it carries.

Slow (a build and a venv; with build isolation pip fetches setuptools): marked `slow`, so
`-m "not slow"` leaves it out; CI's pytest stage runs it. The fresh venv takes pmactl's
dependencies (python-can, cantools, numpy, matplotlib) from this environment through a .pth
file instead of downloading them; PMACTL_WHEEL_TEST_INDEX=1 installs them from the index.
"""
from __future__ import annotations

import importlib.metadata
import os
import shutil
import subprocess
import sys
import sysconfig
import venv
import zipfile
from pathlib import Path

import pytest
from fakenode import PROTO

HOST = Path(__file__).resolve().parents[1]
REPO = HOST.parent
FIRMWARE = {"pmactl/data/pma_proto.dbc": REPO / "firmware/protocol/pma_proto.dbc",
            "pmactl/data/params.toml": REPO / "firmware/app/params.toml",
            "pmactl/data/VERSION": REPO / "VERSION"}

pytestmark = pytest.mark.slow


def _isolation_args() -> list[str]:
    """Without build isolation when this environment has the setuptools pyproject.toml asks
    for (no download); else pip's isolated build (fetches it)."""
    try:
        major = int(importlib.metadata.version("setuptools").split(".")[0])
    except importlib.metadata.PackageNotFoundError:
        return []
    return ["--no-build-isolation"] if major >= 77 else []


def _builder(where: Path) -> Path:
    """A Python with the setuptools pyproject.toml asks for: this one, or a venv in tmp
    with it installed from the index (as pip's isolated build would fetch it)."""
    if _isolation_args():
        return Path(sys.executable)
    venv.EnvBuilder(with_pip=False, clear=True).create(where)
    py = where / "bin" / "python"
    r = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q", "setuptools>=77"],
                       capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    return py


def build_wheel(src: Path, out: Path) -> Path:
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", *_isolation_args(),
                        "-q", "-w", str(out), str(src)], capture_output=True, text=True, cwd=out, check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    (wheel,) = out.glob("pmactl-*.whl")
    return wheel


def fresh_venv(where: Path) -> Path:
    """A new venv; pmactl's dependencies from this environment's site-packages (a .pth
    line: its own .pth files, among them an editable pmactl's finder, are not run)."""
    venv.EnvBuilder(with_pip=False, clear=True).create(where)
    py = where / "bin" / "python"
    if not py.exists():
        py = where / "Scripts" / "python.exe"
    if not os.environ.get("PMACTL_WHEEL_TEST_INDEX"):
        site = subprocess.run([str(py), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                              capture_output=True, text=True, check=True).stdout.strip()
        Path(site, "_pmactl_test_deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return py


def install(py: Path, wheel: Path) -> None:
    deps = [] if os.environ.get("PMACTL_WHEEL_TEST_INDEX") else ["--no-deps"]
    r = subprocess.run([sys.executable, "-m", "pip", "--python", str(py), "install", "-q", *deps, str(wheel)],
                       capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stdout + r.stderr


CHECK = r"""
import sys, pmactl, pmactl.protocol as pp
from pathlib import Path
files = pp.data_files()
env = Path(sys.prefix).resolve()
assert Path(pmactl.__file__).resolve().is_relative_to(env), pmactl.__file__
for f in files.values():
    assert f.resolve().is_relative_to(env), f
p = pp.load_protocol()
sig = p.decode("HEARTBEAT", bytes([3, 0, 0x47, 0, 1, 4, 1, 9]))
assert sig["State"] == 3 and sig["Controller"] == 1 and sig["Counter"] == 9, sig
assert p.param("ppc.w1_cm").unit == "cm"
print("ok", files["dbc"], p.version)
"""


def check_install(py: Path, cwd: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PMA_DBC", "PMA_PARAMS_TOML")}
    bindir = py.parent
    pmactl = bindir / ("pmactl.exe" if os.name == "nt" else "pmactl")
    r = subprocess.run([str(pmactl), "--version"], capture_output=True, text=True, cwd=cwd, env=env, check=False)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith(f"pmactl {importlib.metadata.version('pmactl')} (protocol {PROTO.version}"), r.stdout
    r = subprocess.run([str(py), "-c", CHECK], capture_output=True, text=True, cwd=cwd, env=env, check=False)
    assert r.returncode == 0 and r.stdout.startswith("ok "), r.stdout + r.stderr
    r = subprocess.run([str(pmactl), "dbc", "--nodes", "2"], capture_output=True, text=True, cwd=cwd, env=env,
                       check=False)
    assert r.returncode == 0 and "HEARTBEAT_N2" in r.stdout, r.stderr


def check_wheel_contents(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as z:
        for inside, firmware in FIRMWARE.items():
            assert z.read(inside) == firmware.read_bytes(), inside
        names = z.namelist()
    assert "pmactl/py.typed" in names and "pmactl/cli.py" in names


def test_no_symbolic_links_in_host() -> None:
    links = [p for p in HOST.rglob("*") if p.is_symlink()]
    assert not links, links


def test_wheel_from_host_installs_into_a_fresh_venv(tmp_path: Path) -> None:
    wheel = build_wheel(HOST, tmp_path)
    check_wheel_contents(wheel)
    py = fresh_venv(tmp_path / "venv")
    install(py, wheel)
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    check_install(py, outside)


def test_wheel_from_a_copy_without_links_and_from_its_sdist(tmp_path: Path) -> None:
    """A copy of host/ and the two firmware files, every file a plain file (as a checkout
    with core.symlinks=false has them); and the sdist built from it, unpacked where no
    firmware/ is beside it."""
    copy = tmp_path / "checkout"
    shutil.copytree(HOST, copy / "host", symlinks=False,
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "build", ".pytest_cache"))
    for firmware in FIRMWARE.values():
        dest = copy / firmware.relative_to(REPO)
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(firmware, dest)
    wheels = tmp_path / "wheels"
    wheels.mkdir()
    wheel = build_wheel(copy / "host", wheels)
    check_wheel_contents(wheel)
    # the sdist carries the firmware's files; a wheel built from it has them too
    sd = tmp_path / "sdist"
    r = subprocess.run([str(_builder(tmp_path / "builder")), "-c",
                        "import sys, setuptools.build_meta as b; print(b.build_sdist(sys.argv[1]))", str(sd)],
                       cwd=copy / "host", capture_output=True, text=True, check=False)
    assert r.returncode == 0, r.stdout + r.stderr
    (tarball,) = sd.glob("pmactl-*.tar.gz")
    shutil.unpack_archive(tarball, tmp_path / "unpacked")
    (unpacked,) = (tmp_path / "unpacked").iterdir()
    from_sdist = tmp_path / "from_sdist"
    from_sdist.mkdir()
    check_wheel_contents(build_wheel(unpacked, from_sdist))
    py = fresh_venv(tmp_path / "venv")
    install(py, wheel)
    check_install(py, tmp_path)
