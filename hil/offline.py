# SPDX-License-Identifier: Apache-2.0
"""Offline runs: the real firmware against the simulated rig, without CAN.

The firmware application, its control library and the fake HAL port are built
as one shared library (libpma_offline.so, firmware/targets/offline, preset
host-offline); this module loads it with ctypes and steps it against hil.rig
exactly as the HIL runner steps pma-fw-host --lockstep over CAN: the same
scenario files (hil/scenario.py), the same configuration (every parameter by
name in a PARAM_REQ SET frame, then read back), the same commands (COMMAND
frames), the same tick (a PLANT_SENSOR frame per tick, the PLANT_ACTUATOR
frame's DAC counts to the rig, the rig's RK4 step), the same host heartbeats
and events, and the same summary (hil/summary.py, figures from hil/metrics.py).
Only the transport differs: the frames go through the fake CAN controller of
the same process instead of vcan, so a run takes seconds instead of minutes.

The fake port holds one node per process: the lanes of a scenario run one after
the other (or in worker processes, --jobs), each on a fresh node and rig, as they
run side by side over CAN on identical rigs.

    python -m hil offline case3 --quick
    python -m hil offline case3 --controller ppc --set ppc.c=65 --grid ppc.a_cm_s=8,10,12 --jobs 2
    python -m hil offline case2b --rig load.mass_kg=3.0 --grid rig:sensor.noise_cm=0.001,0.002 --json out.json
"""
from __future__ import annotations

import argparse
import ctypes
import itertools
import json
import math
import multiprocessing
import os
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pmactl.rules import RuleError, set_order

from . import scenario as scn
from .options import NOISE_LIMIT_HELP, OptionError, noise_limit, out_dir, out_file
from .report import print_summary
from .rig import Rig
from .rig_lib import BUILD_HINT as BUILD_HINT  # one preset builds libpma_rig.so and libpma_offline.so
from .rig_lib import open_library
from .rig_params import RigParams, parse_text
from .scenario import RULE_PARAMS, Scenario, ScenarioError, protocol
from .summary import PHASE_ARMED, PHASE_IDLE, PHASE_RUNNING, LaneResult, Recorder, jsonable, summarise

REPO = Path(__file__).resolve().parents[1]
LIB_PATH = Path(os.environ.get("PMA_OFFLINE_LIB",
                               REPO / "build/host-offline/firmware/targets/offline/libpma_offline.so"))
API_VERSION = 3                 # PMA_OFFLINE_API_VERSION in pma_offline.h
# PMA_OFFLINE_ARITH ("f32" or "q16"), where set: the controller slot's arithmetic the library must
# have been built with (a CI stage that means the Q16.16 build and would otherwise run either)
ARITH_ENV = "PMA_OFFLINE_ARITH"
ARITHS = ("f32", "q16")
HOST_HEARTBEAT_PERIOD_S = 0.1   # as the runner: every 100 ms of control time
EXTRA_TICKS = 5                 # as the runner: ticks after the run, so a last-tick fault shows
PMA_OK = 0


class OfflineError(RuntimeError):
    """The library is missing or unusable, or the node did something it never should."""


class ParamError(ValueError):
    """A parameter that cannot be set: unknown name, or refused by the firmware."""


class UnknownParameter(ParamError):
    pass


class ParamRejected(ParamError):
    """The firmware refused a SET; code is its pma_status_t (status its name)."""

    def __init__(self, name: str, value: float, code: int, status: str) -> None:
        super().__init__(f"the firmware refused {name} = {value!r}: {status} ({code})")
        self.name, self.value, self.code, self.status = name, value, code, status


class TickOut(ctypes.Structure):
    """pma_offline_tick_t (pma_offline.h)."""
    _fields_ = [
        ("dac_counts", ctypes.c_uint32), ("seq", ctypes.c_uint32), ("sample_status", ctypes.c_uint32),
        ("output_active", ctypes.c_uint32),
        ("telem_frames", ctypes.c_uint32), ("telem_time_ms", ctypes.c_uint32), ("telem_x_cm", ctypes.c_float),
        ("telem_xr_cm", ctypes.c_float), ("telem_e_cm", ctypes.c_float),
        ("telem_u", ctypes.c_float), ("telem_v_cm_s", ctypes.c_float),
        ("telem_internal1", ctypes.c_float), ("telem_internal2", ctypes.c_float),
        ("telem_pressure_kpa", ctypes.c_float),
        ("telem_ctrl_flags", ctypes.c_uint32), ("telem_breaches", ctypes.c_uint32),
        ("state", ctypes.c_uint32), ("fault", ctypes.c_uint32), ("sensor_status", ctypes.c_int32),
        ("x_cm", ctypes.c_float), ("u", ctypes.c_float), ("p_kpa", ctypes.c_float),
        ("barrier_run", ctypes.c_uint32), ("other_frames", ctypes.c_uint32),
    ]


