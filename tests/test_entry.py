"""The ``leadthrough`` command's entry point outside the package."""

import importlib.abc
import sys

import leadthrough_entry


class _InterruptedImport(importlib.abc.MetaPathFinder):
    """Raises KeyboardInterrupt when the command line module is imported (Ctrl-C then)."""

    def find_spec(self, name, path=None, target=None):
        if name == "leadthrough.cli.main":
            raise KeyboardInterrupt
        return None


def test_ctrl_c_while_starting_is_one_line_and_exit_130(monkeypatch, capsys):
    """A Ctrl-C while the package is being imported: one line on stderr, exit 130."""
    monkeypatch.delitem(sys.modules, "leadthrough.cli.main", raising=False)
    monkeypatch.setattr(sys, "meta_path", [_InterruptedImport(), *sys.meta_path])
    assert leadthrough_entry.main() == 130
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "interrupted while starting" in err


def test_the_entry_point_runs_the_command_line(monkeypatch, capsys):
    """Without an interruption it is the command line itself (here: its help)."""
    monkeypatch.setattr(sys, "argv", ["leadthrough", "info"])
    assert leadthrough_entry.main() == 0
    assert "YuMi" in capsys.readouterr().out
