# SPDX-License-Identifier: Apache-2.0
"""Unit tests of pmactl on python-can's virtual bus, against fake nodes (fakenode.py):
no CAN hardware, no firmware, no vcan.

    .venv/bin/python -m pytest host/tests -q --ignore=host/tests/integration
"""
from __future__ import annotations

import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator

import pytest
from fakenode import FakeNode

from pmactl.cli import main


@dataclass
class Result:
    code: int
    out: str
    err: str


@pytest.fixture(autouse=True)
def _isolated_can_config(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """No CAN_* variable or ~/.canrc of the machine reaches the tests."""
    for var in ("CAN_INTERFACE", "CAN_CHANNEL", "CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(var, raising=False)
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))


@pytest.fixture
def channel() -> str:
    return f"pmactl-test-{uuid.uuid4().hex[:8]}"


@pytest.fixture
def fake(channel: str) -> Iterator[Callable[..., FakeNode]]:
    """Factory: fake(node=0, **options) -> a running FakeNode on the test's channel."""
    nodes: list[FakeNode] = []

    def make(**kw: Any) -> FakeNode:
        n = FakeNode(channel=channel, **kw).__enter__()
        nodes.append(n)
        return n

    yield make
    for n in nodes:
        n.close()


@pytest.fixture
def pmactl(channel: str, capsys: pytest.CaptureFixture[str]) -> Callable[..., Result]:
    """pmactl(*args) -> Result: runs main() on the test's virtual channel."""

    def run(*args: str, bus: bool = True) -> Result:
        argv = (["--interface", "virtual", "--channel", channel, "--timeout", "3"] if bus else []) + list(args)
        capsys.readouterr()
        code = main(argv)
        cap = capsys.readouterr()
        return Result(code, cap.out, cap.err)

    return run