# TickOut fields of each telemetry frame (bit i: TELEM_A + i) -> names in the recording (TELEM_FIELDS)
_TELEM_BITS: list[tuple[int, list[tuple[str, str]]]] = [
    (0x01, [("telem_time_ms", "time_ms"), ("telem_x_cm", "x_cm")]),
    (0x02, [("telem_xr_cm", "xr_cm"), ("telem_e_cm", "e_cm")]),
    (0x04, [("telem_u", "u"), ("telem_v_cm_s", "v_cm_s")]),
    (0x08, [("telem_internal1", "internal1"), ("telem_internal2", "internal2")]),
    (0x10, [("telem_pressure_kpa", "pressure_kpa"), ("telem_ctrl_flags", "ctrl_flags"),
            ("telem_breaches", "breaches")]),
]
_TELEM_KEYS = [key for _, fields in _TELEM_BITS for _, key in fields]


def _load(path: Path) -> ctypes.CDLL:
    lib = open_library(path, OfflineError)
    u8, u16, i32, dbl = ctypes.c_uint8, ctypes.c_uint16, ctypes.c_int, ctypes.c_double
    sigs: dict[str, tuple[Any, list[Any]]] = {
        "pma_offline_api_version": (i32, []),
        "pma_offline_ctrl_arith": (ctypes.c_char_p, []),
        "pma_offline_init": (i32, [u8]),
        "pma_offline_param_count": (i32, []),
        "pma_offline_param_id": (i32, [ctypes.c_char_p]),
        "pma_offline_param_at": (ctypes.c_char_p, [i32, ctypes.POINTER(u16)]),
        "pma_offline_param_type": (i32, [u16]),
        "pma_offline_param_set": (i32, [u16, dbl, ctypes.POINTER(dbl)]),
        "pma_offline_param_get": (i32, [u16, ctypes.POINTER(dbl)]),
        "pma_offline_command": (i32, [u8, u8, ctypes.POINTER(u8)]),
        "pma_offline_host_heartbeat": (i32, [u8]),
        "pma_offline_tick": (i32, [u16, ctypes.POINTER(TickOut)]),
        "pma_offline_host_queue": (None, [i32]),
        "pma_offline_frame_in": (i32, [u16, u8, ctypes.POINTER(u8)]),
        "pma_offline_loop": (i32, []),
        "pma_offline_frame_out": (i32, [ctypes.POINTER(u16), ctypes.POINTER(u8), ctypes.POINTER(u8)]),
        "pma_offline_host_dropped": (ctypes.c_uint32, []),
        "pma_offline_state": (i32, []),
        "pma_offline_fault": (i32, []),
        "pma_offline_ticks": (ctypes.c_uint64, []),
        "pma_offline_time_us": (ctypes.c_uint64, []),
        "pma_offline_status_name": (ctypes.c_char_p, [i32]),
        "pma_offline_state_name": (ctypes.c_char_p, [i32]),
        "pma_offline_fault_name": (ctypes.c_char_p, [i32]),
    }
    for name, (res, args) in sigs.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    version = lib.pma_offline_api_version()
    if version != API_VERSION:
        raise OfflineError(f"{path}: API version {version}, this module needs {API_VERSION}: rebuild ({BUILD_HINT})")
    want = os.environ.get(ARITH_ENV)
    if want is not None:
        if want not in ARITHS:
            raise OfflineError(f"{ARITH_ENV}={want!r}: one of {', '.join(ARITHS)}")
        have = ctrl_arith(lib)
        if have != want:
            raise OfflineError(f"{path}: its controller slot is {have}, {ARITH_ENV} asks for {want} "
                               f"(the preset host-offline builds f32, host-offline-q16 q16)")
    return lib


def ctrl_arith(lib: ctypes.CDLL | None = None) -> str:
    """The controller slot's arithmetic of the library: "f32" or "q16" (PMA_CTRL_ARITH)."""
    name: bytes = (lib or library()).pma_offline_ctrl_arith()
    return name.decode()


_LIB: ctypes.CDLL | None = None


def library(path: Path | None = None) -> ctypes.CDLL:
    """The loaded libpma_offline.so (loaded once per process: its fake port is static)."""
    global _LIB
    if _LIB is None:
        _LIB = _load(path or LIB_PATH)
    return _LIB


