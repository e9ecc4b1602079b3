"""The Python quickstart of docs/python.md runs as written (its python blocks, in order, one namespace)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_readme_python_quickstart_runs(tmp_path, monkeypatch):
    text = (ROOT / "docs" / "python.md").read_text()
    section = re.search(r"<!-- python-quickstart.*?-->(.*?)<!-- /python-quickstart -->", text, re.S)
    assert section, "docs/python.md lost its python-quickstart markers"
    blocks = re.findall(r"```python\n(.*?)```", section.group(1), re.S)
    assert len(blocks) == 4
    monkeypatch.chdir(tmp_path)
    ns = {}
    run = lambda b: exec(compile(b, "docs/python.md", "exec"), ns)  # noqa: E731
    run(blocks[0])
    assert ns["r"]["w_spec_j_kg"].shape == (25,)
    run(blocks[1])
    assert ns["problem"].evaluations == 400
    run(blocks[2])
    assert (tmp_path / "front.png").stat().st_size > 1000
    run(blocks[3])
    assert ns["problem"].n_ieq_constr == 10 and ns["problem"].evaluations == 200
    assert ns["problem"].last["compliant"].shape == (40,)
