# SPDX-License-Identifier: Apache-2.0
"""The rules between parameters: params.toml's [[rule]] tables, which
docs/parameters.md lists, are the PMA_RULE_* numbers of firmware/app/app.h that GET_STATUS
LAST_RULE reports, and the set-time rules are exactly those pma_app_param_rule checks
before its `set_only` return."""
from __future__ import annotations

import re
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def rules() -> list[dict]:
    with open(REPO / "firmware/app/params.toml", "rb") as f:
        return tomllib.load(f)["rule"]


def test_rule_numbers_are_the_c_enum() -> None:
    src = (REPO / "firmware/app/app.h").read_text()
    enum = {m[1]: int(m[2]) for m in re.finditer(r"\bPMA_RULE_(\w+)\s*=\s*(\d+)", src)}
    assert enum.pop("NONE") == 0
    assert enum == {r["name"]: r["number"] for r in rules()}


def test_set_rules_are_the_ones_checked_at_set() -> None:
    src = (REPO / "firmware/app/app_config.c").read_text()
    body = src[src.index("int pma_app_param_rule("):]
    body = body[:body.index("\n}\n")]
    at_set, at_arm = body.split("if (set_only) return PMA_RULE_NONE;")
    names = lambda text: re.findall(r"return PMA_RULE_(\w+);", text)
    assert names(at_set) == [r["name"] for r in rules() if r["checked"] == "set"]
    assert [n for n in names(at_arm) if n != "NONE"] == [r["name"] for r in rules() if r["checked"] == "arm"]


def test_parameters_md_lists_every_rule() -> None:
    doc = (REPO / "docs/parameters.md").read_text()
    for r in rules():
        assert f"| {r['number']} | `{r['name']}` |" in doc, r["name"]