class Node:
    """The one firmware node of this process (libpma_offline.so), reset by start()."""

    def __init__(self, lib: ctypes.CDLL | None = None) -> None:
        self.lib = lib or library()
        self.ids: dict[str, int] = {}
        self.types: dict[int, int] = {}     # id -> 0 f32, 1 u32, 2 i32
        pid = ctypes.c_uint16()
        for i in range(self.lib.pma_offline_param_count()):
            name = self.lib.pma_offline_param_at(i, ctypes.byref(pid))
            self.ids[name.decode()] = pid.value
            self.types[pid.value] = self.lib.pma_offline_param_type(pid.value)
        self.out = TickOut()
        self._out_ref = ctypes.byref(self.out)
        self._value = ctypes.c_double()
        self._value_ref = ctypes.byref(self._value)
        self._state = ctypes.c_uint8()
        self.started = False

    def start(self, node_id: int = 1) -> None:
        """A fresh node: the fake port reset (clock 0), the application started with its defaults."""
        rc = self.lib.pma_offline_init(node_id)
        if rc != PMA_OK:
            raise OfflineError(f"pma_offline_init({node_id}): {self.status_name(rc)}")
        self.started = True

    # ------------------------------------------------------------- names --
    def status_name(self, code: int) -> str:
        """The firmware's name of a status code (PMA_ERR_RANGE, ...)."""
        return str(self.lib.pma_offline_status_name(code).decode())

    def state_name(self, state: int | None = None) -> str:
        return str(self.lib.pma_offline_state_name(self.lib.pma_offline_state() if state is None else state).decode())

    def fault_name(self, fault: int | None = None) -> str:
        return str(self.lib.pma_offline_fault_name(self.lib.pma_offline_fault() if fault is None else fault).decode())

    def param_id(self, key: str | int) -> int:
        """A parameter's id by name (or id); UnknownParameter when the firmware has none."""
        if isinstance(key, int) and not isinstance(key, bool):
            if key not in self.types:
                raise UnknownParameter(f"the firmware has no parameter with id {key}")
            return key
        pid = self.lib.pma_offline_param_id(str(key).encode())
        if pid < 0:
            raise UnknownParameter(f"the firmware has no parameter {key!r} (docs/parameters.md)")
        return int(pid)

    def _typed(self, pid: int, v: float) -> float | int:
        return v if self.types[pid] == 0 else int(v)

    # -------------------------------------------------------- the frames --
    def set(self, key: str | int, value: float) -> float | int:
        """PARAM_REQ SET through the application's frame handler; the value it now has.
        ParamRejected (with the firmware's code) when it refuses, UnknownParameter."""
        pid = self.param_id(key)
        rc = self.lib.pma_offline_param_set(pid, float(value), self._value_ref)
        if rc != PMA_OK:
            raise ParamRejected(str(key), value, rc, self.status_name(rc))
        return self._typed(pid, self._value.value)

    def get(self, key: str | int) -> float | int:
        pid = self.param_id(key)
        rc = self.lib.pma_offline_param_get(pid, self._value_ref)
        if rc != PMA_OK:
            raise OfflineError(f"GET {key}: {self.status_name(rc)}")
        return self._typed(pid, self._value.value)

    def snapshot(self) -> dict[str, float | int]:
        """Every parameter by name, read back with GET (as the runner's summary has them)."""
        return {name: self.get(pid) for name, pid in self.ids.items()}

    def command(self, command: int, arg: int = 0) -> tuple[int, int]:
        """COMMAND frame: (COMMAND_ACK result, state after it)."""
        rc = self.lib.pma_offline_command(command, arg, ctypes.byref(self._state))
        if rc > 0:
            raise OfflineError(f"command {command}: no reply")
        return int(rc), int(self._state.value)

    def host_heartbeat(self, counter: int) -> None:
        rc = self.lib.pma_offline_host_heartbeat(counter & 0xFF)
        if rc != PMA_OK:
            raise OfflineError(f"HOST_HEARTBEAT: {self.status_name(rc)}")

    def tick(self, counts: int) -> TickOut:
        """One tick on a sensor sample (raw counts); what it sent (the same TickOut object each time)."""
        rc = self.lib.pma_offline_tick(counts, self._out_ref)
        if rc != PMA_OK:
            raise OfflineError(f"tick: {self.status_name(rc)}")
        return self.out


# -------------------------------------------------------------------- one lane --
@dataclass
class LaneRun:
    """One lane's result, picklable (a worker process returns it)."""
    index: int
    result: LaneResult
    ticks: int
    run_ticks: int
    loop_wall_s: float
    error: str | None = None
    config_error: str | None = None     # a parameter the firmware refused: nothing ran


