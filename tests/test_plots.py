"""Tests of the figure helpers: the matplotlib backend a user chose is kept."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

SHOW_BACKEND = (
    "from leadthrough.plots import pyplot\n"
    "pyplot()\n"
    "import matplotlib\n"
    "print(matplotlib.get_backend())"
)


@pytest.mark.parametrize(
    ("setup", "environment", "expected"),
    [
        pytest.param("", {}, "agg", id="nothing chosen: Agg"),
        pytest.param("", {"MPLBACKEND": "svg"}, "svg", id="MPLBACKEND kept"),
        pytest.param("import matplotlib\nmatplotlib.use('pdf')\n", {}, "pdf", id="use() kept"),
    ],
)
def test_pyplot_selects_agg_only_when_no_backend_was_chosen(setup, environment, expected):
    """A notebook's or the user's backend survives ``pyplot()``; otherwise it is Agg."""
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"} | environment
    code = setup + SHOW_BACKEND
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip().lower() == expected
