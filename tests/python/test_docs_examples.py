"""The ```python blocks of docs/python.md run as written (docs/reliability.md, "Docs that are tested";
the shell blocks are run by tests/docs/run_doc_commands.py). Each block runs in a fresh namespace
in a temporary directory; a block preceded by `<!-- not-run: REASON -->` is skipped with the reason."""
import os
import re

import pytest

DOC = os.path.join(os.path.dirname(__file__), "..", "..", "docs", "python.md")


def python_blocks():
    lines = open(DOC, encoding="utf-8").read().split("\n")
    blocks, i, previous = [], 0, ""
    while i < len(lines):
        if lines[i].startswith("```python"):
            j = i + 1
            while not lines[j].startswith("```"):
                j += 1
            reason = re.match(r"^<!--\s*not-run:(.*)-->\s*$", previous.strip())
            blocks.append(pytest.param(i + 1, "\n".join(lines[i + 1:j]), reason.group(1).strip() if reason else None,
                                       id=f"python.md:{i + 1}"))
            i, previous = j + 1, ""
            continue
        if lines[i].strip():
            previous = lines[i]
        i += 1
    return blocks


def test_docs_have_python_blocks():
    assert len(python_blocks()) >= 2, "docs/python.md lost its python examples (or this test's parser broke)"


@pytest.mark.parametrize("line,code,reason", python_blocks())
def test_python_block_runs_as_written(line, code, reason, tmp_path, monkeypatch):
    if reason is not None:
        assert reason, f"docs/python.md:{line}: not-run without a reason"
        pytest.skip(reason)
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": f"docs_python_md_{line}"}
    # A failure's traceback names this file's frame "docs/python.md:LINE" and the block's own line.
    exec(compile(code, f"docs/python.md (block at line {line})", "exec"), namespace)
    check_results(namespace)


def check_results(ns):
    """What the example's variables promise, checked independently of how the example got them."""
    import numpy as np
    if "mean" in ns and "var" in ns:  # kriging predictions and variances at the example's targets
        assert np.all(np.isfinite(ns["mean"])) and np.all(np.asarray(ns["var"]) >= 0.0)
    if {"robot", "poses", "sol"} <= ns.keys():  # IK of FK poses: converged and back on the same poses
        assert np.all(ns["sol"].ok)
        np.testing.assert_allclose(ns["robot"].fk(ns["sol"].q), ns["poses"], atol=1e-6)