def run_lane(sc: Scenario, index: int, quick: bool, force_run: bool = False) -> LaneRun:
    """Controller `index` of the scenario on a fresh node and rig (node id index + 1), stepped as
    the HIL runner steps it over CAN. force_run: the run's ticks even when this lane's START was
    refused (the runner ticks every lane while any lane runs)."""
    ctrl = sc.controllers[index]
    proto = protocol()
    fw = Node()
    node_id = index + 1
    fw.start(node_id)
    rig = Rig(sc.rig_params(), seed=sc.seed)
    params = sc.node_params(ctrl)
    try:
        # in the order the runner sets them over CAN (every rule a SET enforces kept)
        for name in set_order({n: fw.get(n) for n in RULE_PARAMS}, params):
            fw.set(name, params[name])
    except (ParamError, RuleError) as e:
        res = LaneResult(ctrl=ctrl, node=node_id, rig=rig, params=params, params_read_back={},
                         state=fw.state_name(), fault_code=fw.fault_name(), start_result="",
                         final_dac=0, final_active=0, data=None)
        return LaneRun(index, res, 0, 0, 0.0, config_error=f"{ctrl.label}: {e}")
    read_back = fw.snapshot()
    period_s = 1.0 / float(params.get("sys.tick_hz", proto.param("sys.tick_hz").default))
    duration = sc.duration(quick)
    n_settle = max(1, round(sc.settle_s / period_s))
    n_armed = max(1, round(sc.armed_s / period_s))
    n_run = max(1, round(duration / period_s))
    rec = Recorder(1, n_settle + n_armed + n_run + 10)
    data = rec.data[0]
    telem: dict[str, list[float]] = {}
    row: dict[str, float] = {}
    pending: list[float] | None = None      # the last tick's telemetry group: kept once a tick follows
    hb_every = max(1, round(HOST_HEARTBEAT_PERIOD_S / period_s))
    hb_counter = 0
    host_hb = True
    state_names, fault_names = proto.state_names, proto.fault_names
    last = (0, 0)
    error: str | None = None

    def heartbeat() -> None:
        nonlocal hb_counter
        if host_hb:
            fw.host_heartbeat(hb_counter)
            hb_counter = (hb_counter + 1) & 0xFF

    def tick(phase: int, run_step: int) -> None:
        nonlocal pending, last
        k = rec.n
        if pending is not None:          # over CAN a group is received during the next tick
            for key, v in zip(_TELEM_KEYS, pending):
                telem.setdefault(key, []).append(v)
            pending = None
        counts = rig.sensor_counts()
        o = fw.tick(counts)
        data["counts"][k] = counts
        data["dac_counts"][k] = o.dac_counts
        data["output_active"][k] = o.output_active
        data["sample_status"][k] = o.sample_status
        data["phase"][k] = phase
        data["run_step"][k] = run_step
        rig.apply_dac(o.dac_counts)
        data["x_true_cm"][k] = rig.x_cm
        data["v_true_cm_s"][k] = rig.v_cm_s
        data["p_kpa"][k] = rig.p_kpa
        data["p_cmd_kpa"][k] = rig.p_cmd_kpa
        data["load_mass_kg"][k] = rig.load_mass_kg
        data["disturbance_n"][k] = rig.disturbance_force_n
        rig.step(period_s)
        rec.n += 1
        last = (int(o.dac_counts), int(o.output_active))
        frames = o.telem_frames
        if frames:
            for bit, fields in _TELEM_BITS:
                if frames & bit:
                    for attr, key in fields:
                        row[key] = float(getattr(o, attr))
            if frames & 0x10:            # TELEM_E ends a group (as the runner's recording)
                pending = [row.get(key, math.nan) for key in _TELEM_KEYS]
                row.clear()

    start_result = ""
    run_ticks = 0
    loop_s = 0.0
    commands = proto.commands
    try:
        heartbeat()
        for _ in range(n_settle):
            tick(PHASE_IDLE, -1)
        rc, _ = fw.command(commands["ARM"])
        if rc != PMA_OK:
            raise OfflineError(f"ARM refused: {{{ctrl.label!r}: {proto.status_name(rc)!r}}} "
                               "(see the rig's idle position and safety.* in docs/hil.md)")
        for k in range(n_armed):
            if k % hb_every == 0:
                heartbeat()
            tick(PHASE_ARMED, -1)
        rc, _ = fw.command(commands["START"])
        start_result = proto.status_name(rc)
        events = list(sc.events)
        t_loop0 = time.perf_counter()
        if rc == PMA_OK or force_run:
            n = 0
            next_hb = 0
            while n < n_run:
                t = n * period_s
                while events and events[0].t_s <= t + 1e-12:
                    ev = events.pop(0)
                    if ev.action == "host_heartbeat":
                        host_hb = bool(ev.value)
                    else:
                        rig.apply_event(ev.action, ev.value)
                if n >= next_hb:
                    next_hb = n + hb_every
                    heartbeat()
                tick(PHASE_RUNNING, n)
                n += 1
            run_ticks = n
        loop_s = time.perf_counter() - t_loop0
        for _ in range(EXTRA_TICKS):
            tick(PHASE_RUNNING, -2)
    except OfflineError as e:
        error = str(e)
    res = LaneResult(ctrl=ctrl, node=node_id, rig=rig, params=params, params_read_back=read_back,
                     state=state_names.get(fw.lib.pma_offline_state(), "?"),
                     fault_code=fault_names.get(fw.lib.pma_offline_fault(), "?"),
                     start_result=start_result, final_dac=last[0], final_active=last[1],
                     data=rec.trimmed(0) if rec.n > 0 else None, telem=telem)
    return LaneRun(index, res, rec.n, run_ticks, loop_s, error)


