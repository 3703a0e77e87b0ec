"""The Python in README.md and docs/python.md runs as written (from the repository's root)."""

import os
import re

import pytest

from conftest import ROOT


def blocks(path):
    return re.findall(r"```python\n(.*?)```", (ROOT / path).read_text(), re.S)


@pytest.mark.parametrize("path", ["README.md", "docs/python.md"])
def test_the_python_in_the_docs_runs(path, tmp_path, monkeypatch):
    found = blocks(path)
    assert found, f"no python block in {path}"
    (tmp_path / "my-device.toml").write_text("shear_modulus = 60e3\n")
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    monkeypatch.chdir(tmp_path)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = {"plt": plt}
    for code in found:
        exec(compile(code, path, "exec"), names)
