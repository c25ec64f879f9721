# SPDX-License-Identifier: Apache-2.0
"""docs/protocol.md is true: its runnable examples, run with can-utils
(cansend, candump) as the client against pma-fw-host, produce the frames the
document shows, and every cell of its state-transition table is what the
firmware answers. The conventions of the examples are in the document
(section "Examples are tests") and in tools/protocol_doc.py, which
parses them; tests/protocol checks the document against the DBC without CAN.

    hil/with-vcan .venv/bin/python -m pytest tests/integration -k protocol_doc
"""
from __future__ import annotations

import shutil
import subprocess
import threading
import time
from pathlib import Path

import cantools
import pytest

from pma_tools import protocol_doc as dx

ROOT = Path(__file__).resolve().parents[2]

NODE = 3
CHANNEL = "vcan0"
RAW_COUNTS = 2948         # about -1.5 cm with the default sensor scaling: inside the limits
REPLY_TIMEOUT_S = 3.0     # for the expected frames of one step
SETTLE_S = 0.15           # then this long for frames that should not come
TOOL_TIMEOUT_S = 10.0


class Candump:
    """`candump vcan0` in the background; every line it prints, as a Frame."""

    def __init__(self, iface: str = CHANNEL) -> None:
        if shutil.which("candump") is None or shutil.which("cansend") is None:
            raise pytest.UsageError("can-utils (candump, cansend) are not installed: apt-get install can-utils")
        argv = ["candump", iface]
        if shutil.which("stdbuf"):
            argv = ["stdbuf", "-oL", *argv]   # a line at a time through the pipe
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.frames: list[dx.Frame] = []
        self.bad: list[str] = []
        self.cond = threading.Condition()
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            with self.cond:
                try:
                    self.frames.append(dx.Frame.parse(line.rstrip("\n")))
                except ValueError:
                    self.bad.append(line)
                self.cond.notify_all()

    def mark(self) -> int:
        with self.cond:
            return len(self.frames)

    def since(self, mark: int) -> list[dx.Frame]:
        with self.cond:
            return list(self.frames[mark:])

    def wait(self, pred, timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        with self.cond:
            while not pred():
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self.cond.wait(left)
            return True

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.thread.join(5)


def match(expected: list[dx.Frame], actual: list[dx.Frame]) -> str | None:
    """None if actual is expected, in order, with nothing else but heartbeats
    the example leaves out; else what is wrong."""
    i = 0
    for f in actual:
        if i < len(expected) and expected[i].matches(f):
            i += 1
        elif not f.is_heartbeat:
            return f"unexpected frame: {f}"
    if i < len(expected):
        return f"missing frame: {expected[i]}"
    return None


def found_all(expected: list[dx.Frame], actual: list[dx.Frame]) -> bool:
    i = 0
    for f in actual:
        if i < len(expected) and expected[i].matches(f):
            i += 1
    return i == len(expected)


def describe(step: dx.Step, got: list[dx.Frame], why: str) -> str:
    want = "\n".join(f"  {f}" for f in step.expected)
    seen = "\n".join(f"  {f}" for f in got) or "  (nothing)"
    return (f"docs/protocol.md line {step.line_no}: $ {step.command}\n{why}\n"
            f"expected:\n{want}\ncandump showed:\n{seen}")


def run_cansend(dump: Candump, step: dx.Step) -> None:
    mark = dump.mark()
    r = subprocess.run(step.argv, capture_output=True, text=True, timeout=TOOL_TIMEOUT_S)
    assert r.returncode == 0, f"line {step.line_no}: {step.command} failed: {r.stderr}"
    dump.wait(lambda: found_all(step.expected, dump.frames[mark:]), REPLY_TIMEOUT_S)
    time.sleep(SETTLE_S)
    got = dump.since(mark)
    why = match(step.expected, got)
    assert why is None, describe(step, got, why)


def run_candump(dump: Candump, step: dx.Step) -> None:
    r = subprocess.run(step.argv, capture_output=True, text=True, timeout=TOOL_TIMEOUT_S)
    assert r.returncode == 0, f"line {step.line_no}: {step.command} failed: {r.stderr}"
    got = [dx.Frame.parse(line) for line in r.stdout.splitlines() if line.strip()]
    ok = len(got) == len(step.expected) and all(e.matches(g) for e, g in zip(step.expected, got))
    assert ok, describe(step, got, "the candump output differs")


def test_protocol_doc_examples(firmware) -> None:
    """Every ```console example of docs/protocol.md, in order, on one node."""
    exs = dx.examples()
    db = cantools.database.load_file(str(dx.DBC))
    covered = dx.example_message_names(exs, {m.frame_id: m.name for m in db.messages})
    assert covered == {m.name for m in db.messages}, "every message needs a runnable example"

    fw, _ = firmware(node=NODE, lockstep=True)  # a fresh storage file: no parameter record
    dump = Candump()
    try:
        # candump is listening once it shows a heartbeat of the node
        assert dump.wait(lambda: any(f.can_id == 0x0A0 + NODE for f in dump.frames), 5.0), \
            "candump shows no heartbeat of the node"
        steps = 0
        for ex in exs:
            for step in ex.steps:
                if step.tool == "cansend":
                    run_cansend(dump, step)
                else:
                    run_candump(dump, step)
                steps += 1
        assert not dump.bad, f"candump lines in an unknown format: {dump.bad[:3]}"
        assert steps >= 40
    finally:
        dump.stop()
    assert fw.proc is not None and fw.proc.poll() is None, f"pma-fw-host ended:\n{fw.output()}"


def test_protocol_doc_transition_table(firmware, proto) -> None:
    """Each cell 'RESULT -> STATE' of the document's transition table is the
    COMMAND_ACK the firmware sends, from a node put into that state."""
    states, rows = dx.transition_table(dx.read_doc())
    commands = proto.commands  # name -> code
    _, node = firmware(node=NODE, lockstep=True)
    act = node.exchange_sample(0, RAW_COUNTS)   # a valid position, so that ARM can succeed
    assert act["Sample"] == 0 and act["OutputActive"] == 0
    ctrl_mode = int(proto.param("ctrl.mode").default)
    ref_kind = int(proto.param("ref.kind").default)

    def enter(state: str) -> None:
        node.command("CLEAR_FAULTS", check=False)
        ack = node.disarm()
        if state in ("ARMED", "RUNNING"):
            ack = node.arm()
        if state == "RUNNING":
            ack = node.start()
        if state == "FAULT":
            ack = node.command("ESTOP")
        assert proto.state_names[ack.state] == state, f"could not enter {state}"

    failures = []
    for head, cells in rows:
        if head.startswith("other"):
            tries = [(0, 0), (max(commands.values()) + 1, 0), (255, 0)]
        else:
            name = dx.unquote(head.split(maxsplit=1)[1])
            arg = {"SELECT_CONTROLLER": ctrl_mode, "SELECT_REFERENCE": ref_kind}.get(name, 0)
            tries = [(commands[name], arg)]
        for state in states:
            want_result, want_state = cells[state]
            for code, arg in tries:
                enter(state)
                ack = node.command(code, arg, check=False)
                got = (proto.status_name(ack.result), proto.state_names[ack.state])
                if code == commands["RESTART"] and ack.result == 0:
                    # footnote [6]: the node restarts; it needs a sample again to ARM
                    node.wait_for("HEARTBEAT", lambda s: proto.state_names[s["State"]] == "BOOT",
                                  timeout_s=10.0)
                    node.heartbeat(timeout_s=10.0)
                    node.exchange_sample(0, RAW_COUNTS)
                if got != (want_result, want_state):
                    failures.append(f"{head} (command {code}, Arg {arg}) in {state}: the document says "
                                    f"{want_result} -> {want_state}, the node answered {got[0]} -> {got[1]}")
    # footnote [5]: an Arg that is not a value is RANGE, also while RUNNING
    for state in states:
        enter(state)
        for name, bad in (("SELECT_CONTROLLER", 200), ("SELECT_REFERENCE", 200)):
            ack = node.command(name, bad, check=False)
            if proto.status_name(ack.result) != "RANGE":
                failures.append(f"{name} {bad} in {state}: {proto.status_name(ack.result)}, not RANGE")
    assert not failures, "\n".join(failures)
