"""A signal at a chosen moment of ``ismb-lab tune``: the best so far is written, or the line says not.

The moment is chosen, not timed: a test wraps the function that runs at that moment
(the GA's generator, the fitness's compiled network runs, the rename that ends a write) so that
its n-th call sends the signal to this process with ``signal.raise_signal``.  CPython
runs the handler (which raises KeyboardInterrupt) before ``raise_signal`` returns, so
the signal lands exactly there on every run.  A signal inside numba's compiled
dispatcher reaches Python as ``SystemError: ... returned a result with an exception
set``, chained to the KeyboardInterrupt; the network hook raises it the same way.
"""

import functools
import json
import signal
from pathlib import Path

import pytest

import ismb_lab._core.files
import ismb_lab.cli.evaluate  # noqa: F401  (imported before any test wraps a function of tuning,
import ismb_lab.cli.tune  # noqa: F401     which ismb_lab.tuning.cases binds by name at its import)
import ismb_lab.tuning.fitness
from ismb_lab.cli import main


@pytest.fixture(autouse=True)
def signals_not_ignored():
    """Each test as a command started from a terminal finds the signals: none ignored.  A test run
    started under ``nohup`` (or as a background job) inherits SIGHUP (or SIGINT) ignored, and the
    command rightly leaves an ignored signal ignored (see the last test)."""
    saved = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    for sig, handler in saved.items():
        if handler == signal.SIG_IGN:
            signal.signal(sig, signal.default_int_handler if sig == signal.SIGINT else signal.SIG_DFL)
    yield
    for sig, handler in saved.items():
        signal.signal(sig, handler)


@pytest.fixture
def lab(hard_lab):
    """The pair and targets the GA never fits exactly: it stops only when told."""
    return hard_lab


def signal_on_call(monkeypatch, owner, name, n, sig=signal.SIGTERM, like_numba=False):
    """Make the `n`-th call of ``owner.name`` send `sig` to this process; returns the calls seen."""
    real, calls = getattr(owner, name), []

    @functools.wraps(real)
    def hooked(*args, **kwargs):
        calls.append(args)
        if len(calls) == n:
            try:
                signal.raise_signal(sig)
            except KeyboardInterrupt as exc:
                if like_numba:
                    raise SystemError("<built-in method run of _dispatcher> returned a result "
                                      "with an exception set") from exc
                raise
        return real(*args, **kwargs)

    monkeypatch.setattr(owner, name, hooked)
    return calls


def signal_after_generation(monkeypatch, n, sig=signal.SIGTERM):
    """Send `sig` when the GA is asked for the generation after the `n`-th (n = 0: before the first)."""
    real = ismb_lab.tuning.fitness.tune

    @functools.wraps(real)
    def tune(*args, **kwargs):
        records = real(*args, **kwargs)
        for k in range(n):
            yield next(records)
        signal.raise_signal(sig)
        yield from records

    monkeypatch.setattr(ismb_lab.tuning.fitness, "tune", tune)


def tune(lab, out, *options):
    return main(["tune", *lab, "--population", "6", "--out", str(out), *options])


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and "SystemError" not in err, err
    lines = [line for line in err.splitlines() if line.startswith("ismb-lab:")]
    assert len(lines) == 1, err
    return lines[0]


def test_before_the_first_generation_the_line_says_nothing_was_saved(lab, tmp_path, monkeypatch, capsys):
    signal_after_generation(monkeypatch, 0)
    out = tmp_path / "params.json"
    assert tune(lab, out, "--generations", "400") == 128 + signal.SIGTERM
    line = one_line(capsys)
    assert line.startswith("ismb-lab: interrupted (SIGTERM)") and "nothing was saved" in line, line
    assert not out.exists()


def test_before_the_command_runs_the_line_says_nothing_was_saved(lab, tmp_path, monkeypatch, capsys):
    import ismb_lab.cli

    calls = signal_on_call(monkeypatch, ismb_lab.cli, "preflight", 1, signal.SIGINT)
    out = tmp_path / "params.json"
    assert tune(lab, out, "--generations", "400") == 130
    assert len(calls) == 1
    assert one_line(capsys) == "ismb-lab: interrupted; nothing was saved"
    assert not out.exists()


def test_between_generations_the_best_so_far_is_written(lab, tmp_path, monkeypatch, capsys):
    signal_after_generation(monkeypatch, 3, signal.SIGHUP)
    out = tmp_path / "params.json"
    assert tune(lab, out, "--generations", "400") == 128 + signal.SIGHUP
    line = one_line(capsys)
    assert "(SIGHUP)" in line and f"best parameters so far were written to {out}" in line, line
    data = json.loads(out.read_text())
    assert data["interrupted"] is True and data["generations"] == 2
    assert f"fitness {data['fitness']:g} after 2 generations" in line


