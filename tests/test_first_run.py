"""The first run says it is compiling: numba's cache is inspected, and the CLI says so once, on
a terminal, before a command that runs the network."""

import importlib
import io
import sys

import pytest

from ismb_lab._core import numba_cache as _numba


def test_cold_is_true_until_numba_has_cached_the_kernel(tmp_path, monkeypatch):
    (tmp_path / "fresh_kernel_module.py").write_text(
        "import numba\n\n@numba.njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("fresh_kernel_module")
    try:
        assert _numba.cold(module.twice)
        assert module.twice(21) == 42
        assert not _numba.cold(module.twice)
    finally:
        sys.modules.pop("fresh_kernel_module", None)


class _Terminal(io.StringIO):
    def isatty(self):
        return True


@pytest.mark.parametrize("cold, said", [(True, 1), (False, 0)])
def test_the_cli_announces_compiling_on_a_terminal_only(monkeypatch, cold, said):
    from ismb_lab import cli

    monkeypatch.setattr(_numba, "cold", lambda kernel: cold)
    terminal = _Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    cli._announce_compiling()
    assert terminal.getvalue().count("compiling the network's kernels") == said
    piped = io.StringIO()
    monkeypatch.setattr(sys, "stderr", piped)
    cli._announce_compiling()
    assert piped.getvalue() == ""


def test_only_the_commands_that_run_the_network_announce():
    from ismb_lab import cli

    parsers = cli.build_parser()._subparsers._group_actions[0].choices
    compiling = {name for name, parser in parsers.items() if parser.get_default("compiles")}
    assert compiling == {"match", "tune", "evaluate", "depth"}
