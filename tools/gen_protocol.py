#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Generates the code and documents that derive from the project's two single
sources of truth, and checks that the committed copies are up to date.

  firmware/protocol/pma_proto.dbc  -> firmware/protocol/generated/pma_proto.{c,h}
                                      (cantools generate_c_source --use-round),
                                      firmware/protocol/generated/pma_proto_version.h,
                                      firmware/app/generated/pma_proto_ties.h (the VAL_
                                      tables tied to the firmware's enums)
  firmware/app/params.toml         -> firmware/app/generated/pma_param_table.{c,h}
                                      docs/parameters.md

Usage: gen_protocol.py           write the generated files
       gen_protocol.py --check   exit 1 (and name the files) if regenerating
                                 would change anything; writes nothing
"""
from __future__ import annotations

import argparse
import re
import struct
import subprocess
import sys
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import cantools

from pmactl.protocol import param_table_hash, protocol_version

ROOT = Path(__file__).resolve().parents[1]
DBC = ROOT / "firmware/protocol/pma_proto.dbc"
PARAMS = ROOT / "firmware/app/params.toml"
PROTO_OUT = ROOT / "firmware/protocol/generated"
PARAM_OUT = ROOT / "firmware/app/generated"
PARAM_DOC = ROOT / "docs/parameters.md"

TYPES = {"f32": "PMA_PARAM_F32", "u32": "PMA_PARAM_U32", "i32": "PMA_PARAM_I32"}
C_TYPES = {"f32": "float", "u32": "uint32_t", "i32": "int32_t"}
ACCESS = {"live": "PMA_PARAM_LIVE", "stopped": "PMA_PARAM_STOPPED", "idle": "PMA_PARAM_IDLE"}
ACCESS_DOC = {
    "live": "any state",
    "stopped": "not while RUNNING",
    "idle": "only with the output inactive (BOOT, IDLE, FAULT)",
}
NAME_RE = re.compile(r"^[a-z][a-z0-9_]*\.[a-z][a-z0-9_]*$")


class TableError(Exception):
    pass


def load_rules(path: Path = PARAMS) -> list[dict[str, Any]]:
    """The [[rule]] tables of params.toml, by number (1, 2, ... without gaps)."""
    with open(path, "rb") as f:
        rules = tomllib.load(f).get("rule", [])
    if [r["number"] for r in rules] != list(range(1, len(rules) + 1)):
        raise TableError("params.toml: the rules must be numbered 1, 2, ... in order")
    return rules


def load_params(path: Path = PARAMS) -> list[dict[str, Any]]:
    """Reads and validates the parameter table; sorted by id."""
    with path.open("rb") as f:
        params = tomllib.load(f)["param"]
    ids: set[int] = set()
    names: set[str] = set()
    for p in params:
        where = f"{path.name}: parameter {p.get('name', '?')}"
        for key in ("id", "name", "type", "unit", "min", "max", "default", "access", "doc"):
            if key not in p:
                raise TableError(f"{where}: missing '{key}'")
        if not NAME_RE.match(p["name"]):
            raise TableError(f"{where}: name must be group.name in lower case")
        if p["type"] not in TYPES or p["access"] not in ACCESS:
            raise TableError(f"{where}: bad type or access")
        if not 1 <= p["id"] <= 0xFFFE or p["id"] in ids or p["name"] in names:
            raise TableError(f"{where}: id must be unique in 1..65534, name unique")
        ids.add(p["id"])
        names.add(p["name"])
        lo, hi, d = p["min"], p["max"], p["default"]
        if not lo <= d <= hi:
            raise TableError(f"{where}: default outside min..max")
        if p["type"] == "f32":
            for v in (lo, hi, d):
                if not isinstance(v, (int, float)) or not abs(float(v)) <= 3.4e38:
                    raise TableError(f"{where}: not a finite float32")
        else:
            bits = (0, 2**32 - 1) if p["type"] == "u32" else (-(2**31), 2**31 - 1)
            for v in (lo, hi, d):
                if not isinstance(v, int) or not bits[0] <= v <= bits[1]:
                    raise TableError(f"{where}: not a {p['type']} integer")
        if "values" in p:
            p["values"] = {int(k): str(v) for k, v in p["values"].items()}
        old = p.get("renamed_from", [])
        if not isinstance(old, list) or not all(isinstance(n, str) and NAME_RE.match(n) for n in old):
            raise TableError(f"{where}: renamed_from must be a list of earlier group.name names")
        p["field"] = p["name"].replace(".", "_")
    return sorted(params, key=lambda q: q["id"])


def c_float(v: float) -> str:
    f = struct.unpack("<f", struct.pack("<f", float(v)))[0]
    return f"{f!r}f" if "e" in repr(f) or "." in repr(f) else f"{f!r}.0f"


def c_value(p: dict[str, Any], v: Any) -> str:
    if p["type"] == "f32":
        return f"{{.f32 = {c_float(v)}}}"
    if p["type"] == "u32":
        return f"{{.u32 = {int(v)}u}}"
    if int(v) == -(2**31):
        return "{.i32 = INT32_MIN}"
    return f"{{.i32 = {int(v)}}}"


def c_escape(s: str) -> str:
    return s.replace("\\", "\\\\").replace('"', '\\"')


HEADER_NOTE = ("/* SPDX-License-Identifier: Apache-2.0 */\n"
               "/* Generated by tools/gen_protocol.py from {src}: do not edit. */\n")


def gen_param_header(params: list[dict[str, Any]]) -> str:
    out = [HEADER_NOTE.format(src="firmware/app/params.toml"),
           "#ifndef PMA_PARAM_TABLE_H\n#define PMA_PARAM_TABLE_H\n\n#include <stdint.h>\n\n",
           "/* Parameter ids (stable: they travel in PARAM_REQ / PARAM_RESP). */\n",
           "enum pma_param_id {\n"]
    for p in params:
        out.append(f"    PMA_PARAM_{p['field'].upper()} = {p['id']},\n")
    out.append("};\n\n")
    out.append(f"#define PMA_PARAM_COUNT {len(params)}u\n")
    out.append("/* CRC-32 of the table (pmactl.protocol.param_table_hash): DEVICE_INFO's ParamTableHash. */\n")
    out.append(f"#define PMA_PARAM_TABLE_HASH 0x{param_table_hash(params):08X}u\n\n")
    for p in params:
        for k, v in sorted(p.get("values", {}).items()):
            out.append(f"#define PMA_{p['field'].upper()}_{v} {k}u\n")
    out.append("\n/* Every parameter's value, in RAM; units in docs/parameters.md. */\n")
    out.append("typedef struct pma_params {\n")
    for p in params:
        unit = f" [{p['unit']}]" if p["unit"] else ""
        out.append(f"    {C_TYPES[p['type']]} {p['field']};{' ' * max(1, 28 - len(p['field']))}"
                   f"/* id {p['id']}{unit} */\n")
    out.append("} pma_params_t;\n\n#endif /* PMA_PARAM_TABLE_H */\n")
    return "".join(out)


def gen_param_source(params: list[dict[str, Any]]) -> str:
    out = [HEADER_NOTE.format(src="firmware/app/params.toml"),
           '#include "params.h"\n\n#include <stddef.h>\n\n',
           "const pma_param_desc_t pma_param_table[PMA_PARAM_COUNT] = {\n"]
    for p in params:
        out.append(
            f"    {{{p['id']}u, \"{c_escape(p['name'])}\", {TYPES[p['type']]}, {ACCESS[p['access']]},\n"
            f"     offsetof(pma_params_t, {p['field']}),\n"
            f"     {c_value(p, p['min'])}, {c_value(p, p['max'])}, {c_value(p, p['default'])}}},\n")
    out.append("};\n")
    return "".join(out)


def fmt_num(p: dict[str, Any], v: Any) -> str:
    if p["type"] == "f32":
        return f"{float(v):g}"
    return str(int(v))


def gen_param_doc(params: list[dict[str, Any]]) -> str:
    out = ["# Parameters\n\n",
           "<!-- Generated by tools/gen_protocol.py from firmware/app/params.toml: do not edit. -->\n\n",
           "Every tunable of the firmware is a parameter with an id, a type, a unit, a range and a\n",
           "default. Read and write them over CAN with PARAM_REQ / PARAM_RESP (docs/protocol.md):\n",
           "SET changes the value in RAM; SAVE writes all parameters to storage (two slots with a CRC:\n",
           "a power cut during a save keeps the previous set); RESTORE_DEFAULTS sets every parameter\n",
           "to its default in RAM; LOAD reads the saved set back.\n\n",
           "A SET is refused, and nothing changes, when the value is outside min..max\n",
           "(`PMA_ERR_RANGE`, -3), NaN or infinite (`PMA_ERR_NOT_FINITE`, -2), of another type\n",
           "(`PMA_ERR_TYPE`, -19), the id is unknown (`PMA_ERR_UNKNOWN_ID`, -18), or the state forbids it\n",
           "(`PMA_ERR_STATE`, -20). Access: *live* any state; *stopped* not while RUNNING (takes effect\n",
           "at the next START); *idle* only while the output is inactive (BOOT, IDLE, FAULT).\n",
           "Rules between parameters (the table below) are refused with `PMA_ERR_RANGE` (-3), and\n",
           "nothing changes; GET_STATUS (PARAM_REQ Op 9) of Id 1, LAST_RULE, then gives the number of\n",
           "the rule that refused (docs/protocol.md, \"Status values\"). START also checks the\n",
           "controller's own rules (for example `PMA_ERR_BAND`: the reference must keep `ppc.w1_cm`\n",
           "inside the constraints).\n\n",
           "Types: f32 (IEEE 754 single), u32, i32; enumerations are u32 (values listed).\n\n",
           "## Rules between parameters\n\n",
           "*checked* `set`: at every SET, because the sensor and DAC scalings act even while the\n",
           "output is inactive (also a stored set that breaks one is not loaded); so a change that\n",
           "would pass through a state that breaks the rule needs the order given. `arm`: at ARM and\n",
           "START only, so the parameters involved can be set in any order while IDLE, and ARM is\n",
           "refused until all of them agree.\n\n",
           "| rule | name | what must hold | checked | order of the changes |\n",
           "|---:|---|---|---|---|\n"]
    for r in load_rules():
        out.append(f"| {r['number']} | `{r['name']}` | {r['rule']} | {r['checked']} | {r['order']} |\n")
    out.append("\n")
    groups: dict[str, list[dict[str, Any]]] = {}
    for p in params:
        groups.setdefault(p["name"].split(".")[0], []).append(p)
    for g, ps in groups.items():
        out.append(f"## {g}\n\n")
        out.append("| id | name | type | unit | min | max | default | access | description |\n")
        out.append("|---:|---|---|---|---:|---:|---:|---|---|\n")
        for p in ps:
            doc = p["doc"]
            if "values" in p:
                doc += " Values: " + ", ".join(f"{k} {v}" for k, v in sorted(p["values"].items())) + "."
            out.append(f"| {p['id']} | `{p['name']}` | {p['type']} | {p['unit'] or '-'} | "
                       f"{fmt_num(p, p['min'])} | {fmt_num(p, p['max'])} | {fmt_num(p, p['default'])} | "
                       f"{p['access']} | {doc.replace('|', '/')} |\n")
        out.append("\n")
    return "".join(out)


def gen_codec() -> dict[str, str]:
    """Runs cantools and returns {file name: text}, without the generation date."""
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([sys.executable, "-m", "cantools", "generate_c_source", "--use-round",
                        "--use-float", "--database-name", "pma_proto", "-o", tmp, str(DBC)],
                       check=True, stdout=subprocess.DEVNULL)
        files = {}
        for name in ("pma_proto.c", "pma_proto.h"):
            text = (Path(tmp) / name).read_text()
            # the date would make every regeneration differ
            text = re.sub(r"(generated by cantools version \S+) .*\.",
                          r"\1 from firmware/protocol/pma_proto.dbc"
                          r" by tools/gen_protocol.py: do not edit.", text, count=1)
            files[name] = "/* SPDX-License-Identifier: Apache-2.0 */\n" + text
        return files


def gen_proto_version() -> str:
    db = cantools.database.load_file(str(DBC))
    assert isinstance(db, cantools.database.can.Database)
    return (HEADER_NOTE.format(src="firmware/protocol/pma_proto.dbc")
            + "#ifndef PMA_PROTO_VERSION_H\n#define PMA_PROTO_VERSION_H\n\n"
            + "/* The protocol version: the number of the DBC's VERSION line (DEVICE_INFO's\n"
            + " * ProtocolVersion). */\n"
            + f"#define PMA_PROTO_VERSION {protocol_version(db)}u\n\n#endif /* PMA_PROTO_VERSION_H */\n")


def gen_proto_senders() -> str:
    """X-macro lists of the messages each DBC node sends, so C code that checks or routes
    frames by sender (tests/fuzz/fuzz_frames.c) reads the DBC's list instead of a copy."""
    db = cantools.database.load_file(str(DBC))
    assert isinstance(db, cantools.database.can.Database)
    out = [HEADER_NOTE.format(src="firmware/protocol/pma_proto.dbc"),
           "#ifndef PMA_PROTO_SENDERS_H\n#define PMA_PROTO_SENDERS_H\n\n",
           "/* The messages each node of the DBC sends, in frame id order:\n",
           " * X(NAME, base frame id (node id 0), length in bytes). */\n"]
    for node in sorted(n.name for n in db.nodes):
        msgs = sorted((m for m in db.messages if node in m.senders), key=lambda m: m.frame_id)
        out.append(f"#define PMA_PROTO_{node.upper()}_TX_MESSAGES(X)")
        for m in msgs:
            out.append(f" \\\n    X({m.name}, 0x{m.frame_id:x}u, {m.length}u)")
        out.append("\n\n")
    out.append("#endif /* PMA_PROTO_SENDERS_H */\n")
    return "".join(out)


# The firmware's C names for the values of the DBC's VAL_ tables: (message, signal) -> the
# prefix of the C constant for each label (the label appended). Every table listed here is
# tied to its C enum by a _Static_assert per value (pma_proto_ties.h), so a value that changes
# on one side only, or a label without a C constant, stops the build.
ENUM_TIES: dict[tuple[str, str], str] = {
    ("COMMAND", "Command"): "PMA_CMD_",
    ("COMMAND_ACK", "Command"): "PMA_CMD_",
    ("COMMAND_ACK", "State"): "PMA_STATE_",
    ("COMMAND_ACK", "Result"): "PMA_ERR_",
    ("PARAM_REQ", "Op"): "PMA_PARAM_OP_",
    ("PARAM_REQ", "Type"): "PMA_PARAM_",
    ("PARAM_RESP", "Op"): "PMA_PARAM_OP_",
    ("PARAM_RESP", "Type"): "PMA_PARAM_",
    ("PARAM_RESP", "Result"): "PMA_ERR_",
    ("PLANT_ACTUATOR", "Sample"): "PMA_SAMPLE_",
    ("HEARTBEAT", "State"): "PMA_STATE_",
    ("HEARTBEAT", "FaultCode"): "PMA_FAULT_",
    ("HEARTBEAT", "Controller"): "PMA_CTRL_MODE_",
    ("HEARTBEAT", "Reference"): "PMA_REF_KIND_",
    ("HEARTBEAT", "ResetCause"): "PMA_RESET_",
}
C_NAME_EXCEPTIONS = {("PMA_ERR_", "OK"): "PMA_OK"}
# The DBC's value tables that no signal carries (VAL_TABLE_): name -> the prefix of the
# firmware's C constants, tied the same way. StatusId: GET_STATUS's Ids (pmactl reads them).
VALUE_TABLE_TIES: dict[str, str] = {"StatusId": "PMA_STATUS_"}

# The parameters whose values (params.toml "values") are a C enum of the firmware's other than
# the param table's own PMA_<NAME>_<VALUE> macros: parameter -> the prefix of that enum's
# constants. Each value is tied by a _Static_assert (pma_proto_ties.h) to both.
PARAM_ENUM_TIES: dict[str, str] = {
    "ref.kind": "PMA_REF_",            # pma_ref_kind_t (control: pma/ref.h)
    "vel.kind": "PMA_VELEST_",         # pma_velest_kind_t (control: pma/velest.h)
    "safety.safe_mode": "PMA_SAFE_",   # pma_safe_mode_t (app: actuator.h)
}


def gen_enum_ties() -> str:
    """_Static_asserts that tie each VAL_ table of ENUM_TIES to the firmware's C constants."""
    db = cantools.database.load_file(str(DBC))
    assert isinstance(db, cantools.database.can.Database)
    out = [HEADER_NOTE.format(src="firmware/protocol/pma_proto.dbc"),
           "#ifndef PMA_PROTO_TIES_H\n#define PMA_PROTO_TIES_H\n\n",
           "/* Each value of the DBC's VAL_ tables is the firmware's constant of that name\n",
           " * (tools/gen_protocol.py ENUM_TIES). Include after the headers that define them\n",
           " * (app.h, supervisor.h, params.h, actuator.h, pma/ref.h, pma/velest.h, pma/status.h,\n",
           " * pma/hal.h) and pma_proto.h. */\n"]
    # one block per value table: signals that share a table (COMMAND.Command and
    # COMMAND_ACK.Command, ...) are listed together, and a table that differs between
    # them gets a block of its own (which then fails to compile)
    blocks: dict[tuple[str, tuple[tuple[int, str], ...]], list[str]] = {}
    for (message, signal), prefix in ENUM_TIES.items():
        sig = db.get_message_by_name(message).get_signal_by_name(signal)
        if not sig.choices:
            raise TableError(f"{message}.{signal} has no VAL_ table to tie to {prefix}*")
        table = tuple(sorted((int(v), str(label)) for v, label in sig.choices.items()))
        blocks.setdefault((prefix, table), []).append(f"{message}.{signal}")
    tables = db.dbc.value_tables if db.dbc is not None else {}
    for name, prefix in VALUE_TABLE_TIES.items():
        if not tables.get(name):
            raise TableError(f"the DBC has no value table {name} to tie to {prefix}*")
        table = tuple(sorted((int(v), str(label)) for v, label in tables[name].items()))
        blocks.setdefault((prefix, table), []).append(f"value table {name}")
    for (prefix, table), signals in blocks.items():
        out.append(f"\n/* {', '.join(signals)} */\n")
        for value, label in table:
            c_name = C_NAME_EXCEPTIONS.get((prefix, label), prefix + label)
            out.append(f"_Static_assert({c_name} == {value}, \"{signals[0]} {label} is {value} in the DBC\");\n")
    params = {p["name"]: p for p in load_params()}
    for name, prefix in PARAM_ENUM_TIES.items():
        if not params.get(name, {}).get("values"):
            raise TableError(f"parameter {name} has no values to tie to {prefix}*")
        macro = "PMA_" + params[name]["field"].upper()
        out.append(f"\n/* parameter {name}: the param table's {macro}_* and the firmware's {prefix}* */\n")
        for value, label in sorted(params[name]["values"].items()):
            out.append(f"_Static_assert({prefix}{label} == {value} && {macro}_{label} == {value}u, "
                       f"\"{name} {label} is {value} in params.toml\");\n")
    out.append("\n#endif /* PMA_PROTO_TIES_H */\n")
    return "".join(out)


def outputs() -> dict[Path, str]:
    params = load_params()
    res = {PROTO_OUT / n: t for n, t in gen_codec().items()}
    res[PROTO_OUT / "pma_proto_version.h"] = gen_proto_version()
    res[PROTO_OUT / "pma_proto_senders.h"] = gen_proto_senders()
    res[PARAM_OUT / "pma_proto_ties.h"] = gen_enum_ties()
    res[PARAM_OUT / "pma_param_table.h"] = gen_param_header(params)
    res[PARAM_OUT / "pma_param_table.c"] = gen_param_source(params)
    res[PARAM_DOC] = gen_param_doc(params)
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only check that the committed files are current")
    args = ap.parse_args()
    try:
        files = outputs()
    except (TableError, KeyError, tomllib.TOMLDecodeError) as e:
        print(f"gen_protocol: {e}", file=sys.stderr)
        return 2
    stale = [p for p, t in files.items() if not p.exists() or p.read_text() != t]
    if args.check:
        for p in stale:
            print(f"gen_protocol: {p.relative_to(ROOT)} is out of date: run tools/gen_protocol.py",
                  file=sys.stderr)
        return 1 if stale else 0
    for p in stale:
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(files[p])
        print(f"gen_protocol: wrote {p.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
