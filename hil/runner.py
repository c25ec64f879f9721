# SPDX-License-Identifier: Apache-2.0
"""The HIL runner: a scenario's controllers, each on its own firmware node and its
own simulated rig, driven tick by tick over CAN through the plant bridge.

One lane = one controller = one CAN node (ids 1, 2, ...) = one Rig built from the
same parameters and seed, so the controllers of a scenario see identical plants
and are compared side by side in one run. Per control tick and lane the runner
sends PLANT_SENSOR (the rig's sensor counts, sequence number), waits for the
node's PLANT_ACTUATOR of that sequence number, applies its DAC counts to the rig
and advances the rig by one control period. With pma-fw-host in lockstep mode
the PLANT_SENSOR frame is the node's tick, so simulated time is exact however
slow the bus is. Against a board (real time, --board) the board ticks on its own
timer and answers every tick, so its answers pace the runner: the next sample
goes out as soon as the last one's answer is in, well before the board's next
tick while the runner keeps up. A tick for which the sample still came late uses
the previous sample again (its PLANT_ACTUATOR says REPEATED). The rig lives
through such ticks too (one control period each, under that tick's command) and
the run's time axis counts them, so the rig's time stays the board's and late
samples cost accuracy, not time.

Configuration goes over CAN exactly as a user's would, through the pmactl
client: parameters by name (SET), ARM, START, STOP, DISARM. Everything on the
bus goes to a python-can log (.blf or .asc), the signals to signals.npz, the
figures of merit to summary.json (hil/metrics.py).
"""
from __future__ import annotations

import dataclasses
import math
import sys
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import can

from pmactl import identity
from pmactl.client import NoReply, PmaError, PmaNode, frame_filters
from pmactl.nodedbc import write_node_dbc
from pmactl.rules import RuleError, set_order

from .fw_process import BUILD_HINT, FW_HOST, FirmwareProcess
from .rig import Rig
from .scenario import RULE_PARAMS, Controller, Scenario, protocol
from .summary import PHASE_ARMED, PHASE_IDLE, PHASE_RUNNING, TELEM_FIELDS, LaneResult, Recorder, summarise

REPLY_TIMEOUT_S = 10.0
LOCKSTEP_WATCHDOG_MS = 10000  # pma-fw-host --watchdog-ms for HIL nodes (wall time; see _start_firmware)
LOG_BATCH = 1024              # frames kept before they go to the bus log (and at the end, however the run ends)
TIMED_EVERY = 64              # the benchmark's split of a tick is timed on every 64th tick (4 clock reads)


class ReplyWait:
    """The reply timeout of one tick without a clock read per frame (in the vcan guest a read
    is a system call of about 70 us): bus.recv waits at most the timeout for any frame, and
    the clock is read only after every CLOCK_EVERY frames that were not the reply, so a node
    that keeps talking without answering still times out (after one to two timeouts)."""

    CLOCK_EVERY = 64

    def __init__(self, timeout_s: float) -> None:
        self.timeout_s = timeout_s
        self.frames = 0
        self.deadline: float | None = None

    def over(self, rx: can.Message | None) -> bool:
        """After a bus.recv(timeout_s): True when the tick's wait is over without a reply."""
        if rx is None:
            return True
        self.frames += 1
        if self.frames % self.CLOCK_EVERY:
            return False
        now = time.monotonic()
        if self.deadline is None:
            self.deadline = now + self.timeout_s
        return now > self.deadline
STOP_FILE = "STOP"  # created in the output directory: stop the run cleanly (Ctrl-C from outside the guest)
BOARD_HEARTBEAT_WAIT_S = 10.0   # --board: how long to wait for the board's first heartbeat
SAMPLE_REPEATED = 1     # PLANT_ACTUATOR.Sample: the tick used the previous sample again (DBC)


class RunError(RuntimeError):
    """The run could not go on (the firmware died, did not answer, refused)."""


