# SPDX-License-Identifier: Apache-2.0
"""Parameter storage through pma-fw-host --storage: SAVE survives a restart
(and clears the PARAMS_* flags), RESTORE_DEFAULTS and LOAD, and a power cut
at every NVM operation of a SAVE (--test-nvm-cut-after N, a few
--test-nvm-cut-permille values) leaves either the whole old set or the whole
new one, never a mix, never an older set or the defaults."""
from __future__ import annotations

import shutil
import subprocess
import time
from pathlib import Path

import pytest
from test_fw_lib import (
    EXIT_POWER_CUT,
    HB_PARAMS_CHANGED,
    HB_PARAMS_DEFAULT,
    HB_SAVE_FAILED,
    PROTO,
    RESULT,
    STATE,
    arm,
    default_of,
    drain,
    fresh_heartbeat,
    query_state,
    snapshot,
    start,
)

NODE = 4

DEFAULTS = {p.name: default_of(p.name) for p in PROTO.params}

# Parameter sets: every type, the first and the last entry of the stored blob.
SET_A = {"sys.node_id": 5, "telem.decimation": 3, "ppc.c": 3.0, "act.polarity": -1,
         "ref.offset_cm": -1.25, "mfac.rho": 11.5, "dac.max_counts": 4000, "safety.safe_kpa": 10.0}
SET_OLD = {"sys.node_id": 6, "telem.decimation": 4, "ppc.c": 4.0, "act.polarity": 1,
           "ref.offset_cm": -2.25, "mfac.rho": 12.5, "dac.max_counts": 3900, "safety.safe_kpa": 20.0}
SET_B = {"sys.node_id": 7, "telem.decimation": 5, "ppc.c": 5.0, "act.polarity": -1,
         "ref.offset_cm": -0.75, "mfac.rho": 13.5, "dac.max_counts": 3800, "safety.safe_kpa": 30.0}


def full(values: dict) -> dict:
    out = dict(DEFAULTS)
    out.update(values)
    return out


def apply(node, values: dict) -> None:
    for k, v in values.items():
        assert node.set(k, v) == v, k


def test_save_restart_restore_load(firmware, bus, tmp_path) -> None:
    store = tmp_path / "nvm.bin"
    fw, node = start(firmware, bus, node=NODE, storage=store)
    hb = fresh_heartbeat(node)
    assert hb["Flags"] & HB_PARAMS_DEFAULT, "empty storage: the defaults"
    assert node.param_request("LOAD").result == RESULT["NO_RECORD"]
    assert snapshot(node) == DEFAULTS
    apply(node, SET_A)
    assert fresh_heartbeat(node)["Flags"] & HB_PARAMS_CHANGED
    node.save()
    hb = fresh_heartbeat(node)
    assert not hb["Flags"] & HB_PARAMS_CHANGED and not hb["Flags"] & HB_SAVE_FAILED, hex(hb["Flags"])
    fw.stop()

    fw, node = start(firmware, bus, node=NODE, storage=store)
    hb = fresh_heartbeat(node)
    assert not hb["Flags"] & (HB_PARAMS_DEFAULT | HB_PARAMS_CHANGED), hex(hb["Flags"])
    assert snapshot(node) == full(SET_A)
    node.restore_defaults()
    assert snapshot(node) == DEFAULTS
    assert fresh_heartbeat(node)["Flags"] & HB_PARAMS_CHANGED
    node.load()
    assert snapshot(node) == full(SET_A)
    hb = fresh_heartbeat(node)
    assert not hb["Flags"] & (HB_PARAMS_DEFAULT | HB_PARAMS_CHANGED), hex(hb["Flags"])
    # RESTORE_DEFAULTS does not touch the storage
    node.restore_defaults()
    fw.stop()
    fw, node = start(firmware, bus, node=NODE, storage=store)
    assert snapshot(node) == full(SET_A)
    # LOAD after a change brings back the stored set; a second SAVE replaces it
    apply(node, SET_B)
    node.load()
    assert snapshot(node) == full(SET_A)
    apply(node, SET_B)
    node.save()
    fw.stop()
    fw, node = start(firmware, bus, node=NODE, storage=store)
    assert snapshot(node) == full(SET_B)
    fw.stop()


