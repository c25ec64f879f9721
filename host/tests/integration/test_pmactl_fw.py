"""pmactl (the installed program, in a subprocess) against pma-fw-host over vcan0.

    hil/with-vcan .venv/bin/python -m pytest host/tests/integration -q
"""
from __future__ import annotations

import csv
import json
import math
import subprocess
import time
from pathlib import Path

import can
import pytest

from fwhost import CHANNEL, PMACTL
from pmactl.protocol import load_protocol

PROTO = load_protocol()


def rows_of(out: str) -> dict[str, list[str]]:
    """params list output: name -> cells."""
    return {line.split()[1]: line.split() for line in out.splitlines()[1:] if line.strip()[:1].isdigit()}


def test_scan_status_and_parameters(firmware, pmactl, tmp_path: Path) -> None:
    firmware(node=3)
    r = pmactl("scan", "--seconds", "0.5")
    assert r.code == 0, r.err
    assert r.out.splitlines()[1].split() == ["3", "IDLE", "NONE", "PPC", "HOLD", "PLANT_BRIDGE", "LOCKSTEP",
                                             "PARAMS_DEFAULT"]
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
    assert f"2 set, {len(PROTO.params) - 2} unchanged, 0 rejected" in r.out
    r = pmactl("status", node=3)
    assert "controller   MFAC (2)" in r.out and "PARAMS_CHANGED" in r.out
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"params": {"ppc.t_u_s": -1, "ppc.w9": 1}}))
    r = pmactl("params", "load", str(bad), node=3)
    assert r.code == 5 and "ppc.t_u_s: -1 s is outside" in r.err and "unknown parameter 'ppc.w9'" in r.err
    assert pmactl("params", "get", "ppc.t_u_s", node=3).out.strip() == "ppc.t_u_s = 6 s"


def test_errors_without_a_node(firmware, pmactl) -> None:
    firmware(node=0)
    r = pmactl("status", node=9)
    assert r.code == 4 and "no HEARTBEAT from node 9" in r.err
    r = pmactl("params", "get", "ppc.c", node=9)
    assert r.code == 4 and "no PARAM_RESP from node 9" in r.err
    r = pmactl("--channel", "vcan7", "status")
    assert r.code == 3 and "cannot open CAN interface socketcan vcan7" in r.err
    r = pmactl("arm")                                           # no sensor sample yet
    assert r.code == 1 and "refused ARM: NOT_READY (-5): no position yet" in r.err


def test_state_commands(firmware, plant, pmactl, tmp_path: Path) -> None:
    firmware(node=0)
    plant(node=0)
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
    r = pmactl("status")
    assert "fault        HOST_HEARTBEAT_LOST (10)" in r.out     # ... so the node faulted
    r = pmactl("stop")
    assert r.code == 1 and "refused STOP: FAULT (-23)" in r.err
    assert pmactl("clear-faults").code == 0
    assert pmactl("arm").code == 0
    # with a host heartbeat from a monitor in the background the node keeps RUNNING
    mon = subprocess.Popen([PMACTL, "--channel", CHANNEL, "monitor", "--host-heartbeat", "--seconds", "20"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert mon.stdout is not None
    mon.stdout.readline()                            # "watching ...": the monitor is up
    assert pmactl("start").code == 0
    time.sleep(1.0)
    assert "state        RUNNING" in pmactl("status").out
    assert pmactl("stop").out.strip() == "node 0: STOP OK, state ARMED"
    assert pmactl("disarm").out.strip() == "node 0: DISARM OK, state IDLE"
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
    mon = subprocess.Popen([PMACTL, "--channel", CHANNEL, "monitor", "--seconds", "12"],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert mon.stdout is not None
    first = mon.stdout.readline()                    # "watching ...": the monitor is up
    plant(node=0)
    assert pmactl("arm").code == 0
    assert pmactl("estop").code == 0
    out, err = mon.communicate(timeout=30)
    out = first + out
    assert mon.returncode == 0, err
    assert "node 0   IDLE, controller PPC, reference HOLD" in out
    assert "state IDLE -> ARMED" in out
    assert "FAULT ESTOP (1)" in out and "state ARMED -> FAULT" in out
    assert out.splitlines()[-1] == "1 node(s) seen: 0 FAULT (ESTOP)"


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
    r = pmactl("record", str(out), "--start", "--seconds", "4", timeout_s=60)
    assert r.code == 0, r.err
    assert "recording" in r.err                               # the progress display
    assert "incomplete rows 0, lost rows 0" in r.out
    header, rows = read_csv(out)
    assert header[:6] == ["t [s]", "x [cm]", "xr [cm]", "e [cm]", "u [input unit]", "v [cm/s]"]
    assert header[6:8] == ["lambda1 [cm]", "lambda2 [cm/s]"]
    assert len(rows) >= 50
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
    assert "node 0: ARMED" in pmactl("scan", "--seconds", "0.3").out.replace("   0  ARMED", "node 0: ARMED")
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
    rec = subprocess.Popen([PMACTL, "--channel", CHANNEL, "record", str(out), "--start", "--seconds", "8",
                            "-q"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 30
    while (not out.exists() or out.read_text().count("\n") < 20) and time.monotonic() < deadline:
        time.sleep(0.2)                              # RUNNING, recording
    r = pmactl("setpoint", "-5")
    assert r.code == 2 and "outside the constraint band (-3, 0) cm" in r.err
    r = pmactl("setpoint", "-1.2")
    assert (r.code, r.out.strip()) == (0, "node 0: set-point -1.2 cm sent"), r.err
    stdout, stderr = rec.communicate(timeout=60)
    assert rec.returncode == 0, stderr
    _, rows = read_csv(out)
    xr = [row[2] for row in rows]
    assert xr[0] == pytest.approx(-1.5) and xr[-1] == pytest.approx(-1.2)


def test_bring_up_recipes(firmware, plant, pmactl, tmp_path: Path) -> None:
    """docs/tuning.md, bring-up: the OFF controller shows the position at the preset
    pressure; OPEN_LOOP with a positive u moves x up (the polarity check)."""
    firmware(node=0)
    rig = plant(node=0, x_rest_cm=0.0)
    assert pmactl("controller", "off").code == 0
    assert pmactl("arm").code == 0
    rig.wait_ticks(200)
    r = pmactl("record", "check.csv", "--start", "--seconds", "2", "-q", cwd=tmp_path)
    assert r.code == 0, r.err
    _, rows = read_csv(tmp_path / "check.csv")
    assert rows and all(abs(row[1]) < 0.1 for row in rows)   # near the equilibrium at p0: x = 0
    assert all(row[4] == 0.0 for row in rows)                 # OFF: u = 0
    assert pmactl("params", "set", "ctrl.openloop_u", "3").code == 0      # plant: x -> +0.3 cm
    assert pmactl("controller", "open_loop").code == 0
    r = pmactl("record", "ol.csv", "--start", "--seconds", "3", "-q", cwd=tmp_path)
    assert r.code == 0, r.err
    _, rows = read_csv(tmp_path / "ol.csv")
    assert rows[0][4] == 3.0 and rows[-1][1] > rows[0][1] + 0.1     # x rises
    assert pmactl("disarm").code == 0
