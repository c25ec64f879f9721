# SPDX-License-Identifier: Apache-2.0
"""pmactl (the installed program, in a subprocess) against pma-fw-host over vcan0.

    hil/with-vcan .venv/bin/python -m pytest host/tests/integration -q
"""
from __future__ import annotations

import csv
import json
import math
import signal
import subprocess
import threading
from pathlib import Path

import can
import pytest
from fwhost import CHANNEL, PMACTL, REPLY_TIMEOUT_S

from pmactl.protocol import load_protocol

PROTO = load_protocol()
TIMEOUT = f"{REPLY_TIMEOUT_S:g}"      # pmactl --timeout of the programs started here (fwhost.py)
# pmactl scan listens this long (wall time) for heartbeats (every 100 ms of wall time): long
# enough for a node that waits for the CPU now and then on a loaded machine
REPO = Path(__file__).resolve().parents[3]
SCAN_S = "2"
# safety.host_timeout_ms in control ticks (sys.tick_hz 1000, lockstep: one tick per plant sample)
HOST_TIMEOUT_TICKS = int(PROTO.param("safety.host_timeout_ms").default)


def rows_of(out: str) -> dict[str, list[str]]:
    """params list output: name -> cells."""
    return {line.split()[1]: line.split() for line in out.splitlines()[1:] if line.strip()[:1].isdigit()}


def test_scan_status_and_parameters(firmware, pmactl, tmp_path: Path) -> None:
    firmware(node=3)
    r = pmactl("scan", "--seconds", SCAN_S)
    assert r.code == 0, r.err
    cells = r.out.splitlines()[1].split()
    assert cells[:5] == ["3", "IDLE", "NONE", "PPC", "HOLD"]
    assert cells[-3:] == ["PLANT_BRIDGE", "LOCKSTEP", "PARAMS_DEFAULT"]
    assert cells[5].startswith((REPO / "VERSION").read_text().strip())   # firmware, then unique id
    assert len(cells[6]) == 24
    r = pmactl("status", node=3)
    assert r.code == 0
    assert "flags        0x0016 PLANT_BRIDGE LOCKSTEP PARAMS_DEFAULT" in r.out
    assert "reset cause  POWER_ON (1)" in r.out

    # every parameter, with the range and default the firmware reports: those of the table
    r = pmactl("params", "list", node=3)
    assert r.code == 0, r.err
    rows = rows_of(r.out)
    assert set(rows) == {p.name for p in PROTO.params}
    for p in PROTO.params:
        cells = rows[p.name]
        assert cells[0] == str(p.id)
        assert cells[2].rstrip("*") == p.text(p.default) == cells[-2], p.name
        assert cells[-1] == p.access
        assert p.text(p.min) in cells and p.text(p.max) in cells, (p.name, cells)

    r = pmactl("params", "set", "ppc.w1_cm", "0.3", node=3)
    assert (r.code, r.out.strip()) == (0, "ppc.w1_cm = 0.3 cm (was 0.2)")
    r = pmactl("params", "set", "ref.kind", "sine", node=3)
    assert (r.code, r.out.strip()) == (0, "ref.kind = SINE (was HOLD)")
    # the firmware's own refusals, with their codes and meanings from the DBC
    r = pmactl("params", "set", "--no-check", "ppc.w1_cm", "300", node=3)
    assert r.code == 1 and "rejected set ppc.w1_cm = 300: RANGE (-3)" in r.err and "stays 0.3" in r.err
    r = pmactl("params", "set", "--no-check", "ppc.t_u_s", "nan", node=3)
    assert r.code == 1 and "NOT_FINITE (-2)" in r.err
    r = pmactl("params", "set", "ppc.t_u_s", "0", node=3)        # checked before sending
    assert r.code == 2 and "outside 0.001..1000 s" in r.err

    assert pmactl("params", "save", node=3).code == 0
    assert pmactl("params", "restore-defaults", node=3).code == 0
    assert pmactl("params", "get", "ppc.w1_cm", "ref.kind", node=3).out.splitlines() == \
        ["ppc.w1_cm = 0.2 cm", "ref.kind = HOLD (0)"]
    assert pmactl("params", "revert", node=3).code == 0
    assert pmactl("params", "get", "ppc.w1_cm", node=3).out.strip() == "ppc.w1_cm = 0.3 cm"

    # dump, edit, load
    path = tmp_path / "node3.json"
    r = pmactl("params", "dump", str(path), node=3)
    assert r.code == 0 and f"{len(PROTO.params)} parameters of node 3" in r.out
    doc = json.loads(path.read_text())
    assert doc["params"]["ppc.w1_cm"] == 0.3 and doc["params"]["ref.kind"] == "SINE"
    doc["params"]["ppc.t_u_s"] = 6
    doc["params"]["ctrl.mode"] = "MFAC"
    path.write_text(json.dumps(doc))
    r = pmactl("params", "load", str(path), node=3)
    assert r.code == 0, r.err
    # sys.node_id is not loaded unless asked (--with-node-id)
    assert f"2 set, {len(PROTO.params) - 3} unchanged, 0 rejected" in r.out
    assert "sys.node_id not loaded" in r.out
    r = pmactl("status", node=3)
    assert "controller   MFAC (2)" in r.out and "PARAMS_CHANGED" in r.out
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"params": {"ppc.t_u_s": -1, "ppc.w9": 1}}))
    r = pmactl("params", "load", str(bad), node=3)
    assert r.code == 5 and "ppc.t_u_s: -1 s is outside" in r.err and "unknown parameter 'ppc.w9'" in r.err
    assert pmactl("params", "get", "ppc.t_u_s", node=3).out.strip() == "ppc.t_u_s = 6 s"


