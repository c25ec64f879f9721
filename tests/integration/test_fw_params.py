# SPDX-License-Identifier: Apache-2.0
"""The parameter table over CAN: every parameter of docs/parameters.md has its
params.toml default after a fresh start, reports the table's min, max and
default, NEXT_ID enumerates exactly the table, min and max are accepted, and
the access classes (live, stopped, idle) hold in every state."""
from __future__ import annotations

import re
from pathlib import Path

from test_fw_lib import (
    HB_PARAMS_CHANGED,
    HB_PARAMS_DEFAULT,
    PROTO,
    RESULT,
    STATE,
    arm,
    f32,
    fresh_heartbeat,
    query_state,
    start,
)

ROOT = Path(__file__).resolve().parents[2]
NODE = 2
TYPES = {"f32": 0, "u32": 1, "i32": 2}


def doc_table() -> dict[int, dict]:
    """The rows of docs/parameters.md's tables, by id."""
    rows = {}
    pat = re.compile(r"^\|\s*(\d+)\s*\|\s*`([^`]+)`\s*\|\s*(f32|u32|i32)\s*\|[^|]*\|\s*([^|]+?)\s*\|"
                     r"\s*([^|]+?)\s*\|\s*([^|]+?)\s*\|\s*(live|stopped|idle)\s*\|")
    for line in (ROOT / "docs/parameters.md").read_text().splitlines():
        m = pat.match(line)
        if m:
            pid, name, typ, mn, mx, df, access = m.groups()
            conv = float if typ == "f32" else int
            rows[int(pid)] = dict(name=name, type=typ, min=conv(mn), max=conv(mx), default=conv(df),
                                  access=access)
    return rows


DOC = doc_table()


def typed(p, v):
    return f32(v) if p.type == "f32" else int(v)


def close(a, b) -> bool:
    """Equal up to the 6 significant digits the document prints."""
    return a == b or abs(a - b) <= 1e-5 * max(abs(a), abs(b))


def test_document_lists_the_table() -> None:
    """docs/parameters.md and params.toml (what the client and firmware use)
    describe the same parameters."""
    assert len(DOC) > 50
    assert sorted(DOC) == [p.id for p in PROTO.params]
    for p in PROTO.params:
        d = DOC[p.id]
        assert (d["name"], d["type"], d["access"]) == (p.name, p.type, p.access), p.name
        for k in ("min", "max", "default"):
            assert close(d[k], getattr(p, k)), (p.name, k, d[k], getattr(p, k))


