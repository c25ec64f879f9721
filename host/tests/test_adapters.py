# SPDX-License-Identifier: Apache-2.0
"""Adapters without surprises: an interface that cannot be opened gives python-can's reason
and the step that fixes it (pmactl.adapters), exit 3, never a traceback."""
from __future__ import annotations

import errno
import tomllib
from pathlib import Path
from typing import Any

import can
import pytest

from pmactl import adapters
from pmactl.cli import EXIT_INTERFACE

HOST = Path(__file__).resolve().parents[1]


def _fail_with(monkeypatch: pytest.MonkeyPatch, exc: BaseException) -> None:
    def bus(**_kw: Any) -> can.BusABC:
        raise exc
    monkeypatch.setattr(can, "Bus", bus)           # pmactl.client opens buses with can.Bus


CASES = [
    # (interface, channel, what python-can raises, words the message must have)
    ("socketcan", "vcan0", OSError(errno.EAFNOSUPPORT, "Address family not supported by protocol"),
     ["no SocketCAN", "modprobe", "hil/with-vcan"]),
    ("socketcan", "vcan0", OSError(errno.ENODEV, "No such device"),
     ["no interface vcan0", "modprobe vcan", "ip link add dev vcan0 type vcan", "hil/with-vcan"]),
    ("socketcan", "can0", OSError(errno.ENODEV, "No such device"),
     ["no interface can0", "gs_usb", "ip link set can0 up type can bitrate 1000000"]),
    ("slcan", "/dev/ttyACM0", can.CanInterfaceNotImplementedError("The serial module is not installed"),
     ["pip install 'pmactl[serial]'"]),
    ("gs_usb", "0", can.CanInterfaceNotImplementedError(
        "Cannot import module can.interfaces.gs_usb for CAN interface 'gs_usb': No module named 'usb'"),
     ["pip install 'pmactl[gs-usb]'", "libusb"]),
    ("pcan", "PCAN_USBBUS1", OSError("pcanbasic library not found."),
     ["PCAN-Basic", "peak_usb", "pip install 'pmactl[pcan]'"]),
    ("udp_multicast", None, ImportError("msgpack not installed"), ["pip install 'pmactl[multicast]'"]),
    ("kvaser", "0", NameError("name 'canGetNumberOfChannels' is not defined"), ["CANlib", "kvaser_usb"]),
    ("vector", None, TypeError("VectorBus.__init__() missing 1 required positional argument: 'channel'"),
     ["needs a channel", "--channel"]),
    ("slcan", "/dev/ttyACM7", can.CanInitializationError("could not open port /dev/ttyACM7"),
     ["no serial port /dev/ttyACM7", "plugged in"]),
]


@pytest.mark.parametrize("interface, channel, exc, words", CASES,
                         ids=[f"{c[0]}-{type(c[2]).__name__}-{i}" for i, c in enumerate(CASES)])
def test_each_open_failure_says_what_to_do(pmactl, monkeypatch: pytest.MonkeyPatch, interface: str,
                                           channel: str | None, exc: BaseException, words: list[str]) -> None:
    _fail_with(monkeypatch, exc)
    args = ["--interface", interface] + (["--channel", channel] if channel else [])
    r = pmactl(*args, "status", bus=False)
    assert r.code == EXIT_INTERFACE
    assert f"cannot open CAN interface {interface}" in r.err and str(exc) in r.err
    for w in words:
        assert w in r.err, (w, r.err)
    assert "Traceback" not in r.err


def test_a_plugin_interface_names_its_extra(pmactl) -> None:
    r = pmactl("--interface", "candle", "status", bus=False)
    assert r.code == EXIT_INTERFACE
    assert "python-can knows" in r.err and "pip install 'pmactl[candle]'" in r.err


def test_this_machines_socketcan(pmactl) -> None:
    """For real, without mocks: socketcan on a channel that does not exist, on whatever kernel
    this is (no SocketCAN at all, or no such interface): exit 3 with the fix."""
    r = pmactl("--interface", "socketcan", "--channel", "vcan9", "status", bus=False)
    assert r.code == EXIT_INTERFACE
    assert "hil/with-vcan" in r.err and ("modprobe" in r.err)
    assert "Traceback" not in r.err


def test_a_bus_that_goes_down_says_how_to_bring_it_up() -> None:
    e = can.CanOperationError("Failed to transmit: [Errno 100] Network is down", error_code=errno.ENETDOWN)
    assert "ip link set can0 up type can bitrate 1000000" in adapters.explain(
        {"interface": "socketcan", "channel": "can0"}, e)


def test_extras_are_python_cans() -> None:
    """Every extra named in a message exists in pyproject.toml and is python-can's extra of
    the same name (pip would otherwise install nothing, silently)."""
    extras = tomllib.loads((HOST / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    import importlib.metadata
    can_extras = set(importlib.metadata.metadata("python-can").get_all("Provides-Extra") or [])
    for interface, extra in adapters.INTERFACE_EXTRAS.items():
        assert extras[extra] == [f"python-can[{extra}]"], interface
        assert extra in can_extras, extra