# -------------------------------------------------------------------- a scenario --
def _lane_job(job: tuple[Scenario, int, bool, bool]) -> LaneRun:
    return run_lane(*job)


def run_scenarios(variants: list[Scenario], quick: bool, jobs: int = 1,
                  out: Path | None = None) -> list[dict[str, Any]]:
    """Every lane of every variant (in `jobs` worker processes), then one summary per variant
    (written to out/summary.json and out/signals.npz, or out/VARIANT_NN/ for several)."""
    t0 = time.monotonic()
    for sc in variants:
        if sc.needs_commissioning():
            raise ParamError(f"{sc.name}: lane(s) {', '.join(sc.needs_commissioning())} take their set from "
                             "commissioning (hil/commissioned.py: commission, commissioned)")
    todo = [(v, sc, i) for v, sc in enumerate(variants) for i in range(len(sc.controllers))]
    results = _map([(sc, i, quick, False) for _, sc, i in todo], jobs)
    for r in results:
        if r.config_error:
            raise ParamError(r.config_error)
    by_variant: dict[int, list[LaneRun]] = {}
    for (v, _, _), r in zip(todo, results):
        by_variant.setdefault(v, []).append(r)
    # the runner ticks every lane while any lane runs: a refused lane of a variant where
    # another one started gets its run ticks too
    again = [(v, r.index) for v, runs in by_variant.items() if any(r.result.start_result == "OK" for r in runs)
             for r in runs if r.result.start_result not in ("OK", "") and r.error is None]
    if again:
        rerun = _map([(variants[v], i, quick, True) for v, i in again], jobs)
        for (v, i), r in zip(again, rerun):
            by_variant[v] = [r if x.index == i else x for x in by_variant[v]]
    wall_s = time.monotonic() - t0
    summaries = []
    for v, sc in enumerate(variants):
        runs = sorted(by_variant.get(v, []), key=lambda r: r.index)
        errors = [f"{r.result.ctrl.label}: {r.error}" for r in runs if r.error]
        ticks = max((r.run_ticks for r in runs), default=0)
        loop_s = sum(r.loop_wall_s for r in runs)
        period_s = 1.0 / float(runs[0].result.params.get("sys.tick_hz", protocol().param("sys.tick_hz").default)) \
            if runs else 1e-3
        bench = {"run_ticks": ticks, "lanes": len(runs), "loop_wall_s": loop_s,
                 "node_steps_per_s": sum(r.run_ticks for r in runs) / loop_s if loop_s > 0 else math.nan,
                 "simulated_s_per_wall_s": sum(r.run_ticks for r in runs) * period_s / loop_s
                 if loop_s > 0 else math.nan}
        vout = None if out is None else (out if len(variants) == 1 else out / f"variant_{v:02d}")
        summaries.append(summarise(sc, [r.result for r in runs], quick=quick, duration_s=sc.duration(quick),
                                   period_s=period_s, errors=errors, interrupted=False, benchmark=bench,
                                   wall_s=wall_s, out=vout,
                                   extra={"offline": True, "ctrl_arith": ctrl_arith(), "signals": "signals.npz"}))
    return summaries


def _map(jobs_list: list[tuple[Scenario, int, bool, bool]], jobs: int) -> list[LaneRun]:
    if jobs <= 1 or len(jobs_list) <= 1:
        return [_lane_job(j) for j in jobs_list]
    ctx = multiprocessing.get_context("fork")
    with ctx.Pool(min(jobs, len(jobs_list))) as pool:
        return pool.map(_lane_job, jobs_list, chunksize=1)


# -------------------------------------------------------------------- the command --
def parse_value(text: str) -> float | int | str:
    """A number (int when written as one), else the text (an enumeration name such as PPC)."""
    t = text.strip()
    try:
        return int(t)
    except ValueError:
        pass
    try:
        return float(t)
    except ValueError:
        return t


