"""The README is true by construction: its tables and numbers are `make docs` outputs."""

import json
import re
from pathlib import Path

from leadthrough.experiments.readme import rewrite, stale

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_readme_quotes_the_generated_tables_and_numbers():
    """Every marked table and number of the README equals docs/results (rerun make docs)."""
    assert stale(README, ROOT) == []


def test_readme_has_generated_parts():
    """The README's measured tables are generated ones (markers present, numbers known)."""
    blocks = re.findall(r"<!-- begin (docs/results/[\w.-]+\.md) -->", README)
    assert len(blocks) >= 7, blocks
    numbers = json.loads((ROOT / "docs/results/numbers.json").read_text(encoding="utf-8"))
    assert {"demo.joint_rms_mrad", "demo.seconds", "identify.seconds"} <= set(numbers)


def test_every_readme_figure_is_regenerated_by_make_docs():
    """Each docs/figures PNG the README shows is one `make docs` writes, and exists."""
    from leadthrough.experiments.docs import FIGURES

    shown = set(re.findall(r"docs/figures/([\w.-]+\.png)", README))
    assert shown <= set(FIGURES), shown - set(FIGURES)
    assert all((ROOT / "docs/figures" / name).stat().st_size > 10_000 for name in shown)


def test_conventions_are_in_the_repository():
    """The conventions the README relies on are a document of the repository, linked from it."""
    assert "(docs/conventions.md)" in README and (ROOT / "docs/conventions.md").exists()
    assert "SPEC" not in README


def test_rewrite_and_stale_on_a_small_readme(tmp_path):
    """Rewrite fills blocks and numbers from the files; stale names each difference."""
    (tmp_path / "docs/results").mkdir(parents=True)
    (tmp_path / "docs/results/t.md").write_text("| a |\n|---|\n| 1 |\n")
    (tmp_path / "docs/results/numbers.json").write_text('{"x.y": "0.25"}')
    text = ("Error <!-- n:x.y -->9.99<!-- /n --> mrad.\n<!-- begin docs/results/t.md -->\nold\n"
            "<!-- end docs/results/t.md -->\n<!-- n:gone -->1<!-- /n -->\n")  # fmt: skip
    problems = stale(text, tmp_path)
    assert len(problems) == 3 and "x.y" in problems[1] + problems[2]
    new = rewrite(text, tmp_path)
    assert "Error <!-- n:x.y -->0.25<!-- /n --> mrad." in new
    assert "-->\n| a |\n|---|\n| 1 |\n<!-- end" in new
    assert stale(new, tmp_path) == ["number gone: not in docs/results/numbers.json"]
    assert rewrite(new, tmp_path) == new


def test_every_benchmark_figure_names_the_script_that_draws_it():
    """A docs/bench PNG the README or a docs page shows exists, and its script writes it."""
    shown = set(re.findall(r"docs/bench/([\w.-]+\.png)", README))
    for page in (ROOT / "docs").glob("*.md"):
        shown |= set(re.findall(r"\]\(bench/([\w.-]+\.png)\)", page.read_text(encoding="utf-8")))
    assert shown  # the pages show some (an empty set would check nothing)
    for name in shown:
        assert (ROOT / "docs/bench" / name).stat().st_size > 10_000
        scripts = [path for path in (ROOT / "benchmarks").glob("*.py")
                   if f"docs/bench/{name}" in path.read_text()]  # fmt: skip
        assert scripts, f"no benchmark writes docs/bench/{name}"


def test_every_relative_link_of_the_documents_exists():
    """The README's and docs/*.md's links to files of the repository resolve (moved pages)."""
    documents = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    broken = []
    for document in documents:
        text = document.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)\s#]+)(?:#[^)]*)?\)", text):
            if "://" not in target and not (document.parent / target).exists():
                broken.append(f"{document.name}: {target}")
    assert broken == []
