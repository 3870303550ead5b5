"""The README's API example runs as printed (keeps the README true)."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_api_example_runs():
    text = README.read_text()
    block = re.search(r"## A first look at the API\n\n```python\n(.*?)```", text, re.S)
    assert block, "README lost its API example"
    env = {}
    exec(compile(block.group(1), "README.md", "exec"), env)  # noqa: S102
    assert env["eq"].residual < 1e-8 * env["eq"].residual_scale
    assert env["sp"].n_kernel == 3 and env["sp"].n_unstable == 2
    assert env["res"].success and env["res"].energy[-1] <= env["res"].energy[0]


def test_quickstart_commands_match_ci():
    text = README.read_text()
    ci = (README.parent / ".ci" / "run").read_text()
    install = re.search(r"```bash\n(pip install[^\n#]*?)\s*#", text).group(1).strip()
    assert install.replace("pip install", "python -m pip install --quiet") in ci
    tests = re.search(r"\n(python -m pytest[^\n#]*?)\s*#", text).group(1).strip()
    assert tests == "python -m pytest -q" and f"\n{tests}\n" in ci