def _assignments(items: list[str] | None, what: str) -> list[tuple[str, str]]:
    out = []
    for item in items or []:
        if "=" not in item:
            raise OptionError(f"{what}: expected NAME=VALUE, got {item!r}")
        k, v = item.split("=", 1)
        if not k.strip() or not v.strip():
            raise OptionError(f"{what}: expected NAME=VALUE, got {item!r}")
        out.append((k.strip(), v.strip()))
    return out


def _set_nested(d: dict[str, Any], path: str, value: Any) -> dict[str, Any]:
    out: dict[str, Any] = json.loads(json.dumps(d))        # a deep copy of plain TOML data
    cur = out
    parts = path.split(".")
    for p in parts[:-1]:
        nxt = cur.get(p)
        if not isinstance(nxt, dict):
            nxt = {}
            cur[p] = nxt
        cur = nxt
    cur[parts[-1]] = value
    return out


@dataclass(frozen=True)
class Override:
    """One firmware parameter or rig value changed by an option: its name, its value (a rig
    value as text is parsed to the parameter's type), and the option as the user wrote it (named
    in errors: "--set ctrl.u_max", "--grid rig:load.bias_force_n")."""
    name: str
    value: Any
    option: str

    def shown(self) -> str:
        return f"{self.option}={self.value}"


def with_overrides(sc: Scenario, fw: list[Override], rig: list[Override]) -> Scenario:
    """The scenario with firmware parameters (for every controller, over everything the file
    sets; ref.* into its [reference]) and rig values (dotted RigParams paths) changed, and checked
    as the file was: each value against its parameter (type, range), the rig's values, and every
    rule between parameters (scenario.check_rules). OptionError naming the option otherwise."""
    proto = protocol()
    reference = dict(sc.reference)
    ctrl_over: dict[str, float | int] = {}
    for o in fw:
        name, value = o.name, o.value
        if name == "ref.kind":
            kind = str(value).upper()
            if kind not in scn.REFERENCE_KINDS:
                raise OptionError(f"{o.option}: {value!r} not one of {', '.join(scn.REFERENCE_KINDS)}")
            reference["kind"] = kind
            continue
        try:
            p = proto.param(name)
        except (KeyError, ValueError) as e:
            raise OptionError(f"{o.option}: the firmware has no such parameter (docs/parameters.md)") from e
        if name == "ctrl.mode":
            raise OptionError(f"{o.option}: a lane's mode is its controller's (choose lanes with --controller)")
        try:
            v = p.check(value)
        except (ValueError, TypeError) as e:
            raise OptionError(f"{o.option}: {_without_name(str(e), name)}") from e
        if name.startswith("ref."):
            reference[name[4:]] = v
        else:
            ctrl_over[name] = v
    rig_data: dict[str, Any] = json.loads(json.dumps(sc.rig))
    for o in rig:
        try:
            value = parse_text(o.name, o.value) if isinstance(o.value, str) else o.value
        except ValueError as e:
            raise OptionError(f"{o.option}: {_without_name(str(e), o.name)}") from e
        rig_data = _set_nested(rig_data, o.name, value)
    try:
        RigParams.from_dict(rig_data)
    except (ValueError, TypeError, KeyError) as e:
        path = getattr(e, "path", None)
        named = [o for o in rig if o.name == path or (path or "").startswith(f"{o.name}[")]
        if named:
            last, msg = named[-1], str(e)
            if msg.startswith(f"{last.name} "):
                msg = msg[len(last.name) + 1:]
            raise OptionError(f"{last.option}: {msg}") from e
        raise OptionError(f"{'/'.join(sorted({o.option.split()[0] for o in rig})) or '--rig'}: {e}") from e
    ctrls = [replace(c, params={**c.params, **ctrl_over}) for c in sc.controllers]
    # a user limit given for every lane is the node's before commissioning too: the pressure range
    # the commissioning sweeps and the band it keeps clear of
    params = {**sc.params, **{k: v for k, v in ctrl_over.items() if k in scn.USER_LIMITS}}
    out = replace(sc, params=params, reference=reference, rig=rig_data, controllers=ctrls)
    if fw or rig:
        given = ", ".join(o.shown() for o in [*fw, *rig])
        try:
            scn.check_rules(given, out)
        except ScenarioError as e:
            raise OptionError(str(e)) from e
    return out


def _without_name(message: str, name: str) -> str:
    """A check's message without its leading "NAME: " (the option already names it)."""
    return message[len(name) + 2:] if message.startswith(f"{name}: ") else message


