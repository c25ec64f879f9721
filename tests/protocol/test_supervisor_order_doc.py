# SPDX-License-Identifier: Apache-2.0
"""docs/firmware.md and docs/protocol.md give the supervisor's check order, which decides
which fault is latched when several hold; both must be the order of
pma_supervisor_check in firmware/app/supervisor.h (inline there: the tick calls it)."""
from __future__ import annotations

import re
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
FAULTS = ["CAN_BUS_OFF", "SENSOR_TIMEOUT", "SENSOR_WIRE_BREAK", "SENSOR_RANGE", "SENSOR_READ",
          "POSITION_LIMIT", "TICK_OVERRUN", "HOST_HEARTBEAT_LOST", "CONTROLLER", "NOT_FINITE",
          "BARRIER"]


def code_order() -> list[str]:
    src = (REPO / "firmware/app/supervisor.h").read_text()
    body = src[src.index("static inline pma_fault_t pma_supervisor_check("):]
    body = body[:body.index("\n}\n")]
    body = body[body.index("return PMA_FAULT_CONTROLLER;") + 1:]   # after the NULL check
    return [n for n in re.findall(r"return PMA_FAULT_([A-Z_]+);", body) if n != "NONE"]


def doc_order(doc: str, start: str, end: str) -> list[str]:
    text = doc[doc.index(start):]
    text = text[:text.index(end)].replace("CAN bus-off", "CAN_BUS_OFF")
    names = re.findall(r"\b(" + "|".join(FAULTS) + r")\b", text)
    out: list[str] = []
    for n in names:
        if n not in out:
            out.append(n)
    return out


def test_the_code_checks_every_fault_once() -> None:
    assert code_order() == FAULTS


def test_firmware_md_gives_the_code_order() -> None:
    doc = (REPO / "docs/firmware.md").read_text()
    assert doc_order(doc, "The supervisor (`firmware/app/supervisor.h`) checks", "| code |") == code_order()


def test_protocol_md_gives_the_code_order() -> None:
    doc = (REPO / "docs/protocol.md").read_text()
    assert doc_order(doc, "The supervisor checks, every tick, in this order", "| value | fault |") == code_order()
