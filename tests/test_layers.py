"""The import contract: each layer of the core imports only itself and the layers below it.

Read from the source (the AST of every module, imports inside functions included), so a
lazy import cannot hide an upward dependency.
"""

from __future__ import annotations

import ast
import os
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "leadthrough"

#: The core from the bottom up; a module may import its own layer and those below.
LAYERS = (
    ("errors", "validation", "filters", "trajectories", "progress", "compiled"),
    ("model",),
    ("logs",),
    ("friction",),
    ("identification",),
    ("estimation",),
    ("safety",),
    ("control",),
    ("runtime",),
)
#: Outside the core: the digital twin, the experiments, the figures, the command line.
OUTER = ("twin", "experiments", "plots", "cli")
#: What each outer package may not import (the twin is a plant, not an experiment).
OUTER_FORBIDDEN = {"twin": ("experiments", "cli"), "experiments": ("cli",), "plots": ("cli",)}

LAYER_OF = {name: level for level, names in enumerate(LAYERS) for name in names}


def module_name(path: Path) -> str:
    """Dotted name of a module file, e.g. ``leadthrough.safety.supervisor``."""
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imported(path: Path) -> list[tuple[str, int]]:
    """The leadthrough modules a file imports, with line numbers, relative imports resolved.

    ``from leadthrough import x`` counts as importing ``leadthrough.x`` when ``x`` is a
    module or a package, else as importing the package root.
    """
    package = module_name(path).split(".")
    if path.name != "__init__.py":
        package = package[:-1]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found += [(alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            for alias in node.names:
                candidate = f"{module}.{alias.name}"
                is_module = _is_module(candidate)
                found.append((candidate if is_module else module, node.lineno))
    mine = [(name, line) for name, line in found if name.split(".")[0] == "leadthrough"]
    return list(dict.fromkeys(mine))


def _is_module(dotted: str) -> bool:
    """Whether ``dotted`` names a module or package of leadthrough."""
    path = PACKAGE.parent.joinpath(*dotted.split("."))
    return path.with_suffix(".py").is_file() or (path / "__init__.py").is_file()


def part(module: str) -> str:
    """The top-level part of leadthrough a module belongs to ('' for the package root)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


MODULES = sorted(PACKAGE.rglob("*.py"))


def test_every_part_of_the_package_has_a_place():
    """Each module belongs to a layer of the core or to an outer package (no stray module)."""
    stray = {part(module_name(p)) for p in MODULES} - set(LAYER_OF) - set(OUTER) - {""}
    assert not stray, f"modules outside the layering: {sorted(stray)}"


@pytest.mark.parametrize("path", MODULES, ids=lambda p: module_name(p))
def test_imports_follow_the_layers(path):
    """A core module imports no layer above its own, no outer package, not the package root.

    The root imports only the core; outer packages do not import the command line, and the
    twin no experiment.
    """
    module = module_name(path)
    here = part(module)
    violations = []
    for name, line in imported(path):
        there = part(name)
        if here in LAYER_OF:
            upward = there not in LAYER_OF or LAYER_OF[there] > LAYER_OF[here]
        elif not here:  # the package root re-exports the core's public API, nothing else
            upward = there in OUTER
        else:
            upward = there in OUTER_FORBIDDEN.get(here, ()) or (there == "cli" != here)
        if upward:
            violations.append(f"{path.relative_to(PACKAGE)}:{line} imports {name}")
    assert not violations, "\n".join(violations)


def test_the_checker_sees_lazy_and_relative_imports(monkeypatch):
    """Imports inside functions and relative imports are found and resolved."""
    source = "def f():\n    from ..twin import runner\n    import leadthrough.cli.main\n"
    fake = PACKAGE / "control" / "fake.py"
    monkeypatch.setattr(Path, "read_text", lambda self, encoding=None: source)
    assert imported(fake) == [("leadthrough.twin.runner", 2), ("leadthrough.cli.main", 3)]


def test_import_loads_no_heavy_library():
    """``import leadthrough`` loads neither scipy, matplotlib, MuJoCo nor numba (kept lazy)."""
    code = (
        "import sys, leadthrough\n"
        "heavy = {'scipy', 'matplotlib', 'mujoco', 'numba'}\n"
        "print(sorted(heavy & {name.split('.')[0] for name in sys.modules}))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "[]"


def test_importing_the_twin_leaves_the_environment_alone():
    """Importing the twin (and MuJoCo) sets no MUJOCO_GL: the backend is chosen to render."""
    env = {key: value for key, value in os.environ.items() if key != "MUJOCO_GL"}
    code = "import os, leadthrough.twin.simulator\nprint(os.environ.get('MUJOCO_GL'))"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    assert run.stdout.strip() == "None", run.stderr


def test_the_command_line_chooses_the_gl_backend_before_mujoco_is_imported():
    """Importing the CLI loads no MuJoCo; its main sets MUJOCO_GL=egl before MuJoCo's import.

    MuJoCo reads MUJOCO_GL once, at import: imported earlier (it was, through the argument
    checks), it took GLFW and no picture of the arm was ever rendered from the command line.
    """
    env = {key: value for key, value in os.environ.items() if key != "MUJOCO_GL"}
    code = (
        "import os, sys\n"
        "from leadthrough.cli.main import main\n"
        "print('mujoco' in sys.modules)\n"
        "main(['info'])\n"
        "import mujoco\n"
        "print(os.environ.get('MUJOCO_GL'))"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env)
    lines = run.stdout.strip().splitlines()
    assert (lines[0], lines[-1]) == ("False", "egl"), run.stderr
