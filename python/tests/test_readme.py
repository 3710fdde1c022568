"""The README's Python example runs as written (as tests/docs_test.cc runs its ```sh blocks)."""

import os
import re

import pytest


def readme_python_blocks():
    source = os.environ.get("ATMO_SOURCE_DIR") or os.path.join(os.path.dirname(__file__), "..", "..")
    text = open(os.path.join(source, "README.md"), encoding="utf-8").read()
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.S | re.M)


def test_readme_has_a_python_example():
    assert readme_python_blocks(), "README.md has no ```python block"


@pytest.mark.parametrize("index", range(len(readme_python_blocks())))
def test_readme_python_block_runs(tmp_path, monkeypatch, capsys, index):
    monkeypatch.chdir(tmp_path)
    exec(compile(readme_python_blocks()[index], f"README.md python block {index}", "exec"), {})
    out = capsys.readouterr().out
    assert "(91, 3, 3) (91, 3, 3)" in out  # the shapes the comments state
    assert (tmp_path / "env.exr").exists() and (tmp_path / "env.png").exists()