@dataclass
class Variant:
    label: str
    scenario: Scenario
    settings: dict[str, Any] = field(default_factory=dict)


def build_variants(sc: Scenario, sets: list[tuple[str, str]], rigs: list[tuple[str, str]],
                   grids: list[str] | None) -> list[Variant]:
    """One scenario per combination of the --grid values, each with --set and --rig on top and
    checked as a whole (with_overrides); OptionError naming the option that is wrong."""
    axes: list[tuple[str, list[tuple[str, Any]]]] = []      # name, [(text, parsed value)]
    for g in grids or []:
        if "=" not in g:
            raise OptionError(f"--grid: expected NAME=V1,V2,..., got {g!r}")
        name, vals = g.split("=", 1)
        values = [(v.strip(), parse_value(v)) for v in vals.split(",") if v.strip()]
        name = name.strip()
        if not name or not values:
            raise OptionError(f"--grid: expected NAME=V1,V2,..., got {g!r}")
        if name == "seed":
            for _, v in values:
                _seed("--grid seed", v)
        elif name.startswith("rig:") and not name[4:]:
            raise OptionError(f"--grid: expected rig:PATH=V1,V2,..., got {g!r}")
        axes.append((name, values))
    base_fw = [Override(k, parse_value(v), f"--set {k}") for k, v in sets]
    base_rig = [Override(k, v, f"--rig {k}") for k, v in rigs]
    out = []
    for combo in itertools.product(*[vals for _, vals in axes]) if axes else [()]:
        fw, rg = list(base_fw), list(base_rig)
        settings: dict[str, Any] = {}
        seed = sc.seed
        for (name, _), (text, v) in zip(axes, combo):
            if name == "seed":
                seed = _seed("--grid seed", v)
            elif name.startswith("rig:"):
                rg.append(Override(name[4:], text, f"--grid {name}"))
            else:
                fw.append(Override(name, v, f"--grid {name}"))
            settings[name] = v
        label = " ".join(f"{k}={v}" for k, v in settings.items())
        out.append(Variant(label, replace(with_overrides(sc, fw, rg), seed=seed), settings))
    return out


def _seed(option: str, value: Any) -> int:
    try:
        return scn.check_seed(option, value)
    except ScenarioError as e:
        raise OptionError(str(e)) from e


def sweep_table(variants: list[Variant], summaries: list[dict[str, Any]]) -> str:
    """One row per variant and controller: RMSTE per window and the main figures."""
    from .report import _f, _table
    windows = summaries[0]["windows"] if summaries else []
    head = ["variant", "controller"] + [f"{a:g}-{b:g} s" for a, b in windows] + \
        ["max|e| >t_u", "breaches >t_u", "TV p kPa/s", "chatter", "state / fault"]
    rows = []
    for var, s in zip(variants, summaries):
        for label, c in s["controllers"].items():
            r = [var.label or "-", label] + [_f(v, ".6f") for v in c.get("rmste_cm", [None] * len(windows))]
            r += [_f(c.get("max_abs_error_after_tu_cm")), _f(c.get("barrier_breaches_after_tu")),
                  _f(c.get("tv_pressure_cmd_kpa_per_s"), ".1f"), _f(c.get("chatter_ratio"), ".2f"),
                  f"{s['state'].get(label)} / {s['fault_code'].get(label)}"
                  + ("" if s["start_result"].get(label) in ("OK", None) else f" (START {s['start_result'][label]})")]
            rows.append(r)
    return _table(head, rows)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help="a name from `python -m hil list` or a .toml path")
    p.add_argument("--quick", action="store_true", help="the scenario's short variant (quick_duration_s)")
    p.add_argument("--duration", type=float, metavar="S", help="control time after START [s] (default: the scenario's)")
    p.add_argument("--controller", action="append", metavar="LABEL", help="run only this controller (repeatable)")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="firmware parameter for every controller, over the scenario's (repeatable; ref.* "
                        "changes the reference)")
    p.add_argument("--rig", action="append", metavar="PATH=VALUE",
                   help="rig parameter, a dotted RigParams path such as load.bias_force_n (repeatable)")
    p.add_argument("--grid", action="append", metavar="NAME=V1,V2,...",
                   help="sweep a firmware parameter (or rig:PATH, or seed) over values; several: every combination")
    p.add_argument("--seed", type=int, help="the rig's sensor-noise seed (default: the scenario's)")
    p.add_argument("--jobs", type=int, default=1, metavar="N", help="worker processes (default 1)")
    p.add_argument("--out", metavar="DIR", help="write summary.json and signals.npz (per variant: DIR/variant_NN)")
    p.add_argument("--json", metavar="FILE", help="write every variant's summary to FILE (a JSON list)")
    p.add_argument("--brief", action="store_true", help="the sweep table only, not each variant's report")
    p.add_argument("--commission", action="store_true",
                   help="run `pmactl commission` on each variant's rig first (over CAN frames, offline) and put "
                        "the lanes with commission = true (ppc, mfac) on the derived set plus the task's own "
                        "parameters (docs/commissioning.md); what was measured and derived goes into the summary")
    p.add_argument("--noise-limit", type=float, metavar="K", help=NOISE_LIMIT_HELP)


