"""The example notebook runs headless, small: with jupyter when it is installed, else its code
cells in order as one script (matplotlib optional: without it the notebook skips its plots)."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "strategies.ipynb"


def test_the_example_notebook_runs(tmp_path, monkeypatch):
    monkeypatch.setenv("ML_NOTEBOOK_QUICK", "1")
    monkeypatch.setenv("ML_NOTEBOOK_FIGURE", str(tmp_path / "figure.png"))
    if shutil.which("jupyter"):
        done = subprocess.run(["jupyter", "nbconvert", "--to", "notebook", "--execute",
                               "--output-dir", str(tmp_path), str(NOTEBOOK)],
                              capture_output=True, text=True, env=os.environ)
        assert done.returncode == 0, done.stderr[-2000:]
        return
    cells = json.loads(NOTEBOOK.read_text())["cells"]
    script = "\n\n".join("".join(c["source"]) for c in cells if c["cell_type"] == "code")
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "mis3-adaptive" in done.stdout and "relMSE" in done.stdout
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return
    assert (tmp_path / "figure.png").stat().st_size > 1000