def test_fresh_start_defaults_and_reported_limits(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    hb = fresh_heartbeat(node)
    assert hb["Flags"] & HB_PARAMS_DEFAULT and not hb["Flags"] & HB_PARAMS_CHANGED, hex(hb["Flags"])
    for p in PROTO.params:
        t = TYPES[p.type]
        # GET with every request Type: the reply has the parameter's Type and its default
        for req_t in (0, 1, 2):
            r = node.param_request("GET", p.id, req_t)
            assert r.result == 0 and r.type == t, (p.name, r)
            assert r.value == typed(p, p.default), (p.name, r.value, p.default)
        got = {op: node.param_request(op, p.id, (t + 1) % 3) for op in ("GET_MIN", "GET_MAX", "GET_DEFAULT")}
        for op, field in (("GET_MIN", "min"), ("GET_MAX", "max"), ("GET_DEFAULT", "default")):
            r = got[op]
            assert r.result == 0 and r.type == t, (p.name, op, r)
            assert r.value == typed(p, getattr(p, field)), (p.name, op, r.value)
            assert close(r.value, DOC[p.id][field]), (p.name, op, r.value, DOC[p.id][field])
    fw.stop()


def test_next_id_enumerates_the_table(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    ids = [p.id for p in PROTO.params]
    assert node.ids() == ids
    # from any id (also ones that are no parameter) the next one of the table
    for after in [0] + list(range(0, max(ids) + 2, 7)) + [i - 1 for i in ids] + [i + 1 for i in ids]:
        r = node.param_request("NEXT_ID", after, 1)
        nxt = [i for i in ids if i > after]
        if nxt:
            assert (r.result, r.type, r.value) == (0, 1, nxt[0]), (after, r)
        else:
            assert r.result == RESULT["EMPTY"], (after, r)
    for after in (max(ids), 1000, 0xFFFF):
        assert node.param_request("NEXT_ID", after, 1).result == RESULT["EMPTY"]
    fw.stop()


# Values other parameters must have first so that an extreme value of a
# member of a scaling group keeps the group consistent (raw_min <= raw_max,
# wire_break <= raw_min, dac min <= max).
PREREQ = {
    ("adc.raw_min_counts", "min"): [("adc.wire_break_below_counts", 0)],
    ("adc.raw_min_counts", "max"): [("adc.raw_max_counts", 65535)],
    ("adc.raw_max_counts", "min"): [("adc.wire_break_below_counts", 0), ("adc.raw_min_counts", 0)],
    ("adc.wire_break_below_counts", "max"): [("adc.raw_max_counts", 65535), ("adc.raw_min_counts", 65535)],
    ("dac.min_counts", "max"): [],  # dac.max_counts is already at its maximum, 4095
    ("dac.max_counts", "min"): [("dac.min_counts", 0)],
}


def test_set_min_and_max_accepted(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    for p in PROTO.params:
        for which in ("min", "max"):
            node.restore_defaults()
            for name, v in PREREQ.get((p.name, which), []):
                assert node.set(name, v) == v
            v = typed(p, getattr(p, which))
            r = node.param_request("SET", p.id, TYPES[p.type], v)
            assert r.result == 0 and r.value == v, (p.name, which, r)
            assert node.get(p.name) == v, (p.name, which)
    node.restore_defaults()
    assert query_state(node) == STATE["IDLE"]
    fw.stop()


def other_value(p):
    """An in-range value different from the default."""
    v = typed(p, p.max)
    return v if v != typed(p, p.default) else typed(p, p.min)


def test_access_classes(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    node.set("ctrl.mode", 0)
    defaults = {p.name: node.get(p.name) for p in PROTO.params}

    def try_set(p, v):
        return node.param_request("SET", p.id, TYPES[p.type], v)

    def check(state: str) -> None:
        assert query_state(node) == STATE[state]
        for p in PROTO.params:
            cur = defaults[p.name]
            allowed = {"live": True, "stopped": state != "RUNNING", "idle": state in ("IDLE", "FAULT")}[p.access]
            if allowed:
                r = try_set(p, cur)                       # the same value: allowed, nothing moves
                assert r.result == 0 and r.value == cur, (state, p.name, r)
            else:
                r = try_set(p, other_value(p))
                assert r.result == RESULT["STATE"], (state, p.name, r)
                assert r.value == cur, (state, p.name, r)
                assert node.get(p.name) == cur, (state, p.name)
        # the whole set: only with the output inactive
        if state in ("ARMED", "RUNNING"):
            for op in ("SAVE", "RESTORE_DEFAULTS", "LOAD"):
                r = node.param_request(op)
                assert r.result == RESULT["STATE"], (state, op, r)

    rig = arm(node, settle_ticks=2)
    check("ARMED")
    assert node.start().result == 0
    rig.tick(host_heartbeat=True)
    check("RUNNING")
    # a live parameter really changes while RUNNING; a stopped one does not
    assert node.set("ctrl.openloop_u", 5.0) == 5.0
    assert node.set("telem.decimation", 3) == 3
    r = try_set(PROTO.param("pid.kp"), 1.0)
    assert r.result == RESULT["STATE"] and node.get("pid.kp") == defaults["pid.kp"]
    node.set("ctrl.openloop_u", defaults["ctrl.openloop_u"])
    node.set("telem.decimation", defaults["telem.decimation"])
    node.estop()
    assert fresh_heartbeat(node)["State"] == STATE["FAULT"]
    check("FAULT")
    assert node.clear_faults().state == STATE["IDLE"]
    check("IDLE")
    fw.stop()


def test_changed_flag(firmware, bus) -> None:
    """PARAMS_CHANGED: set by SET, SELECT_* and RESTORE_DEFAULTS, not by a
    refused SET or a GET; cleared by SAVE and LOAD."""
    fw, node = start(firmware, bus, node=NODE)

    def changed() -> bool:
        return bool(fresh_heartbeat(node)["Flags"] & HB_PARAMS_CHANGED)

    assert not changed()
    node.get("ppc.c")
    r = node.param_request("SET", PROTO.param("ppc.c").id, 0, -1.0)   # below min: refused
    assert r.result == RESULT["RANGE"]
    assert not changed()
    node.set("ppc.c", 3.0)
    assert changed()
    node.save()
    assert not changed()
    node.select_controller("PID")
    assert changed()
    node.load()
    assert not changed() and node.get("ctrl.mode") == 1
    node.restore_defaults()
    assert changed()
    fw.stop()


def test_heartbeat_period_follows_restore_defaults(firmware, bus) -> None:
    """sys.heartbeat_ms is *live*: after RESTORE_DEFAULTS brings it back from
    10 s to 100 ms, heartbeats come at the new period, not 10 s later."""
    fw, node = start(firmware, bus, node=NODE)
    node.set("sys.heartbeat_ms", 10000)
    node.wait_for("HEARTBEAT", timeout_s=2.0)       # the one scheduled before the change
    node.restore_defaults()
    assert node.get("sys.heartbeat_ms") == 100
    # Regression (a bug found by this test, now fixed): pma_app_poll keeps the next heartbeat time computed with the old
    # 10 s period (app->next_heartbeat_us); only a SET of sys.heartbeat_ms
    # pulls it in, not RESTORE_DEFAULTS or LOAD.
    node.wait_for("HEARTBEAT", timeout_s=3.0)
    fw.stop()