def main(args: argparse.Namespace) -> int:
    """python -m hil offline: exit 0 every run ended as its scenario expects, 1 not (or it failed),
    2 bad options or scenario, 3 the library is missing."""
    try:
        sc = scn.load(args.scenario)
        if args.controller:
            keep = [c for c in sc.controllers if c.label in args.controller]
            missing = set(args.controller) - {c.label for c in keep}
            if missing:
                raise OptionError(f"{sc.name} has no controller {', '.join(sorted(missing))} "
                                  f"(it has {', '.join(c.label for c in sc.controllers)})")
            sc.controllers = keep
        if args.jobs < 1:
            raise OptionError("--jobs must be at least 1")
        sc.noise_limit = noise_limit(args.noise_limit, args.commission)
        if args.seed is not None:
            sc.seed = _seed("--seed", args.seed)
        if args.duration is not None:
            if not 0 < args.duration <= 3600:
                raise OptionError("--duration must be in (0, 3600] s")
            sc.duration_s = sc.quick_duration_s = float(args.duration)
            if not sc.windows_for(sc.duration_s):   # shorter than every window: the whole run
                sc.windows = [(0.0, sc.duration_s)]
        variants = build_variants(sc, _assignments(args.set, "--set"), _assignments(args.rig, "--rig"), args.grid)
        # where the results go, checked before anything runs (nothing is written on a refusal)
        out = out_dir("--out", args.out) if args.out else None
        json_path = out_file("--json", args.json) if args.json else None
    except (ScenarioError, OptionError) as e:
        print(f"hil offline: {e}", file=sys.stderr)
        return 2
    try:
        library()
    except OfflineError as e:
        print(f"hil offline: {e}", file=sys.stderr)
        return 3
    runs = [v.scenario for v in variants]
    commissionings: list[Any] = []
    needs = sc.needs_commissioning()
    if needs and not args.commission:
        print(f"hil offline: {sc.name}: lane(s) {', '.join(needs)} take their set from commissioning: add "
              "--commission (or choose other lanes with --controller)", file=sys.stderr)
        return 2
    if args.commission:
        from pmactl.commission import CommissionAborted
        from pmactl.commission_rules import CommissionError

        from .commissioned import commission, commissioned
        if not needs:
            print(f"hil offline: --commission: {sc.name} has no lane with commission = true", file=sys.stderr)
            return 2
        try:
            for i, v in enumerate(runs):
                r = commission(v)
                commissionings.append(r)
                runs[i] = commissioned(v, r)
        except (CommissionError, CommissionAborted) as e:
            print(f"hil offline: commissioning refused: {e}", file=sys.stderr)
            return 1
    try:
        summaries = run_scenarios(runs, args.quick, args.jobs, out)
    except ParamError as e:
        print(f"hil offline: {e}", file=sys.stderr)
        return 2
    for k, (var, s) in enumerate(zip(variants, summaries)):
        s["variant"] = var.settings
        if commissionings:
            s["commissioning"] = jsonable(commissionings[k].report())
            if not args.brief:
                from pmactl.commission_report import text as commission_text
                print("\n".join(commission_text(commissionings[k])))
            if out is not None:
                vout = out if len(variants) == 1 else out / f"variant_{k:02d}"
                vout.mkdir(parents=True, exist_ok=True)
                (vout / "commissioning.json").write_text(json.dumps(s["commissioning"], indent=2) + "\n")
        if not args.brief:
            if var.label:
                print(f"\n#### {var.label}")
            print_summary(s)
            b = s["benchmark"]
            print(f"   offline: {b['simulated_s_per_wall_s']:.1f} simulated s per wall s "
                  f"({b['node_steps_per_s']:.0f} node steps/s)")
    if len(variants) > 1 or args.brief:
        print()
        print(sweep_table(variants, summaries))
    if json_path is not None:
        json_path.write_text(json.dumps(jsonable(summaries), indent=2) + "\n")
        print(f"results: {args.json}")
    if out is not None:
        print(f"results: {out}")
    for s in summaries:
        for err in s["errors"]:
            print(f"hil offline: error: {err}", file=sys.stderr)
    return 0 if all(s["expect_met"] for s in summaries) else 1