@pytest.mark.parametrize("call", [1, 3])   # the first generation's network runs; generation 3's
def test_a_signal_inside_the_network_run_keeps_the_best_so_far(lab, tmp_path, monkeypatch, capsys, call):
    # a generation's networks run in one compiled call per case (the lab is one case)
    calls = signal_on_call(monkeypatch, ismb_lab.tuning.fitness, "fitness_runs", call, like_numba=True)
    out = tmp_path / "params.json"
    assert tune(lab, out, "--generations", "400") == 128 + signal.SIGTERM
    assert len(calls) == call   # the GA stopped at the signal
    line = one_line(capsys)
    if call == 1:
        assert "nothing was saved" in line and not out.exists(), line
    else:
        data = json.loads(out.read_text())
        assert data["interrupted"] is True and data["generations"] >= 1
        assert "best parameters so far were written" in line, line


def test_a_signal_during_the_final_write_lets_it_finish(lab, tmp_path, monkeypatch, capsys):
    out = tmp_path / "params.json"
    calls = signal_on_call(monkeypatch, ismb_lab._core.files.os, "replace", 1)
    assert tune(lab, out, "--generations", "3") == 128 + signal.SIGTERM
    assert len(calls) == 1 and Path(calls[0][1]) == out
    line = one_line(capsys)
    assert f"the parameters were written to {out}" in line, line
    data = json.loads(out.read_text())
    assert data["interrupted"] is False and data["generations"] == 3   # the whole GA ran
    assert not list(tmp_path.glob(".params.json.*"))   # no temporary file left behind


def test_a_second_signal_during_the_best_so_far_write_lets_it_finish(lab, tmp_path, monkeypatch, capsys):
    signal_after_generation(monkeypatch, 2, signal.SIGINT)
    signal_on_call(monkeypatch, ismb_lab._core.files.os, "replace", 1, signal.SIGTERM)
    out = tmp_path / "params.json"
    assert tune(lab, out, "--generations", "400") == 130   # the first signal's code
    line = one_line(capsys)
    assert line.startswith("ismb-lab: interrupted;") and "best parameters so far were written" in line
    assert json.loads(out.read_text())["interrupted"] is True


def test_a_signal_after_the_write_says_the_file_is_there(lab, tmp_path, monkeypatch, capsys):
    out = tmp_path / "params.json"
    signal_on_call(monkeypatch, ismb_lab.tuning.fitness, "evaluate", 1)   # the summary's own network run
    assert tune(lab, out, "--generations", "2") == 128 + signal.SIGTERM
    assert f"the parameters were written to {out}" in one_line(capsys)
    assert json.loads(out.read_text())["interrupted"] is False


@pytest.fixture
def manifest(hard_manifest):
    return str(hard_manifest)


def evaluate(manifest, out):
    return main(["evaluate", manifest, "--jobs", "1", "--seeds", "1", "--population", "6",
                 "--generations", "400", "--json", str(out)])


@pytest.mark.parametrize("call", [1, 3])   # the first generation's network runs; generation 3's
def test_evaluate_signalled_inside_the_network_run_keeps_the_best_so_far(manifest, tmp_path, monkeypatch,
                                                                        capsys, call):
    signal_on_call(monkeypatch, ismb_lab.tuning.fitness, "fitness_runs", call, like_numba=True)
    out = tmp_path / "report.json"
    assert evaluate(manifest, out) == 128 + signal.SIGTERM
    line = one_line(capsys)
    if call == 1:
        assert line == (f"ismb-lab: interrupted (SIGTERM); nothing was written to {out}: "
                        "no GA generation had finished")
        assert not out.exists()
    else:
        report = json.loads(out.read_text())
        assert report["interrupted"] is True and report["fitted_on"] == "a" and report["generations"] >= 1
        assert "best parameters so far" in line, line


def test_evaluate_signalled_while_writing_its_report_finishes_it(manifest, tmp_path, monkeypatch, capsys):
    out = tmp_path / "report.json"
    signal_on_call(monkeypatch, ismb_lab._core.files.os, "replace", 1)
    assert main(["evaluate", manifest, "--jobs", "1", "--seeds", "1", "--population", "6",
                 "--generations", "2", "--json", str(out)]) == 128 + signal.SIGTERM
    assert f"the report is complete and written to {out}" in one_line(capsys)
    assert "interrupted" not in json.loads(out.read_text())


def test_a_hang_up_ignored_by_nohup_stays_ignored(lab, tmp_path, monkeypatch, capsys):
    """``nohup ismb-lab tune ...`` asks to run on after a hang-up: the command installs no handler
    for a signal it inherits ignored, so the hang-up neither stops nor shortens the run."""
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    signal_after_generation(monkeypatch, 1, signal.SIGHUP)
    out = tmp_path / "params.json"
    assert tune(lab, out, "--generations", "4") == 0
    assert "interrupted" not in capsys.readouterr().err
    data = json.loads(out.read_text())
    assert data.get("interrupted") is not True and data["generations"] == 4
