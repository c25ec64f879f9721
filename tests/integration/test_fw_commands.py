# SPDX-License-Identifier: Apache-2.0
"""Every COMMAND in every state it can meet (ACK Result and State, then the
heartbeat), the ESTOP / ESTOP_ALL frames (any DLC) from IDLE, ARMED and
RUNNING, and two nodes on one bus (commands to one leave the other alone,
ESTOP_ALL stops both)."""
from __future__ import annotations

import pytest
from test_fw_lib import (
    CMD,
    COUNTS_MID,
    FAULT,
    PROTO,
    STATE,
    Rig,
    arm,
    arm_and_start,
    base_id,
    cm_to_counts,
    default_of,
    fresh_heartbeat,
    query_state,
    replies_of,
    sentinel_get,
    start,
)

NODE = 3


def fast(node) -> None:
    """Heartbeats every 10 ms, so that checking them costs little."""
    node.set("sys.heartbeat_ms", 10)


def expect(node, command: str | int, arg: int, result: str, state: str, fault: str | None = None) -> None:
    """COMMAND -> COMMAND_ACK with result and state; the next heartbeat agrees."""
    ack = node.command(command, arg, check=False)
    code = CMD[command] if isinstance(command, str) else command
    assert (ack.command, ack.arg) == (code, arg)
    assert PROTO.status_name(ack.result) == result, (command, arg, ack)
    assert PROTO.state_names[ack.state] == state, (command, arg, ack)
    hb = fresh_heartbeat(node)
    assert PROTO.state_names[hb["State"]] == state, hb
    want_fault = fault if fault is not None else ("NONE" if state != "FAULT" else None)
    if want_fault is not None:
        assert PROTO.fault_names[hb["FaultCode"]] == want_fault, hb