def test_counters(firmware, pmactl) -> None:
    """pmactl counters: every GET_STATUS value by its DBC name, from the firmware."""
    firmware(node=3)
    r = pmactl("counters", node=3)
    assert r.code == 0, r.err
    rows = {line.split()[0]: line.split(None, 1)[1] for line in r.out.splitlines() if line.strip()}
    assert list(rows) == list(PROTO.status_ids)
    assert rows["LAST_RULE"] == "none"
    assert rows["TICKS"] == "0"                      # lockstep, and no sample yet
    assert rows["GUARANTEE_LOST_AT_MS"].startswith("never")
    assert int(rows["FRAMES_RX"]) > 0
    # a SET that a rule refuses: LAST_RULE names it
    r = pmactl("params", "set", "adc.raw_min_counts", "4095", node=3)
    assert r.code == 1
    r = pmactl("counters", "last_rule", node=3)
    assert r.code == 0 and r.out.split()[:2] == ["LAST_RULE", "rule"], r.out


def test_errors_without_a_node(firmware, pmactl) -> None:
    firmware(node=0)
    r = pmactl("status", node=9, reply_timeout_s=2)
    assert r.code == 4 and "no HEARTBEAT from node 9" in r.err
    r = pmactl("params", "get", "ppc.c", node=9, reply_timeout_s=2)
    assert r.code == 4 and "no PARAM_RESP from node 9" in r.err
    r = pmactl("--channel", "vcan7", "status")
    assert r.code == 3 and "cannot open CAN interface socketcan vcan7" in r.err
    r = pmactl("arm")                                           # no sensor sample yet
    assert r.code == 1 and "refused ARM: NOT_READY (-5): no position yet" in r.err


