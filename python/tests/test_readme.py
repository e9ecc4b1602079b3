"""The README's Python quickstart runs as written (its python blocks, in order, one namespace)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_readme_python_quickstart_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text()
    section = re.search(r"<!-- python-quickstart.*?-->(.*?)<!-- /python-quickstart -->", text, re.S)
    assert section, "README lost its python-quickstart markers"
    blocks = re.findall(r"```python\n(.*?)```", section.group(1), re.S)
    assert len(blocks) == 3
    monkeypatch.chdir(tmp_path)
    ns = {}
    for b in blocks:
        exec(compile(b, "README.md", "exec"), ns)
    assert ns["r"]["w_spec_j_kg"].shape == (25,)
    assert ns["problem"].evaluations == 400
    assert (tmp_path / "front.png").stat().st_size > 1000
