# SPDX-License-Identifier: Apache-2.0
"""What to do when a CAN interface does not open: python-can's reason plus the step that
fixes it (docs/adapters.md).

python-can raises OSError, CanError, ImportError, TypeError, or (a driver whose native
library is missing) about anything when an interface cannot be opened. ``explain`` turns
the usual ones into one line a user can act on: a kernel without SocketCAN, a SocketCAN
interface that does not exist or is down, an interface whose Python package or native
library is absent (naming pmactl's extra that installs it), an interface that needs a
channel.
"""
from __future__ import annotations

import errno
from typing import Any

# python-can interface name -> pmactl's extra (= python-can's extra) that installs its package
INTERFACE_EXTRAS: dict[str, str] = {
    "slcan": "serial", "serial": "serial", "robotell": "serial", "seeedstudio": "serial",
    "gs_usb": "gs-usb", "pcan": "pcan", "neovi": "neovi", "canalystii": "canalystii",
    "cantact": "cantact", "candle": "candle", "udp_multicast": "multicast",
}
# interfaces that also need a vendor's native library (not on PyPI)
NATIVE_LIBRARIES: dict[str, str] = {
    "pcan": "PEAK's PCAN-Basic library (Windows: the PEAK driver package; macOS: PCBUSB from "
            "mac-can.com; on Linux use the kernel's peak_usb driver instead: --interface socketcan "
            "--channel can0)",
    "kvaser": "Kvaser's CANlib (the Kvaser drivers and CANlib SDK; on Linux the kernel's "
              "kvaser_usb driver works with --interface socketcan --channel can0)",
    "vector": "Vector's XL Driver Library (Windows only)",
    "ixxat": "HMS/IXXAT's VCI driver",
    "gs_usb": "libusb (Linux: apt-get install libusb-1.0-0; on Linux candleLight/gs_usb adapters "
              "are simpler through the kernel's gs_usb driver: --interface socketcan --channel can0)",
    "nican": "National Instruments' NI-CAN driver",
    "etas": "ETAS' BOA library",
    "systec": "SYS TEC's USB-CANmodul driver",
    "usb2can": "8devices' usb2can library (Windows)",
}
NEEDS_CHANNEL = {"vector": "0 (the application channel)", "neovi": "1 (the network)",
                 "kvaser": "0", "ixxat": "0", "slcan": "the serial port: /dev/ttyACM0, COM3",
                 "serial": "the serial port: /dev/ttyUSB0, COM3", "gs_usb": "0 (the device index)"}

SOCKETCAN_HELP = ("this kernel has no SocketCAN (address family AF_CAN): where the kernel has "
                  "the modules, load them with `sudo modprobe can_raw` (and `sudo modprobe vcan` for "
                  "a virtual bus); where it has none (containers, WSL1, some CI machines), run the "
                  "command inside the repository's `hil/with-vcan` (a User-Mode Linux guest with "
                  "vcan0): `hil/with-vcan pmactl ...`")


def _vcan_help(channel: str) -> str:
    return (f"no interface {channel}: create it with `sudo modprobe vcan && sudo ip link add dev "
            f"{channel} type vcan && sudo ip link set up {channel}`, or run the command inside "
            f"the repository's `hil/with-vcan` (which provides vcan0)")


def _can_help(channel: str) -> str:
    return (f"no interface {channel}: is the adapter plugged in and its driver loaded (candleLight: "
            f"gs_usb, PEAK: peak_usb, Kvaser: kvaser_usb)? `ip -details link show type can` lists "
            f"the CAN interfaces; bring one up with `sudo ip link set {channel} up type can bitrate "
            f"1000000`")


def pip_hint(interface: str) -> str:
    extra = INTERFACE_EXTRAS.get(interface)
    return f"pip install 'pmactl[{extra}]'" if extra else ""


def explain(cfg: dict[str, Any], exc: BaseException) -> str:
    """One line of advice for an interface that did not open ('' when there is none)."""
    interface = str(cfg.get("interface") or "")
    channel = str(cfg.get("channel") or "")
    text = str(exc)
    low = text.lower()
    code = exc.errno if isinstance(exc, OSError) else getattr(exc, "error_code", None)
    if code == errno.ENETDOWN:
        return f"{channel} is down: `sudo ip link set {channel} up type can bitrate 1000000`"
    if isinstance(exc, OSError) and interface == "socketcan":
        if exc.errno == errno.EAFNOSUPPORT:
            return SOCKETCAN_HELP
        if exc.errno == errno.ENODEV:
            return _vcan_help(channel) if channel.startswith("vcan") else _can_help(channel)
        if exc.errno in (errno.EPERM, errno.EACCES):
            return "not allowed to open a raw CAN socket here (a sandbox?)"
    missing_module = (isinstance(exc, ImportError) or "no module named" in low
                      or "not installed" in low or "cannot import module" in low)
    if missing_module:
        hint = pip_hint(interface)
        lib = NATIVE_LIBRARIES.get(interface)
        what = f"the python-can interface {interface!r} needs a package that is not installed"
        return what + (f": {hint}" if hint else "") + (f"; it also needs {lib}" if lib else "")
    if interface in NATIVE_LIBRARIES and (
            "library" in low or "dll" in low or "not found" in low or "not defined" in low
            or "could not" in low or isinstance(exc, (NameError, AttributeError))):
        hint = pip_hint(interface)
        return f"the {interface} interface needs {NATIVE_LIBRARIES[interface]}" + \
            (f", and {hint}" if hint else "")
    if isinstance(exc, TypeError) and "channel" in low:
        example = NEEDS_CHANNEL.get(interface, "see docs/adapters.md")
        return f"the {interface} interface needs a channel: --channel CHANNEL (e.g. {example})"
    if interface in ("slcan", "serial") and ("could not open port" in low or "no such file" in low):
        return (f"no serial port {channel}: is the adapter plugged in? (Linux: /dev/ttyACM*, "
                f"/dev/ttyUSB*; Windows: COMn; macOS: /dev/tty.usbmodem*)")
    return ""


def unknown_interface_hint(name: str) -> str:
    """Advice for an interface name python-can does not know (a plugin's, or a typo)."""
    hint = pip_hint(name)
    if hint:
        return f"the {name!r} interface is a python-can plug-in: {hint}"
    return ""