def test_state_commands(firmware, plant, pmactl, tmp_path: Path) -> None:
    firmware(node=0)
    rig = plant(node=0)
    assert pmactl("controller", "pid").out.strip() == "node 0: controller PID (at the next START), state IDLE"
    assert pmactl("reference", "step").code == 0
    r = pmactl("controller")
    assert r.out.startswith("controller PID (ctrl.mode")
    assert pmactl("arm").out.strip() == "node 0: ARM OK, state ARMED"
    # idle-class parameters are refused while the output is active
    r = pmactl("params", "set", "act.p0_kpa", "250")
    assert r.code == 1 and "STATE (-20)" in r.err and "act.p0_kpa stays 300" in r.err
    path = tmp_path / "p.json"
    path.write_text(json.dumps({"params": {"act.p0_kpa": 250, "safety.x_max_cm": 0.5, "pid.kp": 80}}))
    r = pmactl("params", "load", str(path))
    assert r.code == 1
    assert "rejected set act.p0_kpa = 250: STATE (-20)" in r.err
    assert "rejected set safety.x_max_cm = 0.5: STATE (-20)" in r.err
    assert "set pid.kp = 80 input unit/cm (was 100)" in r.out
    r = pmactl("params", "save")
    assert r.code == 1 and "STATE (-20)" in r.err
    r = pmactl("start")
    assert r.code == 0 and r.out.startswith("node 0: START OK, state RUNNING")
    assert "HOST_HEARTBEAT_LOST" in r.out           # the note: nobody sends HOST_HEARTBEAT now ...
    rig.wait_ticks(HOST_TIMEOUT_TICKS + 100)        # (control time: safety.host_timeout_ms at 1 kHz)
    r = pmactl("status")
    assert "fault        HOST_HEARTBEAT_LOST (10)" in r.out     # ... so the node faulted
    r = pmactl("stop")
    assert r.code == 1 and "refused STOP: FAULT (-23)" in r.err
    assert pmactl("clear-faults").code == 0
    assert pmactl("arm").code == 0
    # with a host heartbeat from a monitor in the background the node keeps RUNNING (the
    # rig waits for the monitor's next heartbeat rather than outrun it: plant.py)
    mon = subprocess.Popen([PMACTL, "--channel", CHANNEL, "--timeout", TIMEOUT, "monitor", "--host-heartbeat",
                            "--seconds", "600"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert mon.stdout is not None
        mon.stdout.readline()                        # "watching ...": the monitor is up
        rig.wait_host_heartbeat()                    # ... and sending
        assert pmactl("start").code == 0
        rig.wait_ticks(3 * HOST_TIMEOUT_TICKS)
        assert "state        RUNNING" in pmactl("status").out
        assert pmactl("stop").out.strip() == "node 0: STOP OK, state ARMED"
        assert pmactl("disarm").out.strip() == "node 0: DISARM OK, state IDLE"
    finally:
        mon.kill()
        mon.communicate()
    r = pmactl("estop")
    assert r.code == 0 and r.out.strip() == "node 0: ESTOP sent, state FAULT (ESTOP)"
    r = pmactl("arm")
    assert r.code == 1 and "FAULT (-23)" in r.err
    r = pmactl("status")
    assert "fault        ESTOP (1)" in r.out
    assert pmactl("clear-faults").out.strip() == "node 0: CLEAR_FAULTS OK, state IDLE"


def test_estop_all(firmware, pmactl) -> None:
    firmware(node=1)
    firmware(node=2)
    r = pmactl("estop", "--all")
    assert r.code == 0, r.err
    assert "node 1: FAULT (ESTOP)" in r.out and "node 2: FAULT (ESTOP)" in r.out
    assert "2 node(s) in FAULT" in r.out


def test_monitor(firmware, plant, pmactl) -> None:
    firmware(node=0)
    # until Ctrl-C (SIGINT), once it has shown the ESTOP; --seconds and the timer only guard
    # against a hang. (env: SIGINT may be ignored here, e.g. in hil/with-vcan's guest, and
    # a program started with SIGINT ignored keeps ignoring it.)
    mon = subprocess.Popen(["env", "--default-signal=INT", PMACTL, "--channel", CHANNEL, "monitor",
                            "--seconds", "600"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    guard = threading.Timer(300, mon.kill)
    guard.start()
    try:
        assert mon.stdout is not None
        lines = [mon.stdout.readline()]              # "watching ...": the monitor is up
        plant(node=0)
        assert pmactl("arm").code == 0
        assert pmactl("estop").code == 0             # (it waits for the FAULT heartbeat)
        for line in mon.stdout:                      # the monitor sees that heartbeat too
            lines.append(line)
            if "state ARMED -> FAULT" in line:
                break
        mon.send_signal(signal.SIGINT)
        rest, err = mon.communicate(timeout=60)
    finally:
        guard.cancel()
        if mon.poll() is None:
            mon.kill()
            mon.communicate()
    out = "".join(lines) + rest
    assert mon.returncode == 0, err
    assert "node 0   IDLE, controller PPC, reference HOLD" in out
    assert "state IDLE -> ARMED" in out
    assert "FAULT ESTOP (1)" in out and "state ARMED -> FAULT" in out
    assert out.splitlines()[-1] == "1 node(s) seen: 0 FAULT (ESTOP)"


# pmactl record stops after --samples rows (control time); its --seconds (wall time) and the
# subprocess timeout are only hang guards, far beyond what a loaded machine needs
RECORD_GUARD = ("--seconds", "300")
RECORD_TIMEOUT_S = 400.0


def read_csv(path: Path) -> tuple[list[str], list[list[float]]]:
    with path.open() as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(c) if c else math.nan for c in row] for row in rows[1:]]


def test_record_and_plot(firmware, plant, pmactl, tmp_path: Path) -> None:
    firmware(node=0)
    rig = plant(node=0)
    assert pmactl("arm").code == 0
    rig.wait_ticks(300)
    out = tmp_path / "run.csv"
    # 400 rows: 4 s of control time (telem.decimation 10 at 1 kHz); --seconds only bounds the
    # wall time (the lockstep plant runs as fast as the machine lets it)
    r = pmactl("record", str(out), "--start", *RECORD_GUARD, "--samples", "400", timeout_s=RECORD_TIMEOUT_S)
    assert r.code == 0, r.err
    assert "recording" in r.err                               # the progress display
    assert "recorded 400 rows" in r.out and "400 samples recorded" in r.out
    assert "incomplete rows 0, lost rows 0" in r.out
    header, rows = read_csv(out)
    assert header[:6] == ["t [s]", "x [cm]", "xr [cm]", "e [cm]", "u [input unit]", "v [cm/s]"]
    assert header[6:8] == ["lambda1 [cm]", "lambda2 [cm/s]"]
    assert len(rows) == 400
    t = [row[0] for row in rows]
    steps = {round(b - a, 3) for a, b in zip(t, t[1:])}
    assert steps == {0.01}                                    # telem.decimation 10 at 1 kHz, none lost
    for row in rows:
        assert row[3] == pytest.approx(row[1] - row[2], abs=1e-5)   # one tick's frames together
        assert all(not math.isnan(c) for c in row)
    assert rows[0][2] == pytest.approx(-1.5)                  # HOLD at ref.offset_cm
    assert abs(rows[-1][3]) < 0.2                             # inside w1 by the end
    msgs = list(can.BLFReader(str(tmp_path / "run.blf")))
    ids = {m.arbitration_id for m in msgs}
    assert {PROTO.frame_id(n, 0) for n in ("TELEM_A", "TELEM_E", "HEARTBEAT", "HOST_HEARTBEAT",
                                           "COMMAND", "COMMAND_ACK")} <= ids
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["controller"] == "PPC" and meta["params"]["ppc.t_u_s"] == 2.0
    assert "node 0: ARMED" in pmactl("scan", "--seconds", SCAN_S).out.replace("   0  ARMED", "node 0: ARMED")
    r = pmactl("plot", str(out))
    assert r.code == 0, r.err
    pngs = [Path(line) for line in r.out.splitlines() if line.endswith(".png")]
    assert len(pngs) == 6 and all(p.read_bytes()[:4] == b"\x89PNG" for p in pngs)
    assert "|e| < w1 = 0.2 cm from t = " in r.out and "RMSTE" in r.out


def test_setpoint_stream(firmware, plant, pmactl, tmp_path: Path) -> None:
    firmware(node=0)
    rig = plant(node=0)
    assert pmactl("params", "set", "ref.rate_cm_s", "0").code == 0      # jump to each set-point
    assert pmactl("reference", "stream").code == 0
    r = pmactl("setpoint", "-1.2")
    assert r.code == 1 and "IDLE with reference STREAM" in r.err
    assert pmactl("arm").code == 0
    rig.wait_ticks(200)
    out = tmp_path / "stream.csv"
    rec = subprocess.Popen([PMACTL, "--channel", CHANNEL, "--timeout", TIMEOUT, "record", str(out), "--start",
                            *RECORD_GUARD, "--samples", "300", "-q"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        rig.wait_state("RUNNING")                    # recording
        rig.wait_ticks(100)                          # 10 rows at the initial value
        rig.pause()                                  # control time stands still: RUNNING, recording
        try:
            r = pmactl("setpoint", "-5")
            assert r.code == 2 and "outside the constraint band (-3, 0) cm" in r.err
            r = pmactl("setpoint", "-1.2")
            assert (r.code, r.out.strip()) == (0, "node 0: set-point -1.2 cm sent"), r.err
        finally:
            rig.resume()
        _, stderr = rec.communicate(timeout=RECORD_TIMEOUT_S)
    finally:
        if rec.poll() is None:
            rec.kill()
            rec.communicate()
    assert rec.returncode == 0, stderr
    _, rows = read_csv(out)
    assert len(rows) == 300
    xr = [row[2] for row in rows]
    # the jump (ref.rate_cm_s 0) while paused: the initial value, then the set-point
    jump = next(i for i, v in enumerate(xr) if v != pytest.approx(-1.5))
    assert jump >= 10 and all(v == pytest.approx(-1.2) for v in xr[jump:]), xr


def test_bring_up_recipes(firmware, plant, pmactl, tmp_path: Path) -> None:
    """docs/tuning.md, bring-up: the OFF controller shows the position at the preset
    pressure; OPEN_LOOP with a positive u moves x up (the polarity check)."""
    firmware(node=0)
    rig = plant(node=0, x_rest_cm=0.0)
    assert pmactl("controller", "off").code == 0
    assert pmactl("arm").code == 0
    rig.wait_ticks(200)
    # docs/tuning.md records for --seconds 2 and 3 at a rig in real time; in lockstep the same
    # control time is --samples 200 and 300 (telem.decimation 10 at 1 kHz)
    r = pmactl("record", "check.csv", "--start", *RECORD_GUARD, "--samples", "200", "-q", cwd=tmp_path,
               timeout_s=RECORD_TIMEOUT_S)
    assert r.code == 0, r.err
    _, rows = read_csv(tmp_path / "check.csv")
    assert len(rows) == 200 and all(abs(row[1]) < 0.1 for row in rows)   # near the equilibrium at p0: x = 0
    assert all(row[4] == 0.0 for row in rows)                 # OFF: u = 0
    assert pmactl("params", "set", "ctrl.openloop_u", "3").code == 0      # plant: x -> +0.3 cm
    assert pmactl("controller", "open_loop").code == 0
    r = pmactl("record", "ol.csv", "--start", *RECORD_GUARD, "--samples", "300", "-q", cwd=tmp_path,
               timeout_s=RECORD_TIMEOUT_S)
    assert r.code == 0, r.err
    _, rows = read_csv(tmp_path / "ol.csv")
    assert len(rows) == 300
    assert rows[0][4] == 3.0 and rows[-1][1] > rows[0][1] + 0.1     # x rises
    assert pmactl("disarm").code == 0
