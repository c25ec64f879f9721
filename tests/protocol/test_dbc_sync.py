# SPDX-License-Identifier: Apache-2.0
"""The DBC (firmware/protocol/pma_proto.dbc) agrees with the C sources it is
not generated from: value tables against the C enums, the id layout, and the
generated codec is current. No CAN needed."""
from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

import cantools
import pytest

ROOT = Path(__file__).resolve().parents[2]
DBC = ROOT / "firmware/protocol/pma_proto.dbc"
STATUS_H = ROOT / "firmware/common/include/pma/status.h"
SUPERVISOR_H = ROOT / "firmware/app/supervisor.h"
APP_H = ROOT / "firmware/app/app.h"
PARAMS_H = ROOT / "firmware/app/params.h"
HAL_H = ROOT / "hal/include/pma/hal.h"
PARAMS_TOML = ROOT / "firmware/app/params.toml"


@pytest.fixture(scope="module")
def db() -> cantools.database.can.Database:
    return cantools.database.load_file(str(DBC))


def strip_comments(src: str) -> str:
    src = re.sub(r"/\*.*?\*/", " ", src, flags=re.S)
    return re.sub(r"//[^\n]*", " ", src)


def c_enum(path: Path, typedef_name: str) -> dict[str, int]:
    """NAME -> value of `typedef enum ... { ... } typedef_name;` (explicit or implicit values)."""
    src = strip_comments(path.read_text())
    m = re.search(r"typedef\s+enum\s*\w*\s*\{([^{}]*)\}\s*" + re.escape(typedef_name) + r"\s*;", src, re.S)
    assert m, f"{path.relative_to(ROOT)}: no typedef enum {typedef_name}"
    out: dict[str, int] = {}
    nxt = 0
    for item in m.group(1).split(","):
        item = item.strip()
        if not item:
            continue
        name, _, value = item.partition("=")
        v = int(value.strip(), 0) if value.strip() else nxt
        out[name.strip()] = v
        nxt = v + 1
    assert out, f"{typedef_name} is empty"
    return out


def c_defines(path: Path, prefix: str) -> dict[str, int]:
    src = strip_comments(path.read_text())
    return {m.group(1): int(m.group(2), 0)
            for m in re.finditer(r"#define\s+(" + re.escape(prefix) + r"\w+)\s+(0x[0-9A-Fa-f]+|\d+)u?\b", src)}


def dbc_choices(db, message: str, signal: str) -> dict[int, str]:
    choices = db.get_message_by_name(message).get_signal_by_name(signal).choices
    assert choices, f"{message}.{signal} has no value table"
    return {int(k): str(v) for k, v in choices.items()}


def by_value(enum: dict[str, int], prefix: str) -> dict[int, str]:
    out: dict[int, str] = {}
    for name, v in enum.items():
        assert name.startswith(prefix), f"{name} does not start with {prefix}"
        assert v not in out, f"value {v} twice: {out[v]} and {name}"
        out[v] = name[len(prefix):]
    return out


def test_c_enum_parser_reads_implicit_values(tmp_path: Path) -> None:
    h = tmp_path / "x.h"
    h.write_text("typedef enum e { /* c, d */ A_X, A_Y = 5, A_Z, // x\n A_W = -2 } e_t;\n")
    assert c_enum(h, "e_t") == {"A_X": 0, "A_Y": 5, "A_Z": 6, "A_W": -2}


def test_result_table_is_pma_status_t(db) -> None:
    status = c_enum(STATUS_H, "pma_status_t")
    want = {v: ("OK" if n == "PMA_OK" else n.removeprefix("PMA_ERR_")) for n, v in status.items()}
    assert all(n == "PMA_OK" or n.startswith("PMA_ERR_") for n in status)
    assert all(v <= 0 for v in want), "status codes are 0 or negative"
    for msg in ("COMMAND_ACK", "PARAM_RESP"):
        assert dbc_choices(db, msg, "Result") == want, f"{msg}.Result VAL_ differs from pma_status_t"
        sig = db.get_message_by_name(msg).get_signal_by_name("Result")
        assert sig.is_signed and sig.length == 8
        assert min(want) >= -128, "a status code does not fit the signed byte Result"


def test_fault_code_table_is_pma_fault_t(db) -> None:
    want = by_value(c_enum(SUPERVISOR_H, "pma_fault_t"), "PMA_FAULT_")
    assert dbc_choices(db, "HEARTBEAT", "FaultCode") == want


def test_state_tables_are_pma_app_state_t(db) -> None:
    want = by_value(c_enum(APP_H, "pma_app_state_t"), "PMA_STATE_")
    for msg in ("HEARTBEAT", "COMMAND_ACK"):
        assert dbc_choices(db, msg, "State") == want, f"{msg}.State"


