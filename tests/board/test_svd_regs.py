"""The STM32G474 port's register definitions (hal/portable/st/stm32g474/g4_regs.h)
against ST's SVD (../shared/data/svd/STM32G474xx.svd beside the repository),
through tools/check_svd_regs.py. Skipped, with the reason, when the SVD is absent.

The mutation tests edit a copy of the header (one wrong base, offset, position,
width, field name, interrupt, layout claim) and require the checker to name
each mistake: a checker that passes everything fails them."""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))
import check_svd_regs as chk  # noqa: E402

SVD = chk.DEFAULT_SVD
HEADER = chk.DEFAULT_HEADER

needs_svd = pytest.mark.skipif(
    not SVD.is_file(), reason=f"SVD not found at {SVD}: register definitions not checked")


@needs_svd
def test_header_matches_svd():
    errors, n = chk.check(SVD, HEADER)
    assert errors == []
    # what the port uses, at least: RCC, PWR, FLASH, GPIOA/B, TIM2, TIM6, ADC1,
    # ADC12 common, DAC1, FDCAN1, IWDG, DBGMCU, NVIC, CPACR, message RAM
    assert n["bases"] >= 16
    assert n["offsets"] >= 70
    assert n["fields"] >= 160
    assert n["irqs"] == 4
    assert n["layouts"] == 1


@needs_svd
def test_command_line_exit_status():
    r = subprocess.run([sys.executable, str(ROOT / "tools/check_svd_regs.py")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout
    assert "0 mismatches" in r.stdout


def test_missing_svd_is_reported_not_passed(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "tools/check_svd_regs.py"),
                        "--svd", str(tmp_path / "absent.svd")], capture_output=True, text=True)
    assert r.returncode == chk.EXIT_NO_SVD
    assert "SKIPPED" in r.stdout


MUTATIONS = [
    # (pattern in the header, replacement, text expected in an error)
    (r"#define G4_FDCAN1_BASE 0x40006400u", "#define G4_FDCAN1_BASE 0x40006800u", "G4_FDCAN1_BASE"),
    (r"#define G4_RCC_CSR_OFFSET 0x94u", "#define G4_RCC_CSR_OFFSET 0x90u", "G4_RCC_CSR_OFFSET"),
    (r"#define G4_FDCAN1_NBTP_NTSEG1_Pos 8u", "#define G4_FDCAN1_NBTP_NTSEG1_Pos 9u",
     "G4_FDCAN1_NBTP_NTSEG1_Pos"),
    (r"\(0x1FFu << G4_FDCAN1_NBTP_NBRP_Pos\)", "(0xFFu << G4_FDCAN1_NBTP_NBRP_Pos)",
     "G4_FDCAN1_NBTP_NBRP_Msk"),
    (r"#define G4_FLASH_SR_BSY_Pos 16u", "#define G4_FLASH_SR_BUSY_Pos 16u", "no field BUSY"),
    (r"#define G4_IRQ_TIM6_DACUNDER 54u", "#define G4_IRQ_TIM6_DACUNDER 55u", "G4_IRQ_TIM6_DACUNDER"),
    (r"#define G4_GPIOB_SAME_LAYOUT_AS_GPIOA 1", "#define G4_TIM6_SAME_LAYOUT_AS_GPIOA 1",
     "G4_TIM6_SAME_LAYOUT_AS_GPIOA"),
    (r"#define G4_IWDG_RLR_OFFSET 0x08u", "#define G4_IWDG_RELOAD_OFFSET 0x08u", "no register RELOAD"),
]


@needs_svd
@pytest.mark.parametrize("pattern,replacement,expected", MUTATIONS)
def test_checker_finds_a_wrong_definition(tmp_path, pattern, replacement, expected):
    text = HEADER.read_text()
    mutated, count = re.subn(pattern, replacement, text)
    assert count == 1, f"the header no longer contains {pattern}"
    h = tmp_path / "g4_regs.h"
    h.write_text(mutated)
    errors, _ = chk.check(SVD, h)
    assert any(expected in e for e in errors), errors