def test_no_storage(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE, storage=False)
    for op in ("SAVE", "LOAD"):
        assert node.param_request(op).result == RESULT["NOT_IMPLEMENTED"], op
    assert node.param_request("RESTORE_DEFAULTS").result == 0
    hb = fresh_heartbeat(node)
    assert hb["Flags"] & HB_PARAMS_DEFAULT
    fw.stop()


def test_whole_set_refused_while_output_active(firmware, bus, tmp_path) -> None:
    fw, node = start(firmware, bus, node=NODE, storage=tmp_path / "s.bin")
    node.set("ppc.c", 9.0)
    node.save()
    node.set("ppc.c", 8.0)
    arm(node, settle_ticks=1)
    for op in ("SAVE", "LOAD", "RESTORE_DEFAULTS"):
        assert node.param_request(op).result == RESULT["STATE"], op
    assert node.get("ppc.c") == 8.0
    assert node.disarm().result == 0
    node.load()
    assert node.get("ppc.c") == 9.0
    fw.stop()


def test_node_id_from_storage(firmware, bus, tmp_path) -> None:
    """sys.node_id takes effect at the next start-up without --node."""
    store = tmp_path / "id.bin"
    fw, node = start(firmware, bus, node=NODE, storage=store)
    node.set("sys.node_id", 11)
    node.save()
    assert query_state(node) == STATE["IDLE"]          # still node NODE until a restart
    fw.stop()
    from conftest import CHANNEL, FW_HOST, WATCHDOG_MS
    drain(bus)
    log = (tmp_path / "noid.log").open("wb")
    proc = subprocess.Popen([str(FW_HOST), "--can", CHANNEL, "--lockstep", "--storage", str(store),
                             "--watchdog-ms", str(WATCHDOG_MS)],
                            stdout=log, stderr=subprocess.STDOUT)
    try:
        from pmactl.client import PmaNode
        n11 = PmaNode(bus, 11, PROTO, timeout_s=2.0)
        n11.wait_for("HEARTBEAT", lambda s: s["State"] == STATE["BOOT"], timeout_s=10)
        assert n11.get("sys.node_id") == 11
        assert query_state(n11) == STATE["IDLE"]
    finally:
        proc.terminate()
        assert proc.wait(10) == 0
        log.close()


# ---------------------------------------------------------------- power cut --

def save_and_maybe_die(fw, node, timeout_s: float = 60.0) -> int | None:
    """Sends SAVE; returns its Result, or None when the process exited first.
    timeout_s is only a guard against a hung process (a save is a few writes)."""
    node.send("PARAM_REQ", {"Op": 2, "Type": 0, "Id": 0, "Reserved": 0, "ValueF32": 0.0})
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        got = node.receive(0.02)
        if got is not None:
            name, nid, sig, _ = got
            if name == "PARAM_RESP" and nid == node.node and sig["Op"] == 2:
                return sig["Result"]
            if name == "HEARTBEAT" and nid == node.node and sig["State"] == STATE["BOOT"]:
                # the watchdog re-executed it (same pid): the SAVE will never be answered
                pytest.fail(f"pma-fw-host restarted during the SAVE:\n{fw.output()}")
        if fw.proc.poll() is not None:
            return None
    pytest.fail(f"SAVE neither answered nor the process ended within {timeout_s:g} s:\n{fw.output()}")


def prepare(firmware, bus, path: Path, sets: list[dict]) -> None:
    fw, node = start(firmware, bus, node=NODE, storage=path)
    for s in sets:
        apply(node, s)
        node.save()
    fw.stop()