def test_command_tables_are_pma_command_t(db) -> None:
    want = by_value(c_enum(APP_H, "pma_command_t"), "PMA_CMD_")
    for msg in ("COMMAND", "COMMAND_ACK"):
        assert dbc_choices(db, msg, "Command") == want, f"{msg}.Command"


def test_param_op_and_type_tables(db) -> None:
    ops = by_value(c_enum(APP_H, "pma_param_op_t"), "PMA_PARAM_OP_")
    types = by_value(c_enum(PARAMS_H, "pma_param_type_t"), "PMA_PARAM_")
    for msg in ("PARAM_REQ", "PARAM_RESP"):
        assert dbc_choices(db, msg, "Op") == ops, f"{msg}.Op"
        assert dbc_choices(db, msg, "Type") == types, f"{msg}.Type"
    # the value signals multiplexed by Type: ValueF32 m0, ValueU32 m1, ValueI32 m2
    for msg in ("PARAM_REQ", "PARAM_RESP"):
        m = db.get_message_by_name(msg)
        for code, name in types.items():
            sig = m.get_signal_by_name("Value" + name)
            assert sig.multiplexer_ids == [code], f"{msg}.Value{name}"


def test_sample_table_is_pma_sample(db) -> None:
    want = {v: n.removeprefix("PMA_SAMPLE_") for n, v in c_defines(APP_H, "PMA_SAMPLE_").items()}
    assert dbc_choices(db, "PLANT_ACTUATOR", "Sample") == want


def test_reset_cause_table_is_the_hal_enum(db) -> None:
    src = strip_comments(HAL_H.read_text())
    want = {int(m.group(2)): m.group(1) for m in re.finditer(r"\bPMA_RESET_(\w+)\s*=\s*(\d+)", src)}
    assert want, "no PMA_RESET_* in hal.h"
    assert dbc_choices(db, "HEARTBEAT", "ResetCause") == want


def test_controller_and_reference_tables_are_the_parameter_values(db) -> None:
    with PARAMS_TOML.open("rb") as f:
        params = {p["name"]: p for p in tomllib.load(f)["param"]}

    def values(name: str) -> dict[int, str]:
        return {int(k): v for k, v in params[name]["values"].items()}

    assert dbc_choices(db, "HEARTBEAT", "Controller") == values("ctrl.mode")
    assert dbc_choices(db, "HEARTBEAT", "Reference") == values("ref.kind")


def test_heartbeat_flags_comment_names_every_flag(db) -> None:
    flags = c_defines(APP_H, "PMA_HB_")
    bits = sorted(v.bit_length() - 1 for v in flags.values())
    assert all(v & (v - 1) == 0 for v in flags.values()), "one bit per flag"
    assert bits == list(range(len(bits))), "flags are bits 0..n-1"
    comment = db.get_message_by_name("HEARTBEAT").get_signal_by_name("Flags").comment
    for b in bits:
        assert re.search(rf"(Bit |, ){b} ", comment), f"the DBC's Flags comment omits bit {b}"
    assert not re.search(rf", {len(bits)} ", comment), "the DBC's Flags comment names a bit the firmware lacks"


def test_ids_are_base_ids_below_0x800_and_distinct(db) -> None:
    seen: dict[int, str] = {}
    for m in db.messages:
        assert not m.is_extended_frame, f"{m.name}: classic 11-bit ids only"
        assert m.frame_id % 16 == 0, f"{m.name}: base id 0x{m.frame_id:03X} is not a multiple of 16"
        assert m.frame_id < 0x800, f"{m.name}: id 0x{m.frame_id:03X} is not an 11-bit id"
        assert m.frame_id not in seen, f"{m.name} and {seen[m.frame_id]} share base id 0x{m.frame_id:03X}"
        seen[m.frame_id] = m.name
        assert 0 <= m.length <= 8, f"{m.name}: classic CAN has 0..8 data bytes"
    assert seen.get(0) == "ESTOP_ALL", "ESTOP_ALL is the broadcast at id 0"


def test_base_id_masks_match_the_firmware(db) -> None:
    masks = c_defines(APP_H, "PMA_")
    assert masks["PMA_NODE_ID_MASK"] == 0x00F and masks["PMA_BASE_ID_MASK"] == 0x7F0


def test_signals_fit_their_frames(db) -> None:
    for m in db.messages:
        for s in m.signals:
            assert s.byte_order == "little_endian", f"{m.name}.{s.name}: the protocol is little-endian"
            assert s.start + s.length <= 8 * m.length, f"{m.name}.{s.name} beyond DLC {m.length}"


def test_generated_code_is_current() -> None:
    r = subprocess.run([sys.executable, str(ROOT / "tools/gen_protocol.py"), "--check"],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, f"tools/gen_protocol.py --check failed:\n{r.stdout}{r.stderr}"
