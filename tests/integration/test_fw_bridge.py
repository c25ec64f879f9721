# SPDX-License-Identifier: Apache-2.0
"""The plant bridge: PLANT_ACTUATOR echoes the sample's Seq; Sample NEW / GAP
/ REPEATED / NONE in lockstep and in real time; a duplicate (the same Seq
again) is no new sample; the heartbeat flags of the bridge."""
from __future__ import annotations

import pytest
from test_fw_lib import (
    COUNTS_MID,
    FAULT,
    HB_LOCKSTEP,
    HB_PLANT_BRIDGE,
    HB_SENSOR_VALID,
    PROTO,
    SAMPLE,
    STATE,
    Rig,
    arm,
    fresh_heartbeat,
    frozen,
    query_state,
    replies_until,
    sentinel_get,
    start,
)

NODE = 7


def test_lockstep_seq_echo_gap_and_duplicates(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    hb = fresh_heartbeat(node)
    assert hb["Flags"] & HB_PLANT_BRIDGE and hb["Flags"] & HB_LOCKSTEP
    # lockstep: no sample, no tick, no PLANT_ACTUATOR
    assert not [f for f in sentinel_get(node) if f[0] == "PLANT_ACTUATOR"]

    def ex(seq, counts=COUNTS_MID):
        return node.exchange_sample(seq, counts)

    a = ex(250)
    assert (a["Seq"], a["Sample"]) == (250, SAMPLE["NEW"]), a      # the first sample is new
    for seq in (251, 252, 253, 254, 255, 0, 1):                       # +1 mod 256, also across the wrap
        a = ex(seq)
        assert (a["Seq"], a["Sample"]) == (seq, SAMPLE["NEW"]), a
    a = ex(1)                                                          # duplicate
    assert (a["Seq"], a["Sample"]) == (1, SAMPLE["REPEATED"]), a
    a = ex(3)                                                          # 2 lost
    assert (a["Seq"], a["Sample"]) == (3, SAMPLE["GAP"]), a
    a = ex(4)
    assert (a["Seq"], a["Sample"]) == (4, SAMPLE["NEW"]), a
    a = ex(2)                                                          # backwards: a gap, not a duplicate
    assert (a["Seq"], a["Sample"]) == (2, SAMPLE["GAP"]), a
    a = ex(254)                                                        # far jump
    assert (a["Seq"], a["Sample"]) == (254, SAMPLE["GAP"]), a
    a = ex(0)                                                          # 255 lost across the wrap
    assert (a["Seq"], a["Sample"]) == (0, SAMPLE["GAP"]), a
    a = ex(1)
    assert (a["Seq"], a["Sample"]) == (1, SAMPLE["NEW"]), a
    for _ in range(3):
        a = ex(1)
        assert (a["Seq"], a["Sample"]) == (1, SAMPLE["REPEATED"]), a
    a = ex(2)
    assert (a["Seq"], a["Sample"]) == (2, SAMPLE["NEW"]), a
    fw.stop()


def test_duplicate_does_not_replace_the_sample(firmware, bus) -> None:
    """ARMED: a duplicate carrying a wire-break value is not a new sample:
    the node keeps using the last one (no fault; the command continues)."""
    fw, node = start(firmware, bus, node=NODE)
    rig = arm(node, settle_ticks=3)
    prev = (rig.seq - 1) & 0xFF
    for _ in range(3):
        a = node.exchange_sample(prev, 100)
        assert a["Sample"] == SAMPLE["REPEATED"] and a["OutputActive"] == 1, a
    assert fresh_heartbeat(node)["Flags"] & HB_SENSOR_VALID
    assert query_state(node) == STATE["ARMED"]
    a = rig.tick(100)                                  # a new sample with it: the fault
    assert a["OutputActive"] == 0 and a["Sample"] == SAMPLE["NEW"]
    assert fresh_heartbeat(node)["FaultCode"] == FAULT["SENSOR_WIRE_BREAK"]
    fw.stop()


def test_sensor_valid_flag(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    assert not fresh_heartbeat(node)["Flags"] & HB_SENSOR_VALID          # no sample yet
    rig = Rig(node)
    rig.tick()
    assert fresh_heartbeat(node)["Flags"] & HB_SENSOR_VALID
    rig.tick(100)                                                          # IDLE: no fault, not valid
    hb = fresh_heartbeat(node)
    assert not hb["Flags"] & HB_SENSOR_VALID and hb["State"] == STATE["IDLE"]
    rig.tick(4095)
    assert not fresh_heartbeat(node)["Flags"] & HB_SENSOR_VALID
    rig.tick()
    assert fresh_heartbeat(node)["Flags"] & HB_SENSOR_VALID
    fw.stop()


def collect(node, n: int, timeout_s: float = 5.0) -> list[dict]:
    return [node.wait_for("PLANT_ACTUATOR", timeout_s=timeout_s) for _ in range(n)]


def test_real_time_sample_semantics(firmware, bus) -> None:
    """Real time: one PLANT_ACTUATOR per tick of the node's clock: NONE before
    any sample, NEW for the tick that takes a new sample, REPEATED for the
    ticks after it (same Seq), GAP after lost samples; a duplicate makes no
    NEW."""
    fw, node = start(firmware, bus, node=NODE, lockstep=False)
    hb = fresh_heartbeat(node)
    assert hb["Flags"] & HB_PLANT_BRIDGE and not hb["Flags"] & HB_LOCKSTEP
    node.set("sys.tick_hz", 100)
    pre = collect(node, 3)
    assert all(f["Sample"] == SAMPLE["NONE"] and f["Seq"] == 0 and f["OutputActive"] == 0 for f in pre), pre

    def after(seq: int, counts: int = COUNTS_MID, n: int = 4) -> list[dict]:
        """Sends a sample; the frames from the first one that echoes it."""
        node.sensor_sample(seq, counts)
        first = node.wait_for("PLANT_ACTUATOR", lambda s: s["Seq"] == seq, timeout_s=5)
        return [first] + collect(node, n - 1)

    fr = after(9)
    assert fr[0]["Sample"] == SAMPLE["NEW"], fr
    assert all(f["Sample"] == SAMPLE["REPEATED"] and f["Seq"] == 9 for f in fr[1:]), fr
    fr = after(11)
    assert fr[0]["Sample"] == SAMPLE["GAP"], fr
    assert all(f["Sample"] == SAMPLE["REPEATED"] and f["Seq"] == 11 for f in fr[1:]), fr
    node.sensor_sample(11, COUNTS_MID)                  # a duplicate: no new sample
    fr = collect(node, 4)
    assert all(f["Sample"] == SAMPLE["REPEATED"] and f["Seq"] == 11 for f in fr), fr
    fr = after(12)
    assert fr[0]["Sample"] == SAMPLE["NEW"], fr
    assert all(f["Sample"] == SAMPLE["REPEATED"] for f in fr[1:]), fr
    fw.stop()


def test_real_time_arm_needs_a_fresh_sample(firmware, bus) -> None:
    """Real time: a sample older than safety.sensor_timeout_ticks is no
    position: SENSOR_VALID clears and ARM is refused with NOT_READY (the rig
    is not sending); with a fresh one ARM succeeds."""
    fw, node = start(firmware, bus, node=NODE, lockstep=False)
    node.set("sys.tick_hz", 100)
    # 100 ticks = 1 s: the fresh sample below stays fresh until ARM even on a slow guest
    node.set("safety.sensor_timeout_ticks", 100)
    node.set("safety.max_late_ticks", 1000)
    node.exchange_sample(1, COUNTS_MID, timeout_s=5)
    node.wait_for("PLANT_ACTUATOR", lambda s: s["Sample"] == SAMPLE["REPEATED"], timeout_s=5)
    for _ in range(101):                                  # the node's own ticks: the sample ages
        node.wait_for("PLANT_ACTUATOR", timeout_s=5)
    assert not fresh_heartbeat(node)["Flags"] & HB_SENSOR_VALID
    ack = node.command("ARM", check=False)
    assert PROTO.status_name(ack.result) == "NOT_READY" and ack.state == STATE["IDLE"], ack
    node.exchange_sample(2, COUNTS_MID, timeout_s=5)
    ack = node.command("ARM", check=False)
    assert ack.result == 0 and ack.state == STATE["ARMED"], ack
    fw.stop()


def test_samples_to_other_nodes_make_no_tick(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    for other in (0, 1, 8, 15):
        node.send("PLANT_SENSOR", {"Seq": 1, "RawCounts": COUNTS_MID}, node=other)
    got = sentinel_get(node)
    assert not [f for f in got if f[0] == "PLANT_ACTUATOR"], got
    fw.stop()


def test_one_actuator_per_sample_when_timing_is_reapplied(firmware, bus, tmp_path) -> None:
    """Lockstep: exactly one PLANT_ACTUATOR per PLANT_SENSOR (docs/protocol.md
    "Plant bridge"), also when a request that re-applies the timing
    (RESTORE_DEFAULTS, LOAD, SET sys.tick_hz) reaches the node together with
    the sample (the node is stopped while both are sent)."""
    fw, node = start(firmware, bus, node=NODE, storage=tmp_path / "t.bin")
    node.save()
    rig = Rig(node)
    rig.tick()
    requests = {
        "RESTORE_DEFAULTS": {"Op": 3, "Type": 0, "Id": 0, "Reserved": 0, "ValueF32": 0.0},
        "LOAD": {"Op": 8, "Type": 0, "Id": 0, "Reserved": 0, "ValueF32": 0.0},
        "SET sys.tick_hz": {"Op": 1, "Type": 1, "Id": PROTO.param("sys.tick_hz").id, "Reserved": 0,
                            "ValueU32": 1000},
    }
    frames = []
    sent = {}
    for _ in range(4):
        for what, req in requests.items():
            seq = rig.seq
            sent[seq] = what
            with frozen(fw.proc.pid):
                node.send("PARAM_REQ", req)
                node.sensor_sample(seq, COUNTS_MID)
            rig.seq = (rig.seq + 1) & 0xFF
            frames += replies_until(node, lambda name, nid, s, seq=seq: name == "PLANT_ACTUATOR" and nid == NODE
                                    and s["Seq"] == seq and s["Sample"] == SAMPLE["NEW"])
            frames += sentinel_get(node)
    frames += sentinel_get(node)
    frames += sentinel_get(node)                        # a phantom tick needs no frame: look again
    resp = [s for name, nid, s in frames if name == "PARAM_RESP" and nid == NODE and s["Op"] != 0]
    assert len(resp) == len(sent) and all(r["Result"] == 0 for r in resp), resp
    per_seq = {}
    for name, nid, s in frames:
        if name == "PLANT_ACTUATOR" and nid == NODE:
            per_seq.setdefault(s["Seq"], []).append(PROTO._choices("PLANT_ACTUATOR", "Sample")[s["Sample"]])
    extra = {sent[q]: v for q, v in per_seq.items() if q in sent and v != ["NEW"]}
    # Regression (a bug found by this test, now fixed): hal/portable/linux/linux_can.c
    # pma_linux_can_tick_arm() recounts the tick frames still queued in the RX ring when the application re-starts
    # the tick (pma_app_apply_timing -> pma_hal_tick_start) while handling
    # frames; a sample whose tick pma_hal_tick_wait() has already taken is
    # counted again: a phantom tick (a second PLANT_ACTUATOR, Sample REPEATED).
    assert not extra, extra
    fw.stop()


@pytest.mark.parametrize("depth", [2, 12])
def test_lockstep_queued_samples_each_make_their_own_tick(firmware, bus, depth) -> None:
    """Lockstep: "each received PLANT_SENSOR *is* a control tick" (docs/
    protocol.md "Plant bridge"). Samples that reach the node together (a rig
    that sends ahead, or a busy host: here the node is stopped while they are
    sent) must still give one tick each, computed from that sample: Seq
    echoed, Sample NEW; while ARMED no SENSOR_TIMEOUT."""
    fw, node = start(firmware, bus, node=NODE)
    rig = arm(node, settle_ticks=3)
    seqs = []
    with frozen(fw.proc.pid):
        for _ in range(depth):
            seqs.append(rig.seq)
            node.sensor_sample(rig.seq, COUNTS_MID)
            rig.seq = (rig.seq + 1) & 0xFF
    got = []
    for _ in range(depth):                          # one PLANT_ACTUATOR per sample ...
        got += replies_until(node, lambda name, nid, s: name == "PLANT_ACTUATOR" and nid == NODE)
    got += sentinel_get(node)                       # ... and no more
    got += sentinel_get(node)
    acts = [(s["Seq"], PROTO._choices("PLANT_ACTUATOR", "Sample")[s["Sample"]], s["OutputActive"])
            for name, nid, s in got if name == "PLANT_ACTUATOR" and nid == NODE]
    hb = fresh_heartbeat(node)
    # Regression (a bug found by this test, now fixed): firmware/app/app_step.c pma_app_step()
    # handles up to PMA_APP_RX_PER_STEP (64) received frames before the one tick that tick_wait() granted, so
    # every queued sample but the last is overwritten before any tick uses
    # it: one NEW tick with the last Seq, then REPEATED ticks (and, from
    # safety.sensor_timeout_ticks queued samples on, a SENSOR_TIMEOUT fault
    # although no sample was missing). In lockstep the loop should stop
    # handling frames after this node's first PLANT_SENSOR of the iteration.
    assert acts == [(s, "NEW", 1) for s in seqs], acts
    assert hb["FaultCode"] == FAULT["NONE"], hb
    fw.stop()
