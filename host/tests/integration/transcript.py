# SPDX-License-Identifier: Apache-2.0
"""docs/tuning.md quotes the worked session that test_tuning_session.py runs: each
```console block of its session is a stretch of the run's transcript. These helpers
compare the two, and rewrite the blocks from a transcript (PMACTL_SESSION_OUT):

    PMACTL_SESSION_OUT=/tmp/s/session.md hil/with-vcan .venv/bin/python -m pytest \\
        host/tests/integration -k tuning_session
    .venv/bin/python host/tests/integration/transcript.py /tmp/s/session.md   # rewrites docs/tuning.md

What varies from run to run is masked: wall-clock times ("in 9.3 s"), logged frame counts,
the progress lines of `pmactl record` (their times and row counts), and matplotlib's
one-time font-cache notice."""
from __future__ import annotations

import re
import sys
from pathlib import Path

DOC = Path(__file__).resolve().parents[3] / "docs" / "tuning.md"
BLOCK = re.compile(r"```console\n(.*?)```", re.S)


def _clean(lines: list[str]) -> list[str]:
    return [line for line in lines if not line.startswith("Matplotlib is building the font cache")]


def normalize(lines: list[str]) -> list[str]:
    out = []
    for line in _clean(lines):
        if re.match(r"recording\s+[\d.]+/\d+ s", line):
            out.append("recording <progress>")
            continue
        line = re.sub(r" in [\d.]+ s:", " in <wall> s:", line)
        # the build's git commit and dirty flag, and the unique id (from the storage file's
        # path): the scan's columns (and its header); their widths follow, so runs of spaces
        # count as one
        line = re.sub(r"\b(\d+\.\d+\.\d+)\+[0-9a-f]{8}(-dirty)?", r"\1+<commit>", line)
        line = re.sub(r"\b[0-9a-f]{24}\b", "<unique id>", line)
        if "<commit>" in line or "<unique id>" in line or line.startswith("node  state  fault"):
            line = re.sub(r" {2,}", "  ", line)
        line = re.sub(r"\(\d+ frames\)", "(<n> frames)", line)
        out.append(line)
    # the number of progress lines depends on the machine's speed
    squashed: list[str] = []
    for line in out:
        if line == "recording <progress>" and squashed and squashed[-1] == line:
            continue
        squashed.append(line)
    return squashed


def session_stretch(session: list[str], block: list[str]) -> list[str]:
    """The transcript's lines from the block's first command to the end of its last."""
    cmds = [line for line in block if line.startswith("$ ")]
    assert cmds, block
    start = session.index(cmds[0])
    at = start
    for c in cmds[1:]:
        at = session.index(c, at + 1)
    end = at + 1
    while end < len(session) and not session[end].startswith("$ "):
        end += 1
    assert [line for line in session[start:end] if line.startswith("$ ")] == cmds, (cmds, session[start:end])
    return session[start:end]


def stale_blocks(doc: str, session_text: str) -> list[str]:
    """The doc's console blocks (their first command) that differ from the transcript."""
    session = _clean(session_text.splitlines())
    stale = []
    for m in BLOCK.finditer(doc):
        block = m.group(1).rstrip("\n").splitlines()
        if normalize(block) != normalize(session_stretch(session, block)):
            stale.append(block[0])
    return stale


def rewrite(doc: str, session_text: str) -> str:
    session = _clean(session_text.splitlines())

    def sub(m: re.Match) -> str:
        block = m.group(1).rstrip("\n").splitlines()
        return "```console\n" + "\n".join(session_stretch(session, block)) + "\n```"
    return BLOCK.sub(sub, doc)


if __name__ == "__main__":
    text = Path(sys.argv[1]).read_text()
    DOC.write_text(rewrite(DOC.read_text(), text))
    print(f"{DOC}: {len(BLOCK.findall(DOC.read_text()))} blocks from {sys.argv[1]}")
