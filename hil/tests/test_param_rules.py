# SPDX-License-Identifier: Apache-2.0
"""The harness meets the rules between parameters (docs/parameters.md)
itself. A rig with an 11-bit ADC puts adc.raw_min_counts (3.8 mA) below the default
wire-break level 737: the harness must set adc.wire_break_below_counts first (rule 3), and
the scenario check must refuse a set the node would refuse. No CAN: the node's rules are
pmactl.rules (the same numbers as firmware/app/app_config.c; tests/protocol/test_rules_doc.py
ties those to params.toml)."""
from __future__ import annotations

from pathlib import Path

import pytest

from hil.scenario import RULE_PARAMS, ScenarioError, load, protocol
from pmactl.rules import RuleError, broken_rule, set_order

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def scenario_file(tmp_path: Path, extra: str) -> Path:
    base = (SCENARIOS / "_rig_paper.toml").as_posix()
    p = tmp_path / "s.toml"
    p.write_text(f'base = "{base}"\nname = "rules"\nduration_s = 2.0\n'
                 f'[[controllers]]\nlabel = "ppc"\nmode = "PPC"\n{extra}\n')
    return p


def defaults() -> dict[str, float]:
    return {p.name: p.default for p in protocol().params}


def test_11_bit_adc_is_configured_in_a_valid_order(tmp_path) -> None:
    s = load(str(scenario_file(tmp_path, "[rig.sensor]\nadc_bits = 11")))
    params = s.node_params(s.controllers[0])
    assert params["adc.raw_min_counts"] < defaults()["adc.wire_break_below_counts"]
    # the wiring's own order (what the harness once used) breaks rule 3 on the way
    now = {n: defaults()[n] for n in RULE_PARAMS}
    naive = dict(now)
    broke = []
    for name, v in params.items():
        if name in naive:
            naive[name] = v
            broke.append(broken_rule({**defaults(), **naive}, set_only=True))
    assert 3 in broke
    # set_order never does
    order = set_order(now, params)
    assert sorted(order) == sorted(params)
    assert order.index("adc.wire_break_below_counts") < order.index("adc.raw_min_counts")
    step = dict(now)
    for name in order:
        step[name] = params[name]
        assert broken_rule({**defaults(), **step}, set_only=True) == 0, name


@pytest.mark.parametrize("extra, rule", [
    ('params = { "adc.wire_break_below_counts" = 800 }', 3),
    ('params = { "adc.raw_max_counts" = 700 }', 2),
    ('params = { "ctrl.u_min" = -900.0 }', 12),
    ('params = { "ctrl.u_max" = 300.0 }', 12),
    ('params = { "act.polarity" = 0 }', 6),
])
def test_scenario_check_refuses_what_the_node_refuses(tmp_path, extra, rule) -> None:
    with pytest.raises(ScenarioError, match=f"breaks rule {rule} "):
        load(str(scenario_file(tmp_path, extra)))


def test_set_order_refuses_a_set_that_breaks_a_set_rule() -> None:
    now = {n: defaults()[n] for n in RULE_PARAMS}
    with pytest.raises(RuleError) as e:
        set_order(now, {"adc.raw_min_counts": 500, "adc.wire_break_below_counts": 600})
    assert e.value.rule == 3


def test_every_shipped_scenario_keeps_every_rule() -> None:
    from hil.scenario import available
    for name in available():
        s = load(name)
        for c in s.controllers:
            assert broken_rule({**defaults(), **s.node_params(c)}) == 0, (name, c.label)