def test_commands_in_idle(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    fast(node)
    expect(node, "ARM", 0, "NOT_READY", "IDLE")           # no sample yet
    expect(node, "DISARM", 0, "OK", "IDLE")
    expect(node, "START", 0, "STATE", "IDLE")
    expect(node, "STOP", 0, "STATE", "IDLE")
    expect(node, "CLEAR_FAULTS", 0, "OK", "IDLE")         # harmless without a fault
    for mode in range(5):
        expect(node, "SELECT_CONTROLLER", mode, "OK", "IDLE")
        assert fresh_heartbeat(node)["Controller"] == mode
        assert node.get("ctrl.mode") == mode
    for bad in (5, 9, 255):
        expect(node, "SELECT_CONTROLLER", bad, "RANGE", "IDLE")
    assert node.get("ctrl.mode") == 4
    for kind in range(7):
        expect(node, "SELECT_REFERENCE", kind, "OK", "IDLE")
        assert fresh_heartbeat(node)["Reference"] == kind
    for bad in (7, 200):
        expect(node, "SELECT_REFERENCE", bad, "RANGE", "IDLE")
    assert node.get("ref.kind") == 6
    for unknown in (0, 10, 11, 128, 255):
        expect(node, unknown, 0, "UNKNOWN_COMMAND", "IDLE")
        expect(node, unknown, 7, "UNKNOWN_COMMAND", "IDLE")

    # ARM needs a valid position inside the limits, and consistent parameters
    rig = Rig(node)
    rig.tick(700)                                             # below adc.wire_break_below_counts
    expect(node, "ARM", 0, "WIRE_BREAK", "IDLE")
    rig.tick(760)                                             # wire break < 760 < adc.raw_min_counts
    expect(node, "ARM", 0, "RANGE", "IDLE")
    rig.tick(4095)                                            # above adc.raw_max_counts
    expect(node, "ARM", 0, "RANGE", "IDLE")
    rig.tick(cm_to_counts(1.0))                               # x = 1 cm > x_max + margin
    expect(node, "ARM", 0, "RANGE", "IDLE")
    rig.tick(COUNTS_MID)
    node.set("ctrl.u_min", 500.0)                             # u_min >= u_max: a cross rule
    expect(node, "ARM", 0, "RANGE", "IDLE")
    node.set("ctrl.u_min", default_of("ctrl.u_min"))
    node.set("act.p0_kpa", 700.0)                             # p0 above act.p_max_kpa
    expect(node, "ARM", 0, "RANGE", "IDLE")
    node.set("act.p0_kpa", 300.0)
    expect(node, "ARM", 0, "OK", "ARMED")
    expect(node, "DISARM", 0, "OK", "IDLE")
    expect(node, "ESTOP", 0, "OK", "FAULT", "ESTOP")
    fw.stop()


def test_commands_in_armed(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    fast(node)
    node.set("ctrl.mode", 0)
    rig = arm(node)
    expect(node, "ARM", 0, "OK", "ARMED")
    expect(node, "STOP", 0, "OK", "ARMED")
    expect(node, "CLEAR_FAULTS", 0, "OK", "ARMED")
    expect(node, "SELECT_CONTROLLER", 3, "OK", "ARMED")
    expect(node, "SELECT_CONTROLLER", 5, "RANGE", "ARMED")
    expect(node, "SELECT_REFERENCE", 1, "OK", "ARMED")
    expect(node, "SELECT_REFERENCE", 7, "RANGE", "ARMED")
    expect(node, 0, 0, "UNKNOWN_COMMAND", "ARMED")
    expect(node, 200, 1, "UNKNOWN_COMMAND", "ARMED")
    assert rig.tick()["OutputActive"] == 1
    expect(node, "DISARM", 0, "OK", "IDLE")
    assert rig.tick()["OutputActive"] == 0
    expect(node, "ARM", 0, "OK", "ARMED")
    # START refused (stays ARMED) when the reference leaves the band
    node.set("ref.kind", 0)
    node.set("ref.offset_cm", -5.0)
    expect(node, "START", 0, "BAND", "ARMED")
    node.set("ref.offset_cm", -1.5)
    node.set("ctrl.u_min", 500.0)                             # START checks u_min < u_max too
    expect(node, "START", 0, "RANGE", "ARMED")
    node.set("ctrl.u_min", default_of("ctrl.u_min"))
    expect(node, "START", 0, "OK", "RUNNING")
    expect(node, "STOP", 0, "OK", "ARMED")
    expect(node, "ESTOP", 0, "OK", "FAULT", "ESTOP")
    assert rig.tick()["OutputActive"] == 0
    fw.stop()


def test_commands_in_running(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    fast(node)
    node.set("ctrl.mode", 0)
    rig = arm_and_start(node)
    expect(node, "ARM", 0, "STATE", "RUNNING")
    expect(node, "START", 0, "STATE", "RUNNING")
    expect(node, "CLEAR_FAULTS", 0, "OK", "RUNNING")
    expect(node, "SELECT_CONTROLLER", 1, "STATE", "RUNNING")
    expect(node, "SELECT_CONTROLLER", 9, "RANGE", "RUNNING")  # the range is checked first
    expect(node, "SELECT_REFERENCE", 2, "STATE", "RUNNING")
    expect(node, "SELECT_REFERENCE", 9, "RANGE", "RUNNING")
    assert node.get("ctrl.mode") == 0 and node.get("ref.kind") == 0
    expect(node, 0, 0, "UNKNOWN_COMMAND", "RUNNING")
    expect(node, 77, 0, "UNKNOWN_COMMAND", "RUNNING")
    assert rig.tick(host_heartbeat=True)["OutputActive"] == 1
    expect(node, "STOP", 0, "OK", "ARMED")
    expect(node, "START", 0, "OK", "RUNNING")
    expect(node, "DISARM", 0, "OK", "IDLE")                    # straight to IDLE
    assert rig.tick()["OutputActive"] == 0
    rig.tick()
    expect(node, "ARM", 0, "OK", "ARMED")
    expect(node, "START", 0, "OK", "RUNNING")
    expect(node, "ESTOP", 0, "OK", "FAULT", "ESTOP")
    act = rig.tick()
    assert act["OutputActive"] == 0 and act["DacCounts"] == 0
    fw.stop()


def test_commands_in_fault(firmware, bus) -> None:
    fw, node = start(firmware, bus, node=NODE)
    fast(node)
    rig = arm(node)
    rig.tick(600)                                              # wire break: FAULT in this tick
    assert fresh_heartbeat(node)["FaultCode"] == FAULT["SENSOR_WIRE_BREAK"]
    for command in ("ARM", "DISARM", "START", "STOP"):
        expect(node, command, 0, "FAULT", "FAULT", "SENSOR_WIRE_BREAK")
    expect(node, "ESTOP", 0, "OK", "FAULT", "SENSOR_WIRE_BREAK")   # the first fault stays
    expect(node, "SELECT_CONTROLLER", 2, "OK", "FAULT", "SENSOR_WIRE_BREAK")
    expect(node, "SELECT_REFERENCE", 3, "OK", "FAULT", "SENSOR_WIRE_BREAK")
    expect(node, "SELECT_REFERENCE", 8, "RANGE", "FAULT", "SENSOR_WIRE_BREAK")
    expect(node, 0, 0, "UNKNOWN_COMMAND", "FAULT", "SENSOR_WIRE_BREAK")
    expect(node, 255, 255, "UNKNOWN_COMMAND", "FAULT", "SENSOR_WIRE_BREAK")
    expect(node, "CLEAR_FAULTS", 0, "OK", "IDLE", "NONE")
    # the cause persists: ARM finds it again
    expect(node, "ARM", 0, "WIRE_BREAK", "IDLE")
    rig.tick()
    expect(node, "ARM", 0, "OK", "ARMED")
    fw.stop()


@pytest.mark.parametrize("message", ["ESTOP", "ESTOP_ALL"])
def test_estop_frames_from_every_state(firmware, bus, message) -> None:
    """ESTOP / ESTOP_ALL with DLC 0 and with data: FAULT ESTOP from IDLE,
    ARMED and RUNNING; no reply; the safe output at the next tick."""
    fw, node = start(firmware, bus, node=NODE)
    fast(node)
    node.set("ctrl.mode", 0)
    frame_id = base_id(message) if message == "ESTOP_ALL" else base_id(message) | NODE
    rig = Rig(node)
    for state in ("IDLE", "ARMED", "RUNNING"):
        for data in (b"", b"\x01", bytes(range(8))):
            rig.tick()
            if state in ("ARMED", "RUNNING"):
                assert node.arm().state == STATE["ARMED"]
                assert rig.tick()["OutputActive"] == 1
            if state == "RUNNING":
                assert node.start().state == STATE["RUNNING"]
                assert rig.tick(host_heartbeat=True)["OutputActive"] == 1
            assert query_state(node) == STATE[state]
            node.send_raw(frame_id, data)
            assert not replies_of(sentinel_get(node)), "ESTOP frames are not answered"
            hb = fresh_heartbeat(node)
            assert (PROTO.state_names[hb["State"]], PROTO.fault_names[hb["FaultCode"]]) == ("FAULT", "ESTOP"), \
                (state, data, hb)
            act = rig.tick()
            assert act["OutputActive"] == 0 and act["DacCounts"] == 0, act
            assert node.clear_faults().state == STATE["IDLE"]
    # an ESTOP to another node id, and the reserved ids 0x001..0x00F, are not for this node
    for other in (base_id("ESTOP") | ((NODE + 1) & 0xF), base_id("ESTOP") | 0, NODE, 0x00F):
        if other == frame_id:
            continue
        node.send_raw(other, b"")
    sentinel_get(node)
    assert fresh_heartbeat(node)["State"] == STATE["IDLE"]
    fw.stop()


def test_two_nodes_on_one_bus(firmware, bus, tmp_path) -> None:
    fw1, n1 = start(firmware, bus, node=1, storage=tmp_path / "n1.bin")
    fw2, n2 = start(firmware, bus, node=2, storage=tmp_path / "n2.bin")
    fast(n1)
    fast(n2)
    r1, r2 = Rig(n1), Rig(n2, seq=100)

    # parameters are per node
    n1.set("telem.mask", 7)
    n1.set("ctrl.mode", 0)
    assert n2.get("telem.mask") == 31 and n2.get("ctrl.mode") == 1

    # a sample to node 1 makes a tick of node 1 only
    r1.tick()
    before_n2 = sentinel_get(n2)
    assert not [f for f in before_n2 if f[1] == 2 and f[0] == "PLANT_ACTUATOR"], before_n2

    # ARM / START node 1: node 2 stays IDLE
    assert n1.arm().state == STATE["ARMED"]
    r1.tick()
    assert n1.start().state == STATE["RUNNING"]
    r1.tick(host_heartbeat=True)
    assert query_state(n2) == STATE["IDLE"]
    assert fresh_heartbeat(n2)["State"] == STATE["IDLE"]
    assert r2.tick()["OutputActive"] == 0

    # node 2 armed; ESTOP to node 2 leaves node 1 RUNNING
    assert n2.arm().state == STATE["ARMED"]
    assert r2.tick()["OutputActive"] == 1
    n2.estop()
    hb2 = fresh_heartbeat(n2)
    assert (hb2["State"], hb2["FaultCode"]) == (STATE["FAULT"], FAULT["ESTOP"])
    hb1 = fresh_heartbeat(n1)
    assert (hb1["State"], hb1["FaultCode"]) == (STATE["RUNNING"], FAULT["NONE"])
    assert r1.tick(host_heartbeat=True)["OutputActive"] == 1
    assert n2.clear_faults().state == STATE["IDLE"]
    # a command to node 1 is not answered by node 2
    ack = n1.command("STOP")
    assert ack.state == STATE["ARMED"]
    assert not [f for f in sentinel_get(n2) if f[0] == "COMMAND_ACK" and f[1] == 2]
    assert query_state(n2) == STATE["IDLE"]

    # ESTOP_ALL stops both (node 1 ARMED, node 2 RUNNING)
    r2.tick()
    assert n2.arm().result == 0
    r2.tick()
    n2.set("ctrl.mode", 0)
    assert n2.start().state == STATE["RUNNING"]
    assert r2.tick(host_heartbeat=True)["OutputActive"] == 1
    n1.estop(all_nodes=True)
    for n, r in ((n1, r1), (n2, r2)):
        hb = fresh_heartbeat(n)
        assert (hb["State"], hb["FaultCode"]) == (STATE["FAULT"], FAULT["ESTOP"]), (n.node, hb)
        act = r.tick()
        assert act["OutputActive"] == 0 and act["DacCounts"] == 0
    fw1.stop()
    fw2.stop()


def test_heartbeat_boot_and_counter(firmware, bus) -> None:
    """The first heartbeat after a start says BOOT with Counter 0, POWER_ON;
    then IDLE, Counter +1 per heartbeat; the flags of a fresh lockstep node."""
    fw, node = start(firmware, bus, node=NODE)
    boot = node.boot
    assert (boot["State"], boot["Counter"], boot["FaultCode"]) == (STATE["BOOT"], 0, 0), boot
    assert PROTO._choices("HEARTBEAT", "ResetCause")[boot["ResetCause"]] == "POWER_ON"
    hbs = [node.wait_for("HEARTBEAT", timeout_s=2.0) for _ in range(4)]
    counters = [h["Counter"] for h in hbs]
    assert counters[0] >= 1 and counters == list(range(counters[0], counters[0] + 4)), counters
    for h in hbs:
        assert (h["State"], h["FaultCode"], h["Controller"], h["Reference"]) == (STATE["IDLE"], 0, 1, 0), h
        assert h["Flags"] == 0x0016, hex(h["Flags"])   # PLANT_BRIDGE, LOCKSTEP, PARAMS_DEFAULT
    fw.stop()


def test_restart_re_executes_the_node(firmware, bus) -> None:
    """RESTART: refused with the output active; from IDLE the node answers, then re-executes
    itself (the same process), comes back through BOOT with ResetCause SOFTWARE and the saved
    parameters, the unsaved change gone; from FAULT it comes back IDLE."""
    fw, node = start(firmware, bus, node=NODE)
    pid = fw.proc.pid
    node.set("ppc.c", 7.0)
    node.save()
    node.set("ppc.c", 9.0)                                  # not saved: lost at the restart
    rig = arm(node)
    expect(node, "RESTART", 0, "STATE", "ARMED")
    assert rig.tick()["OutputActive"] == 1                  # still running its output
    node.disarm()
    for before in ("IDLE", "FAULT"):
        if before == "FAULT":
            node.command("ESTOP")
        ack = node.command("RESTART")
        assert PROTO.state_names[ack.state] == before
        boot = node.wait_for("HEARTBEAT", lambda s: s["State"] == STATE["BOOT"], timeout_s=10)
        assert PROTO._choices("HEARTBEAT", "ResetCause")[boot["ResetCause"]] == "SOFTWARE"
        assert boot["Counter"] == 0
        hb = fresh_heartbeat(node)
        assert (hb["State"], hb["FaultCode"]) == (STATE["IDLE"], FAULT["NONE"]), hb
        assert fw.proc.poll() is None and fw.proc.pid == pid
        assert node.get("ppc.c") == 7.0
    assert fw.stop() == 0
    assert fw.output().count("software reset: re-executing") == 2
