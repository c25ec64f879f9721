# SPDX-License-Identifier: Apache-2.0
"""Choosing and opening a python-can bus, and the receive filters of a node's frames: one way
for pmactl and the HIL harness."""
from __future__ import annotations

from typing import Any, Iterable

import can

from pmactl import adapters
from pmactl.errors import BadBusConfig, InterfaceError
from pmactl.protocol import BASE_ID_MASK, BROADCASTS, Protocol

DEFAULT_INTERFACE = "socketcan"
DEFAULT_CHANNEL = "vcan0"           # only when the interface is socketcan


# ---------------------------------------------------------------- the bus --
def bus_config(interface: str | None = None, channel: str | None = None,
               bitrate: int | None = None, context: str | None = None,
               config_file: str | None = None) -> dict[str, Any]:
    """The bus configuration: the given values, then python-can's own configuration
    (can.rc, CAN_INTERFACE / CAN_CHANNEL / CAN_BITRATE / CAN_CONFIG, ~/.canrc and the
    other files of can.util.load_config), and only what is still unset defaults:
    interface socketcan, and channel vcan0 when the interface is socketcan.

    BadBusConfig (an InterfaceError) for a value python-can cannot use, wherever it came
    from: an interface name it does not have (neither built in nor an installed plug-in:
    can.interfaces.VALID_INTERFACES), an empty one included, an empty channel, a bit rate that
    is not a whole number of bit/s above 0; InterfaceError for a plug-in pmactl knows that is
    not installed (with the pip command that installs it) and for another bad value. The one
    check of both pmactl's and the HIL harness's bus options."""
    given: dict[str, Any] = {k: v for k, v in (("interface", interface), ("channel", channel),
                                                 ("bitrate", bitrate)) if v is not None}
    if "interface" not in given:
        sources: list[dict[str, Any]] = [dict(can.rc), can.util.load_environment_config(context),
                                         can.util.load_environment_config(),
                                         can.util.load_file_config(config_file, context or "default"),
                                         can.util.load_file_config(config_file)]
        if not any(src.get("interface") or src.get("bustype") for src in sources):
            given["interface"] = DEFAULT_INTERFACE
    try:
        cfg = dict(can.util.load_config(path=config_file, config=given, context=context))
    except can.CanInterfaceNotImplementedError as e:
        known = ", ".join(sorted(can.interfaces.VALID_INTERFACES))
        name = str(given.get("interface") or "")
        hint = adapters.unknown_interface_hint(name) if name else ""
        if hint:    # a plug-in pmactl knows (docs/adapters.md), not installed: a missing driver
            raise InterfaceError(f"bad CAN configuration: {e} (python-can knows: {known})\n  {hint}") from e
        raise BadBusConfig(f"bad CAN configuration: {e} (python-can knows: {known})") from e
    except (ValueError, TypeError) as e:
        raise InterfaceError(f"bad CAN configuration: {e}") from e
    channel = cfg.get("channel")
    if channel is not None and not str(channel).strip():
        raise BadBusConfig("bad CAN configuration: the channel is empty")
    rate = cfg.get("bitrate")
    if rate is not None and (isinstance(rate, bool) or not isinstance(rate, int) or rate <= 0):
        raise BadBusConfig(f"bad CAN configuration: bit rate {rate!r} is not a whole number of bit/s above 0")
    if cfg.get("channel") is None and cfg.get("interface") == DEFAULT_INTERFACE:
        cfg["channel"] = DEFAULT_CHANNEL
    return {k: v for k, v in cfg.items() if v is not None}


def describe_bus(cfg: dict[str, Any]) -> str:
    text = f"{cfg.get('interface')} {cfg.get('channel', '(default channel)')}"
    if cfg.get("bitrate"):
        text += f" at {int(cfg['bitrate'])} bit/s"
    return text


def open_bus(cfg: dict[str, Any]) -> can.BusABC:
    """can.Bus(**cfg); InterfaceError with python-can's reason when it cannot be opened
    (python-can raises CanError or OSError on open, ImportError for a missing driver) and
    the step that fixes it (pmactl.adapters.explain)."""
    try:
        return can.Bus(**cfg)
    except KeyboardInterrupt:
        raise
    except Exception as e:      # a driver without its library raises about anything
        hint = adapters.explain(cfg, e)
        reason = str(e) or type(e).__name__
        raise InterfaceError(f"cannot open CAN interface {describe_bus(cfg)}: {reason}"
                             + (f"\n  {hint}" if hint else "")) from e


# Messages a node sends: what a client listens to.
NODE_REPLIES = ("COMMAND_ACK", "PARAM_RESP", "HEARTBEAT", "DEVICE_INFO")


def frame_filters(proto: Protocol, messages: Iterable[str], node: int | None = None) -> list[dict[str, Any]]:
    """python-can receive filters for the given messages, of one node (None: every node).
    On a busy bus (a plant bridge at 1 kHz) a client that receives every frame can fall
    behind and lose frames in its socket; filters (in the kernel for socketcan) avoid it."""
    out: list[dict[str, Any]] = []
    for m in messages:
        base = proto.messages[m].frame_id
        if m in BROADCASTS:
            out.append({"can_id": base, "can_mask": 0x7FF, "extended": False})
        elif node is None:
            out.append({"can_id": base, "can_mask": BASE_ID_MASK, "extended": False})
        else:
            out.append({"can_id": base | node, "can_mask": 0x7FF, "extended": False})
    return out