@dataclass
class Lane:
    index: int
    ctrl: Controller
    node: int
    rig: Rig
    client: PmaNode
    params: dict[str, float | int]
    fw: FirmwareProcess | None = None
    seq: int = 0
    host_heartbeat: bool = True
    hb_counter: int = 0
    state: str = "BOOT"
    fault_code: str = "NONE"
    start_result: str = ""
    last_dac: int = 0
    last_active: int = 0
    last_counts: int = 0    # this tick's sample (PLANT_SENSOR RawCounts)
    last_status: int = 0    # this tick's PLANT_ACTUATOR Sample
    repeated_dac: list[int] = field(default_factory=list)   # --board: commands of ticks without a new sample
    repeated_ticks: int = 0                                   # --board: how many, over the run
    telem: dict[str, list[float]] = field(default_factory=dict)
    telem_row: dict[str, float] = field(default_factory=dict)
    telem_frames: list[tuple[str, bytes]] = field(default_factory=list)  # received, not yet decoded
    params_read_back: dict[str, float | int] = field(default_factory=dict)  # every parameter, after configuring
    identity: dict[str, Any] = field(default_factory=dict)  # the node's DEVICE_INFO (pmactl.identity)
    sink: deque[can.Message] | None = None   # while commissioning: the node's frames for its LaneBus
    commissioning: dict[str, Any] | None = None   # what commissioning measured and derived (--commission)
    sensor_id: int = 0      # the frame id of its PLANT_SENSOR (set with the lane)


BUS_DBC = "bus.dbc"     # the DBC of the run's nodes (pmactl.nodedbc), beside the bus log


@dataclass
class RunOptions:
    out: Path
    quick: bool = False
    bus_config: dict[str, Any] = field(default_factory=lambda: {"interface": "socketcan", "channel": "vcan0"})
    board: bool = False             # drive an external node in real time (no pma-fw-host, no lockstep)
    board_node: int = 0              # a fresh board's sys.node_id
    log_format: str = "blf"         # python-can log of the bus: blf or asc
    progress: bool = True
    # how long a node may take to answer (a sample, a parameter, a command) before the run
    # fails: in lockstep a node answers at once, but the vcan guest's one CPU, on a busy
    # host, can hold it back for seconds; a dead node is found at once (_check_alive)
    reply_timeout_s: float = REPLY_TIMEOUT_S
    # run `pmactl commission` on the node of every lane with commission = true before ARM, on
    # that lane's rig over this bus, and run the lane on the derived set (hil/commissioned.py)
    commission: bool = False


class Progress:
    """A one-line progress bar on stderr (a line per 10 % when stderr is not a terminal)."""

    def __init__(self, total: int, label: str, enabled: bool) -> None:
        self.total, self.label, self.enabled = total, label, enabled
        self.tty = sys.stderr.isatty()
        self.t0 = time.monotonic()
        self.last = 0.0
        self.last_decile = -1

    def update(self, done: int, extra: str = "") -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        frac = done / max(self.total, 1)
        if self.tty:
            if now - self.last < 0.25 and done < self.total:
                return
            self.last = now
            bar = "#" * int(frac * 30)
            rate = done / max(now - self.t0, 1e-9)
            eta = (self.total - done) / rate if rate > 0 else 0
            sys.stderr.write(f"\r{self.label} [{bar:<30}] {100 * frac:5.1f}% {rate:6.0f} ticks/s "
                             f"eta {eta:4.0f} s {extra}   ")
            sys.stderr.flush()
            if done >= self.total:
                sys.stderr.write("\n")
        else:
            decile = int(frac * 10)
            if decile != self.last_decile:
                self.last_decile = decile
                print(f"{self.label}: {100 * frac:3.0f}% ({done}/{self.total} ticks, "
                      f"{now - self.t0:.0f} s) {extra}", file=sys.stderr, flush=True)