def cut_run(firmware, bus, base: Path, work: Path, n: int, permille: int | None,
            allowed: list[dict]) -> bool:
    """One power-cut experiment on a copy of base: SAVE of SET_B with the cut
    after n operations; then a restart without the hook must load one of the
    allowed sets (or SET_B) entirely. Returns whether the save completed."""
    shutil.copyfile(base, work)
    extra = ["--test-nvm-cut-after", str(n)]
    if permille is not None:
        extra += ["--test-nvm-cut-permille", str(permille)]
    fw, node = start(firmware, bus, node=NODE, storage=work, extra=extra)
    apply(node, SET_B)
    result = save_and_maybe_die(fw, node)
    if result is None:
        status = fw.stop(expect_status=None)
        assert status == EXIT_POWER_CUT, (n, permille, status, fw.output())
        assert "power cut" in fw.output()
        completed = False
    else:
        assert result == 0, (n, permille, result)
        fw.stop()
        completed = True
    fw, node = start(firmware, bus, node=NODE, storage=work)
    loaded = snapshot(node)
    hb = node.boot                                 # its Flags tell what the start-up loaded
    fw.stop()
    candidates = [full(s) if s is not None else DEFAULTS for s in allowed] + [full(SET_B)]
    assert loaded in candidates, (
        f"cut after {n} ops (permille {permille}): a mix or an older set loaded: "
        f"{ {k: loaded[k] for k in SET_B} }")
    if completed:
        assert loaded == full(SET_B), (n, permille)
    assert bool(hb["Flags"] & HB_PARAMS_DEFAULT) == (loaded == DEFAULTS), hex(hb["Flags"])
    return completed


def sweep(firmware, bus, base: Path, work: Path, permille: int | None, allowed: list[dict],
          max_ops: int = 200) -> int:
    """Cuts after N = 0, 1, ... operations until the SAVE completes; returns
    that N (the operations of one save), checked one beyond."""
    for n in range(max_ops):
        if cut_run(firmware, bus, base, work, n, permille, allowed):
            assert n > 1, "a save takes at least an erase and a program"
            assert cut_run(firmware, bus, base, work, n + 1, permille, allowed)
            return n
    pytest.fail(f"the save never completed within {max_ops} operations")


@pytest.fixture(scope="module")
def ops_per_save() -> dict:
    return {}


@pytest.mark.parametrize("history", ["empty", "one_record", "two_records"])
def test_power_cut_at_every_operation_of_a_save(firmware, bus, tmp_path, history, ops_per_save) -> None:
    """history: what the storage holds before the interrupted save: nothing
    (then the defaults are a correct outcome), one record (SET_A; the new
    record goes to the other slot), or two (SET_OLD then SET_A: the save
    overwrites SET_OLD's slot, which must never come back)."""
    base = tmp_path / "base.bin"
    sets = {"empty": [], "one_record": [SET_A], "two_records": [SET_OLD, SET_A]}[history]
    prepare(firmware, bus, base, sets)
    allowed = [None] if not sets else [sets[-1]]
    work = tmp_path / "work.bin"
    n = sweep(firmware, bus, base, work, None, allowed)
    ops_per_save[history] = n
    print(f"NVM operations per save: {n}")
    if len(ops_per_save) > 1:
        assert len(set(ops_per_save.values())) == 1, ops_per_save
    if history == "two_records":
        for permille in (0, 999, 1000):
            assert sweep(firmware, bus, base, work, permille, allowed) == n, permille


def test_storage_usable_after_a_power_cut(firmware, bus, tmp_path) -> None:
    """After a cut in the middle of a save, the next save and load work."""
    base = tmp_path / "base.bin"
    prepare(firmware, bus, base, [SET_A])
    work = tmp_path / "work.bin"
    assert not cut_run(firmware, bus, base, work, 3, 500, [SET_A])
    fw, node = start(firmware, bus, node=NODE, storage=work)
    assert snapshot(node) == full(SET_A)
    apply(node, SET_OLD)
    node.save()
    apply(node, SET_B)
    node.load()
    assert snapshot(node) == full(SET_OLD)
    fw.stop()
    fw, node = start(firmware, bus, node=NODE, storage=work)
    assert snapshot(node) == full(SET_OLD)
    fw.stop()