class Runner:
    def __init__(self, scenario: Scenario, opts: RunOptions) -> None:
        self.sc = scenario
        self.opts = opts
        self.proto = protocol()
        self.out = opts.out
        self.lanes: list[Lane] = []
        self.bus: can.BusABC | None = None
        self.logger: can.Listener | None = None
        self.log_queue: list[can.Message] = []
        self.tick = 0
        self.period_s = 1.0
        self.interrupted = False
        self.errors: list[str] = []
        self.bench: dict[str, float] = {}
        self._dispatch: dict[int, tuple[int, str]] = {}
        # the benchmark's split of a tick, timed on every TIMED_EVERY-th tick only (a clock read
        # is a system call, and in the vcan guest one costs about 70 us): wall time in bus.recv
        # (waiting for the nodes, and receiving) and stepping the rigs and recording
        self.t_recv_s = 0.0
        self.t_rig_s = 0.0
        self.timed_ticks = 0
        # the kernel's receive time of the last frame: the timestamp of the samples sent after
        # it (the bus log's), without a clock read per sample
        self.last_rx_s = time.time()

    # ------------------------------------------------------------- set-up --
    def _open(self) -> None:
        self.out.mkdir(parents=True, exist_ok=True)
        stop = self.out / STOP_FILE
        if stop.exists():
            stop.unlink()
        if not self.opts.board and not FW_HOST.exists():
            raise RunError(f"{FW_HOST} not found: build it first ({BUILD_HINT})")
        cfg = dict(self.opts.bus_config)
        try:
            self.bus = can.Bus(**cfg)
        except (can.CanError, OSError, ImportError, ValueError) as e:
            raise RunError(f"cannot open the CAN bus {cfg}: {e}") from e
        self.logger = can.Logger(str(self.out / f"bus.{self.opts.log_format}"))
        nodes = [self.opts.board_node] if self.opts.board else list(range(1, len(self.sc.controllers) + 1))
        if self.opts.board and len(self.sc.controllers) != 1:
            raise RunError("--board runs one controller at a time: choose it with --controller LABEL")
        needs = self.sc.needs_commissioning()
        if needs and self.opts.board:
            raise RunError(f"lane(s) {', '.join(needs)} take their set from commissioning, which --board does not "
                           "run: commission the board with `pmactl commission --apply`, or choose another lane")
        if needs and not self.opts.commission:
            raise RunError(f"lane(s) {', '.join(needs)} take their set from commissioning: run with --commission")
        msgs = ["PLANT_ACTUATOR", "COMMAND_ACK", "PARAM_RESP", "HEARTBEAT", "TELEM_A", "TELEM_B",
                "TELEM_C", "TELEM_D", "TELEM_E", "DEVICE_INFO"]
        filters: list[dict[str, Any]] = []
        for n in nodes:
            filters += frame_filters(self.proto, msgs, n)
        self.bus.set_filters(filters)  # type: ignore[arg-type]  # python-can takes these dicts
        # the DBC of these nodes beside the bus log: any DBC viewer decodes the log with it
        write_node_dbc(self.out / BUS_DBC, nodes, self.proto)
        rp = self.sc.rig_params()
        for i, (ctrl, node) in enumerate(zip(self.sc.controllers, nodes)):
            client = PmaNode(self.bus, node, self.proto, timeout_s=self.opts.reply_timeout_s)
            client.raw_listeners.append(self._log)
            params = self.sc.node_params(ctrl)
            if self.opts.board:
                # a board samples its ADC unless told to take the rig's samples (only while disarmed)
                params = {"sys.plant_bridge": 1, **params}
            lane = Lane(i, ctrl, node, Rig(rp, seed=self.sc.seed), client, params,
                        sensor_id=self.proto.frame_id("PLANT_SENSOR", node))
            self.lanes.append(lane)
            for name in msgs:
                self._dispatch[self.proto.frame_id(name, node)] = (i, name)
        tick_hz = {float(lane.params.get("sys.tick_hz", self.proto.param("sys.tick_hz").default))
                   for lane in self.lanes}
        if len(tick_hz) != 1:
            raise RunError("all controllers of a scenario must run at the same sys.tick_hz")
        self.period_s = 1.0 / tick_hz.pop()

    def _log(self, msg: can.Message) -> None:
        if self.logger is not None:
            self.log_queue.append(msg)
            if len(self.log_queue) >= LOG_BATCH:
                self._flush_log()

    def _flush_log(self) -> None:
        """The frames kept so far into the bus log: a tick's own frames then cost a list append
        (in the vcan guest the log writer's code, cold after the tick's system calls, costs
        several times more per frame than in a block)."""
        if self.logger is not None:
            for m in self.log_queue:
                self.logger.on_message_received(m)
        self.log_queue.clear()

    def _start_firmware(self) -> None:
        if self.opts.board:
            # the board is already up: its heartbeat says it is on this bus with this node id
            for lane in self.lanes:
                try:
                    self._wait_heartbeat(lane, BOARD_HEARTBEAT_WAIT_S)
                except RunError as e:
                    raise RunError(f"{e}: is the board powered, on this bus at the right bit rate, "
                                   f"and is its sys.node_id {lane.node} (--node)?") from e
            return
        fwdir = self.out / "firmware"
        fwdir.mkdir(exist_ok=True)
        channel = str(self.opts.bus_config.get("channel", "vcan0"))
        for lane in self.lanes:
            store = fwdir / f"node{lane.node}.nvm"
            if store.exists():
                store.unlink()      # every run starts from the defaults and sets what it needs
            # The host port's watchdog counts wall time. In lockstep the control time is the
            # harness's, and four nodes plus the harness on the vcan guest's single CPU can starve
            # one node for over a second under load (a WATCHDOG_RESET in a CI run): 10 s still
            # catches a hung process without resetting a merely slow one.
            lane.fw = FirmwareProcess(fwdir, ["--node", str(lane.node), "--storage", str(store), "--lockstep",
                                              "--watchdog-ms", str(LOCKSTEP_WATCHDOG_MS)],
                                      channel=channel).start()
        for lane in self.lanes:
            self._wait_heartbeat(lane, 10.0)

    def _wait_heartbeat(self, lane: Lane, timeout_s: float) -> dict[str, Any]:
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if lane.fw is not None and lane.fw.proc is not None and lane.fw.proc.poll() is not None:
                raise RunError(f"pma-fw-host (node {lane.node}) exited with status {lane.fw.proc.returncode}:\n"
                               f"{lane.fw.output()}")
            try:
                sig = lane.client.wait_for("HEARTBEAT", timeout_s=0.5)
            except NoReply:
                continue
            self._note_heartbeat(lane, sig)
            return sig
        raise RunError(f"no HEARTBEAT from node {lane.node} within {timeout_s:g} s")

    def _note_heartbeat(self, lane: Lane, sig: dict[str, Any]) -> None:
        lane.state = self.proto.state_names.get(int(sig["State"]), str(sig["State"]))
        lane.fault_code = self.proto.fault_names.get(int(sig["FaultCode"]), str(sig["FaultCode"]))

    def _configure(self) -> None:
        for lane in self.lanes:
            # in an order that keeps every rule a SET enforces (docs/parameters.md: e.g. an
            # 11-bit ADC's adc.raw_min_counts below the default wire-break level needs
            # adc.wire_break_below_counts first); the rules' parameters as the node has them
            try:
                current = {name: lane.client.get(name) for name in RULE_PARAMS}
                order = set_order(current, lane.params)
            except RuleError as e:
                raise RunError(f"node {lane.node} ({lane.ctrl.label}): {e}") from e
            except NoReply as e:
                raise RunError(f"node {lane.node} ({lane.ctrl.label}) does not answer PARAM_REQ: {e}") from e
            for name in order:
                value = lane.params[name]
                try:
                    lane.client.set(name, value)
                except PmaError as e:
                    raise RunError(f"node {lane.node} ({lane.ctrl.label}): {e}") from e
                except NoReply as e:
                    raise RunError(f"node {lane.node} ({lane.ctrl.label}) does not answer PARAM_REQ: {e}") from e
            lane.params_read_back = lane.client.snapshot()
            try:
                lane.identity = identity.device_info(lane.client).as_dict()
            except NoReply as e:
                lane.identity = {"node": lane.node, "error": str(e)}

    # -------------------------------------------------------- commissioning --
    def _commission(self) -> None:
        """--commission: `pmactl commission` on the node of each lane with commission = true,
        one lane at a time, over the bus and on the lane's rig (hil/lane_bus.py), as a user would
        on a freshly wired rig: the node is told only the rig's wiring and the user's limits
        first. The lane then runs on the derived set plus the task's own parameters, on a fresh
        rig of the same parameters and seed, so that every lane of the scenario starts alike."""
        from pmactl.commission import CommissionAborted, Commissioning
        from pmactl.commission_rules import CommissionError

        from .commissioned import task_of, tell_wiring, with_derivation
        from .lane_bus import LaneBus
        from .summary import jsonable
        for lane in self.lanes:
            if not (lane.ctrl.commission and not lane.ctrl.derived):
                continue
            label = lane.ctrl.label
            try:
                tell_wiring(lane.client, self.sc)
            except (RuleError, PmaError, NoReply) as e:
                raise RunError(f"node {lane.node} ({label}): setting its wiring before commissioning: {e}") from e
            bus = LaneBus(self, lane)
            lane.sink = bus.rx
            try:
                for _ in range(max(1, round(self.sc.settle_s / self.period_s))):
                    self.tick_lane(lane)
                # what the node sent before its last settle tick is stale: a heartbeat it sent
                # (on its wall clock) while the wiring was being set may show the sensor before
                # the scalings' first tick, and commissioning starts from the node's status
                bus.rx.clear()
                node = PmaNode(bus, lane.node, self.proto, timeout_s=self.opts.reply_timeout_s, host_heartbeat_s=0.1)
                progress = self._commission_progress(label) if self.opts.progress else None
                result = Commissioning(node, task_of(self.sc, label), progress=progress).run()
            except (CommissionError, CommissionAborted) as e:
                raise RunError(f"commissioning lane {label} (node {lane.node}) refused: {e}") from e
            except (PmaError, NoReply) as e:
                raise RunError(f"commissioning lane {label} (node {lane.node}): {e}") from e
            finally:
                lane.sink = None
                bus.shutdown()
            lane.ctrl = with_derivation(lane.ctrl, result.derivation.params)
            lane.params = self.sc.node_params(lane.ctrl)
            lane.commissioning = jsonable({**result.report(), "control_ticks": bus.ticks})
            lane.rig = Rig(self.sc.rig_params(), seed=self.sc.seed)     # (lane.seq goes on: the node counts it)
            lane.telem, lane.telem_row = {}, {}     # the run's telemetry starts at the run
            lane.telem_frames.clear()
        self.sc = dataclasses.replace(self.sc, controllers=[lane.ctrl for lane in self.lanes])

    @staticmethod
    def _commission_progress(label: str) -> Any:
        last: list[str] = []

        def show(what: str, frac: float) -> None:
            if not last or last[0] != what:
                print(f"commissioning {label}: {what} ({100 * frac:.0f} %)", file=sys.stderr, flush=True)
                last[:] = [what]
        return show

    def tick_lane(self, lane: Lane) -> None:
        """One control tick of one lane, not recorded (commissioning): its rig's sample out, the
        node's command in (its other frames go to the lane's sink), one rig period."""
        assert self.bus is not None
        self._send_sample(lane)
        waited = ReplyWait(self.opts.reply_timeout_s)
        while True:
            rx = self.bus.recv(self.opts.reply_timeout_s)
            if waited.over(rx):
                self._check_alive()
                raise RunError(f"no PLANT_ACTUATOR from node {lane.node} within {self.opts.reply_timeout_s:g} s "
                               "while commissioning")
            got = self._receive(rx) if rx is not None else None
            if got is not None and got[0] is lane and got[1]["Seq"] == lane.seq:
                lane.last_dac = int(got[1]["DacCounts"])
                break
        lane.rig.apply_dac(lane.last_dac)
        lane.rig.step(self.period_s)

    def poll_lane(self, lane: Lane) -> None:
        """The frames already received, every lane's (the node's replies come without a tick;
        `_receive` puts the lane's into its sink)."""
        assert self.bus is not None
        while (msg := self.bus.recv(0)) is not None:
            self._receive(msg)

    def _send_sample(self, lane: Lane) -> int:
        """The lane's next PLANT_SENSOR (sequence number + 1, the rig's sensor counts); returns
        the counts."""
        lane.seq = (lane.seq + 1) & 0xFF
        counts = lane.rig.sensor_counts()
        data = self.proto.encode_raw("PLANT_SENSOR", {"Seq": lane.seq, "RawCounts": counts})
        self.send_frame(can.Message(arbitration_id=lane.sensor_id, data=data,
                                    is_extended_id=False, timestamp=self.last_rx_s, is_rx=False))
        return counts

    def send_frame(self, msg: can.Message) -> None:
        assert self.bus is not None
        self.bus.send(msg)
        self._log(msg)

    # ------------------------------------------------------------- ticking --
    def _tick(self, rec: Recorder, phase: int, run_step: int) -> int:
        """One control tick of every lane: sensor out, actuator in, rig step. Returns how
        many board ticks passed before this sample's (--board; 0 in lockstep): the sample's
        run step is run_step plus those."""
        assert self.bus is not None
        if self.opts.board:
            self._collect_repeats()
        for lane in self.lanes:
            lane.last_counts = self._send_sample(lane)
        pending = {lane.index for lane in self.lanes}
        prev_seq = {lane.index: (lane.seq - 1) & 0xFF for lane in self.lanes}
        timed = self.tick % TIMED_EVERY == 0
        waited = ReplyWait(self.opts.reply_timeout_s)
        while pending:
            if timed:
                t_wait = time.perf_counter()
            rx = self.bus.recv(self.opts.reply_timeout_s)
            if timed:
                self.t_recv_s += time.perf_counter() - t_wait
            if waited.over(rx):
                self._check_alive()
                raise RunError(f"no PLANT_ACTUATOR from node(s) "
                               f"{sorted(self.lanes[i].node for i in pending)} within {self.opts.reply_timeout_s:g} s "
                               f"at tick {self.tick}")
            got = self._receive(rx) if rx is not None else None
            if got is None:
                continue
            lane, sig = got
            i = lane.index
            if self.opts.board and sig["Seq"] == prev_seq[i] and sig["Sample"] == SAMPLE_REPEATED:
                lane.repeated_dac.append(int(sig["DacCounts"]))   # a board tick before this sample's
                continue
            if sig["Seq"] != lane.seq or i not in pending:
                continue
            pending.discard(i)
            lane.last_dac, lane.last_active = int(sig["DacCounts"]), int(sig["OutputActive"])
            lane.last_status = int(sig["Sample"])
        if timed:
            t_rig = time.perf_counter()
        skipped_ticks = 0   # --board: the most board ticks any lane had before this sample's
        for lane in self.lanes:
            rig = lane.rig
            skipped_ticks = max(skipped_ticks, len(lane.repeated_dac))
            step = run_step + len(lane.repeated_dac) if run_step >= 0 else run_step
            for dac in lane.repeated_dac:           # --board: ticks the rig lived through meanwhile
                rig.apply_dac(dac)
                rig.step(self.period_s)
            lane.repeated_ticks += len(lane.repeated_dac)
            lane.repeated_dac.clear()
            rig.apply_dac(lane.last_dac)
            rec.add(lane.index, (lane.last_counts, lane.last_dac, lane.last_active, lane.last_status, phase, step,
                                 rig.x_cm, rig.v_cm_s, rig.p_kpa, rig.p_cmd_kpa, rig.load_mass_kg,
                                 rig.disturbance_force_n))
            rig.step(self.period_s)
        if timed:
            self.t_rig_s += time.perf_counter() - t_rig
            self.timed_ticks += 1
        rec.end_tick()
        self.tick += 1
        return skipped_ticks

    def _collect_repeats(self) -> None:
        """--board, before a sample goes out: the board's PLANT_ACTUATOR frames received
        since the last sample's reply. Those of ticks that used the last sample again
        (REPEATED) are ticks the rig must live through before this sample."""
        assert self.bus is not None
        while (msg := self.bus.recv(0)) is not None:
            got = self._receive(msg)
            if got is None:
                continue
            lane, sig = got
            if sig["Seq"] == lane.seq and sig["Sample"] == SAMPLE_REPEATED:
                lane.repeated_dac.append(int(sig["DacCounts"]))

    def _receive(self, msg: can.Message) -> tuple[Lane, dict[str, Any]] | None:
        """A frame from the bus: logged; a node's PLANT_ACTUATOR is returned with its lane
        (raw signals); its other frames (heartbeat, telemetry, ...) are noted."""
        self._log(msg)
        self.last_rx_s = msg.timestamp
        found = self._dispatch.get(msg.arbitration_id)
        if found is None or msg.is_error_frame or msg.is_remote_frame:
            return None
        i, name = found
        lane = self.lanes[i]
        if name != "PLANT_ACTUATOR":
            if lane.sink is not None:
                lane.sink.append(msg)
            self._other_frame(lane, name, msg)
            return None
        if len(msg.data) != 4:
            return None
        return lane, self.proto.decode("PLANT_ACTUATOR", bytes(msg.data))

    def _other_frame(self, lane: Lane, name: str, msg: can.Message) -> None:
        if name.startswith("TELEM_"):       # decoded after the run (_telemetry): not in the tick
            lane.telem_frames.append((name, bytes(msg.data)))
            return
        try:
            sig = self.proto.decode(name, bytes(msg.data))
        except Exception:       # a frame of the wrong length: the bus log keeps it
            return
        if name == "HEARTBEAT":
            self._note_heartbeat(lane, sig)

    def _telemetry(self, lane: Lane) -> dict[str, list[float]]:
        """The lane's telemetry frames received so far, as signals (TELEM_FIELDS): one row per
        telemetry group (mask 0x1F), a field missing from a group NaN."""
        for name, data in lane.telem_frames:
            try:
                sig = self.proto.decode(name, data)
            except Exception:       # a frame of the wrong length: the bus log keeps it
                continue
            for (m, s), key in TELEM_FIELDS.items():
                if m == name:
                    lane.telem_row[key] = float(sig[s])
            if name == "TELEM_E":      # the last of a telemetry group
                for key in TELEM_FIELDS.values():
                    lane.telem.setdefault(key, []).append(lane.telem_row.get(key, math.nan))
                lane.telem_row = {}
        lane.telem_frames.clear()
        return lane.telem

    def _check_alive(self) -> None:
        for lane in self.lanes:
            if lane.fw is not None and lane.fw.proc is not None and lane.fw.proc.poll() is not None:
                raise RunError(f"pma-fw-host (node {lane.node}) exited with status {lane.fw.proc.returncode}:\n"
                               f"{lane.fw.output()[-4000:]}")

    def _command_all(self, command: str, lanes: list[Lane] | None = None) -> dict[int, str]:
        out = {}
        for lane in lanes or self.lanes:
            ack = lane.client.command(command, check=False)
            out[lane.index] = self.proto.status_name(ack.result)
            lane.state = self.proto.state_names.get(ack.state, str(ack.state))
        return out

    def _host_heartbeats(self) -> None:
        for lane in self.lanes:
            if lane.host_heartbeat:
                lane.client.host_heartbeat(lane.hb_counter)
                lane.hb_counter = (lane.hb_counter + 1) & 0xFF

    def _apply_event(self, action: str, value: float) -> None:
        for lane in self.lanes:
            if lane.rig.apply_event(action, value):
                continue
            if action == "host_heartbeat":
                lane.host_heartbeat = bool(value)

    def _stop_requested(self) -> bool:
        return (self.out / STOP_FILE).exists()

    # ----------------------------------------------------------------- run --
    def run(self) -> dict[str, Any]:
        t_wall0 = time.monotonic()
        sc = self.sc
        duration = sc.duration(self.opts.quick)
        try:
            self._open()
            self._start_firmware()
            self._commission()
            self._configure()
            n_settle = max(1, round(sc.settle_s / self.period_s))
            n_armed = max(1, round(sc.armed_s / self.period_s))
            n_run = max(1, round(duration / self.period_s))
            rec = Recorder(len(self.lanes), n_settle + n_armed + n_run + 10)
            self.rec = rec
            hb_every = max(1, round(0.1 / self.period_s))   # HOST_HEARTBEAT every 100 ms of control time
            self._host_heartbeats()
            for _ in range(n_settle):
                self._tick(rec, PHASE_IDLE, -1)
            try:
                arm = self._command_all("ARM")
            except NoReply as e:
                raise RunError(f"no reply to ARM: {e}") from e
            bad = {self.lanes[i].ctrl.label: r for i, r in arm.items() if r != "OK"}
            if bad:
                raise RunError(f"ARM refused: {bad} (see the rig's idle position and safety.* in docs/hil.md)")
            for k in range(n_armed):
                if k % hb_every == 0:
                    self._host_heartbeats()
                self._tick(rec, PHASE_ARMED, -1)
            try:
                start = self._command_all("START")
            except NoReply as e:
                raise RunError(f"no reply to START: {e}") from e
            for i, r in start.items():
                self.lanes[i].start_result = r
            running = [lane for lane in self.lanes if lane.start_result == "OK"]
            events = list(sc.events)
            progress = Progress(n_run, f"{sc.name} ({', '.join(c.label for c in sc.controllers)})",
                                self.opts.progress)
            t_loop0 = time.monotonic()
            self.t_recv_s = self.t_rig_s = 0.0
            self.timed_ticks = 0
            steps_done = 0
            if running:
                n = 0                   # control ticks since START (a board's may outrun the samples)
                next_hb = 0
                next_progress = 0
                while n < n_run:
                    t = n * self.period_s
                    while events and events[0].t_s <= t + 1e-12:
                        ev = events.pop(0)
                        self._apply_event(ev.action, ev.value)
                    if n >= next_hb:
                        next_hb = n + hb_every
                        self._host_heartbeats()
                        if self._stop_requested():
                            self.interrupted = True
                            break
                    n += 1 + self._tick(rec, PHASE_RUNNING, n)
                    steps_done += 1
                    if n >= next_progress:
                        next_progress = n + 250
                        progress.update(min(n, n_run))
                progress.update(min(n, n_run))
            loop_s = time.monotonic() - t_loop0
            scale = steps_done / self.timed_ticks if self.timed_ticks else math.nan   # timed ticks to all
            recv_s, rig_s = self.t_recv_s * scale, self.t_rig_s * scale
            self.bench = {"run_ticks": steps_done, "lanes": len(self.lanes), "loop_wall_s": loop_s,
                          "ticks_per_s": steps_done / loop_s if loop_s > 0 else math.nan,
                          "node_steps_per_s": steps_done * len(self.lanes) / loop_s if loop_s > 0 else math.nan,
                          "timed_ticks": self.timed_ticks, "recv_wait_s": recv_s, "rig_s": rig_s,
                          "other_s": loop_s - recv_s - rig_s}
            # a few ticks more so that a fault found in the last tick shows in the heartbeat
            for _ in range(5):
                self._tick(rec, PHASE_RUNNING, -2)
            for lane in self.lanes:
                self._wait_heartbeat(lane, 3.0)
            final = {lane.index: (lane.state, lane.fault_code, lane.last_dac, lane.last_active) for lane in self.lanes}
        except KeyboardInterrupt:
            self.interrupted = True
            final = {lane.index: (lane.state, lane.fault_code, lane.last_dac, lane.last_active) for lane in self.lanes}
        except RunError as e:
            self.errors.append(str(e))
            final = {lane.index: (lane.state, lane.fault_code, lane.last_dac, lane.last_active) for lane in self.lanes}
        finally:
            self._shutdown()
        summary = self._summarise(final, duration, time.monotonic() - t_wall0)
        return summary

    def _shutdown(self) -> None:
        """STOP and DISARM every node that is still active, stop the firmware
        processes (SIGTERM, exit status checked), close the log and the bus."""
        for lane in self.lanes:
            try:
                if lane.state in ("RUNNING",):
                    lane.client.command("STOP", check=False)
                if lane.state in ("RUNNING", "ARMED"):
                    lane.client.command("DISARM", check=False)
            except (NoReply, can.CanError, OSError) as e:
                self.errors.append(f"node {lane.node}: stopping: {e}")
        for lane in self.lanes:
            if lane.fw is not None:
                try:
                    lane.fw.stop(expect_status=0)
                except AssertionError as e:
                    self.errors.append(f"node {lane.node}: {e}")
        if self.logger is not None:
            self._flush_log()
            self.logger.stop()
            self.logger = None
        if self.bus is not None:
            self.bus.shutdown()
            self.bus = None

    # ------------------------------------------------------------- results --
    def _summarise(self, final: dict[int, tuple[str, str, int, int]], duration: float,
                   wall_s: float) -> dict[str, Any]:
        rec: Recorder | None = getattr(self, "rec", None)
        lanes = []
        for lane in self.lanes:
            state, fault, dac, active = final.get(lane.index, (lane.state, lane.fault_code, 0, 0))
            lanes.append(LaneResult(
                ctrl=lane.ctrl, node=lane.node, rig=lane.rig, params=lane.params,
                params_read_back=lane.params_read_back, state=state, fault_code=fault,
                start_result=lane.start_result, final_dac=dac, final_active=active,
                data=rec.trimmed(lane.index) if rec is not None and rec.n > 0 else None,
                telem=self._telemetry(lane),
                repeated_ticks=lane.repeated_ticks if self.opts.board else None))
        return summarise(self.sc, lanes, quick=self.opts.quick, duration_s=duration, period_s=self.period_s,
                         errors=self.errors, interrupted=self.interrupted, benchmark=self.bench, wall_s=wall_s,
                         out=self.out, extra={"bus_log": f"bus.{self.opts.log_format}", "bus_dbc": BUS_DBC,
                                                "signals": "signals.npz",
                                                "identity": {ln.ctrl.label: ln.identity for ln in self.lanes},
                                                **({"commissioning": {ln.ctrl.label: ln.commissioning
                                                                      for ln in self.lanes if ln.commissioning}}
                                                   if any(ln.commissioning for ln in self.lanes) else {})})
