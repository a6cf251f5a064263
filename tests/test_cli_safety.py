"""Outputs that never destroy anything, signals that stop the work cleanly, crashes gone."""

import functools
import json
import os
import shutil
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ismb_lab.cli import main

ROOT = Path(__file__).resolve().parent.parent
LAB = ROOT / "images" / "lab"


@pytest.fixture
def lab(tmp_path):
    """images/lab's pair and answer key, copied: (left, right, targets)."""
    names = ("left.png", "right.png", "answer_key.json")
    for name in names:
        shutil.copy(LAB / name, tmp_path / name)
    return [tmp_path / n for n in names]


@pytest.fixture
def hard_targets(lab, tmp_path):
    """Two targets with swapped partners: the GA can never reach the target fitness."""
    data = json.loads(lab[2].read_text())
    p = data["pairs"]
    p[0]["right_xy"], p[1]["right_xy"] = p[1]["right_xy"], p[0]["right_xy"]
    path = tmp_path / "hard.json"
    path.write_text(json.dumps(data))
    return path


def default_signals():
    """In the child: signals at their defaults, even if this test run was started with SIGINT
    ignored (a background job of a shell), which the child would inherit and respect."""
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)


@pytest.fixture
def cli():
    """Start ``python -m ismb_lab.cli ...``; whatever is still running at teardown is killed."""
    started = []

    def start(*args):
        proc = subprocess.Popen([sys.executable, "-m", "ismb_lab.cli", *map(str, args)],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                                preexec_fn=default_signals)
        started.append(proc)
        return proc

    yield start
    for proc in started:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def handlers_installed(pid, timeout=120.0) -> bool:
    """Wait until the process catches SIGTERM (main() has installed its handlers)."""
    status = Path(f"/proc/{pid}/status")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            caught = next(int(line.split()[1], 16) for line in status.read_text().splitlines()
                          if line.startswith("SigCgt"))
        except (OSError, StopIteration):
            return False
        if caught >> (signal.SIGTERM - 1) & 1:
            return True
        time.sleep(0.005)
    return False


needs_proc = pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux /proc")


# --- outputs -----------------------------------------------------------------------------

def test_a_symbolic_link_is_written_through_and_kept(lab, tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old\n")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert main(["match", *map(str, lab[:2]), "--json", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(real)
    assert json.loads(real.read_text())["method"] == "III"


def test_force_writes_into_a_device_and_never_replaces_it(lab, tmp_path):
    device = tmp_path / "null"
    try:
        os.mknod(device, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except OSError:
        pytest.skip("cannot make a character device here")
    assert main(["match", *map(str, lab[:2]), "--json", str(device), "--force"]) == 0
    assert stat.S_ISCHR(os.lstat(device).st_mode) and os.lstat(device).st_rdev == os.makedev(1, 3)


@pytest.mark.slow
def test_json_to_stdout_through_its_link_with_force(lab):
    proc = subprocess.run([sys.executable, "-m", "ismb_lab.cli", "match", *map(str, lab[:2]),
                           "--json", "/dev/stdout", "--force"], capture_output=True, text=True,
                          timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert '"method": "III"' in proc.stdout


def test_force_replaces_a_read_only_file_and_keeps_its_mode(lab, tmp_path):
    out = tmp_path / "ro.json"
    out.write_text("{}\n")
    out.chmod(0o444)
    assert main(["match", *map(str, lab[:2]), "--json", str(out), "--force"]) == 0
    assert json.loads(out.read_text())["method"] == "III"
    assert stat.S_IMODE(out.stat().st_mode) == 0o444


def test_an_input_is_refused_even_with_force(lab, capsys):
    before = lab[2].read_bytes()
    assert main(["tune", *map(str, lab), "--out", str(lab[2]), "--force"]) == 2
    assert "also an input" in capsys.readouterr().err
    assert lab[2].read_bytes() == before


def test_the_folder_is_fsynced_after_the_rename(tmp_path, monkeypatch):
    from ismb_lab._core.files import atomic_write_bytes

    synced = []
    real_fsync = os.fsync

    def spy(fd):
        synced.append(stat.S_ISDIR(os.fstat(fd).st_mode))
        return real_fsync(fd)

    monkeypatch.setattr(os, "fsync", spy)
    atomic_write_bytes(tmp_path / "x.bin", b"data")
    assert synced == [False, True]   # the file's data, then the folder's entry


def test_an_output_is_checked_before_any_work(lab, tmp_path, monkeypatch, capsys):
    import ismb_lab.matching.pipeline

    def no_work(*args, **kwargs):
        raise AssertionError("the work started before the output was checked")

    monkeypatch.setattr(ismb_lab.matching.pipeline, "prepare", no_work)
    code = main(["tune", *map(str, lab), "--out", str(tmp_path / "nodir" / "p.json")])
    err = capsys.readouterr().err
    assert code == 2 and "nodir/p.json" in err and ".tmp" not in err and ".probe" not in err
    assert not list(tmp_path.glob(".*"))


def test_check_output_names_the_rule(tmp_path):
    from ismb_lab._core.files import OutputError, check_output

    fifo = tmp_path / "f"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="FIFO"):
        check_output(fifo, what="--json")
    assert check_output(fifo, force=True) == fifo


# --- signals -----------------------------------------------------------------------------

@pytest.mark.slow
@needs_proc
@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_sigterm_and_sighup_stop_tune_and_write_the_best_so_far(cli, lab, hard_targets, tmp_path, sig,
                                                               code):
    out = tmp_path / "params.json"
    proc = cli("tune", lab[0], lab[1], hard_targets, "--generations", "100000", "--out", out)
    assert handlers_installed(proc.pid)
    time.sleep(3)   # start-up and, on an idle machine, a few generations
    proc.send_signal(sig)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr and "interrupted" in stderr, stderr
    if "best parameters so far were written" in stderr:   # whenever a generation had finished
        assert json.loads(out.read_text())["interrupted"] is True
    else:
        assert not out.exists()


@needs_proc
@pytest.mark.parametrize("delay", [0.0, 0.05, 0.2, 0.5, 1.0])
@pytest.mark.slow   # five fresh interpreters, each signalled
def test_a_signal_during_start_up_exits_130_with_one_line(cli, lab, hard_targets, tmp_path, delay):
    # From the moment main() has its handlers: imports, loading the pair, numba's first
    # compilation or cache load, the first generation.
    proc = cli("tune", lab[0], lab[1], hard_targets, "--generations", "100000",
               "--out", tmp_path / "p.json")
    assert handlers_installed(proc.pid)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "SystemError" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.startswith("ismb-lab:")]
    assert len(lines) == 1 and "interrupted" in lines[0], stderr


def test_a_swallowed_ctrl_c_still_stops_tune(lab, hard_targets, tmp_path, monkeypatch, capsys):
    """C code (numba's dispatcher) can swallow the KeyboardInterrupt; the next generation stops."""
    import ismb_lab.tuning.fitness

    real_tune = ismb_lab.tuning.fitness.tune

    @functools.wraps(real_tune)   # the same signature, whose defaults the command reads
    def swallowing(*args, **kwargs):
        for n, record in enumerate(real_tune(*args, **kwargs)):
            if n == 2:
                try:
                    os.kill(os.getpid(), signal.SIGINT)
                    time.sleep(0.5)
                except KeyboardInterrupt:
                    pass   # lost, as inside a C extension
            yield record

    monkeypatch.setattr(ismb_lab.tuning.fitness, "tune", swallowing)
    out = tmp_path / "p.json"
    # as from a terminal: a run started as a background job inherits SIGINT ignored, which the
    # command rightly leaves ignored (tests/test_cli_signals.py)
    saved = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        code = main(["tune", *map(str, lab[:2]), str(hard_targets), "--generations", "400", "--out", str(out)])
    finally:
        signal.signal(signal.SIGINT, saved)
    assert code == 130, capsys.readouterr().err
    assert json.loads(out.read_text())["generations"] <= 3


def test_evaluate_interrupted_writes_the_best_so_far(lab, tmp_path, monkeypatch, capsys):
    import ismb_lab.cli.evaluate

    manifest = tmp_path / "m.json"
    entry = {"left": "left.png", "right": "right.png", "targets": "hard.json"}
    data = json.loads(lab[2].read_text())
    data["pairs"][0]["right_xy"], data["pairs"][1]["right_xy"] = (data["pairs"][1]["right_xy"],
                                                                  data["pairs"][0]["right_xy"])
    (tmp_path / "hard.json").write_text(json.dumps(data))
    manifest.write_text(json.dumps({"pairs": [{**entry, "name": "a"}, {**entry, "name": "b"}]}))
    real_protocol = ismb_lab.cli.evaluate.protocol

    def interrupted_in_the_ga(*args, progress, **kwargs):
        def relay(name, record):
            progress(name, record)
            if record.index == 3:
                raise KeyboardInterrupt
        return real_protocol(*args, progress=relay, **kwargs)

    monkeypatch.setattr(ismb_lab.cli.evaluate, "protocol", interrupted_in_the_ga)
    out = tmp_path / "report.json"
    assert main(["evaluate", str(manifest), "--seeds", "1", "--jobs", "1", "--json", str(out)]) == 130
    report = json.loads(out.read_text())
    assert report["interrupted"] is True and report["generations"] == 3 and report["fitted_on"] == "a"
    assert set(report["params"]) == {"theta_c", "theta_s", "lambda_c", "lambda_s"}
    assert "interrupted" in capsys.readouterr().err


# --- crashes and wrong results -----------------------------------------------------------

@pytest.mark.slow
def test_a_file_name_that_is_not_utf8_is_read(lab, tmp_path):
    name = os.path.join(os.fsencode(tmp_path), b"\xff.png")
    shutil.copy(lab[0], name)
    proc = subprocess.run([sys.executable, "-m", "ismb_lab.cli", "match", name, os.fsencode(lab[1])],
                          capture_output=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr[-500:]
    assert b"Pair  Left Right" in proc.stdout


def test_a_re_encoded_image_passes_with_no_hash_check(lab, tmp_path, capsys):
    import cv2

    image = cv2.imread(str(lab[0]), cv2.IMREAD_UNCHANGED)
    re_encoded = tmp_path / "left_again.png"
    cv2.imwrite(str(re_encoded), image, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    assert re_encoded.read_bytes() != lab[0].read_bytes()
    args = ["tune", str(re_encoded), str(lab[1]), str(lab[2]), "--generations", "3",
            "--out", str(tmp_path / "p.json")]
    assert main(args) == 2
    assert "--no-hash-check" in capsys.readouterr().err
    assert main(args + ["--no-hash-check"]) == 0


def test_json_outputs_are_strict(lab, tmp_path):
    out = tmp_path / "m.json"
    code = main(["match", *map(str, lab[:2]), "--method", "NM", "--match-bias", "1e300",
                 "--json", str(out)])
    assert code in (0, 2)   # 2 once the network refuses weights it cannot represent
    if code == 0:
        def refuse(name):
            raise ValueError(f"{name} is not JSON")
        json.loads(out.read_text(), parse_constant=refuse)


def test_an_infinite_depth_is_null_in_the_json():
    from ismb_lab.cli._guard import json_text

    text = json_text({"objects": [{"depth_m": float("inf"), "depth_range_m": [1.0, float("inf")]}]})
    assert json.loads(text) == {"objects": [{"depth_m": None, "depth_range_m": [1.0, None]}]}


def test_a_match_bias_the_method_does_not_run_is_refused_and_nm_keeps_it(lab, tmp_path):
    assert main(["match", *map(str, lab[:2]), "--method", "NM4", "--match-bias", "0"]) == 0
    out = tmp_path / "nm.json"
    assert main(["match", *map(str, lab[:2]), "--method", "NM", "--match-bias", "0.5",
                 "--json", str(out)]) == 0
    assert json.loads(out.read_text())["params"]["match_bias"] == 0.5


def test_memory_error_is_one_line(lab, monkeypatch, capsys):
    import ismb_lab.matching.pipeline

    def out_of_memory(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(ismb_lab.matching.pipeline, "prepare", out_of_memory)
    assert main(["match", *map(str, lab[:2])]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "out of memory" in err


def test_the_pixel_limit_reads_the_header_and_can_be_raised(tmp_path, monkeypatch):
    from ismb_lab.images.io import load_image

    path = tmp_path / "wide.png"
    import cv2
    cv2.imwrite(str(path), np.zeros((10, 300), np.uint8))
    monkeypatch.setenv("ISMB_LAB_MAX_PIXELS", "2999")
    with pytest.raises(ValueError, match="300x10"):
        load_image(path)
    monkeypatch.setenv("ISMB_LAB_MAX_PIXELS", "3000")
    assert load_image(path).shape == (10, 300)


def test_help_lists_every_limit():
    from ismb_lab.cli import build_parser
    from ismb_lab.cli._guard import LIMITS
    from ismb_lab.images.io import MAX_PIXELS, MOST_PIXELS
    from ismb_lab.labels.targets import MAX_BYTES, MAX_PAIRS

    epilog = " ".join(build_parser().epilog.split())
    assert f"<= {MAX_PIXELS} (ISMB_LAB_MAX_PIXELS, at most {MOST_PIXELS})" in epilog
    assert f"targets files <= {MAX_PAIRS} pairs and {MAX_BYTES} bytes" in epilog
    assert "a default above it is lowered to it with a note" in epilog
    for variable, default, _, option in LIMITS.values():
        assert f"{option} <= {default} ({variable})" in epilog


@pytest.mark.slow   # a fresh interpreter
def test_importing_the_cli_does_not_import_numpy():
    code = "import sys, ismb_lab.cli; print('numpy' in sys.modules, 'numba' in sys.modules)"
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          cwd=ROOT)
    assert proc.stdout.split() == ["False", "False"], proc.stderr


# --- app mode ----------------------------------------------------------------------------

def test_readme_install_command_installs_voila():
    import re

    tomllib = pytest.importorskip("tomllib")   # Python 3.11+
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    readme = (ROOT / "README.md").read_text()
    first = re.search(r"```bash\n(.*?)\n```", readme, re.S).group(1)
    spec = re.search(r"pip install (\S+)", first).group(1).strip("\"'")
    extras = re.findall(r"\[([\w,\s-]+)\]", spec)
    wanted = list(project["dependencies"])
    for extra in (e.strip() for group in extras for e in group.split(",")):
        wanted += project["optional-dependencies"][extra]
    assert any(re.match(r"voila\b", dep) for dep in wanted), first
    assert "voila notebooks/04_label_targets.ipynb" in readme


def test_an_interrupt_swallowed_in_a_finaliser_prints_nothing(monkeypatch):
    """After a signal, "Exception ignored ... KeyboardInterrupt" reports are dropped."""
    import gc

    from ismb_lab.cli._guard import Interrupts, interrupted

    reports = []
    monkeypatch.setattr(sys, "unraisablehook", lambda report: reports.append(report.exc_type))

    class Finalised:
        def __del__(self):
            raise KeyboardInterrupt   # what a signal handler raising inside __del__ gives

    with Interrupts() as interrupts:
        Finalised()
        gc.collect()
        assert reports == [KeyboardInterrupt]   # no signal yet: reported as usual
        interrupts.signum = signal.SIGINT   # as the handler records it
        Finalised()
        gc.collect()
        assert interrupted()
    assert reports == [KeyboardInterrupt]
    assert not interrupted()


def test_an_interrupt_printed_by_c_code_prints_nothing_after_a_signal(capfd):
    """C code that reports an error with PyErr_Print (numpy's import_array does) echoes nothing."""
    import ctypes

    from ismb_lab.cli._guard import Interrupts

    def c_code_prints(kind):
        # PyRun_SimpleString reports the exception with PyErr_Print and returns -1.
        assert ctypes.pythonapi.PyRun_SimpleString(f"raise {kind.__name__}".encode()) == -1
        return capfd.readouterr().err

    with Interrupts() as interrupts:
        assert "KeyboardInterrupt" in c_code_prints(KeyboardInterrupt)   # no signal yet
        interrupts.signum = signal.SIGINT
        assert c_code_prints(KeyboardInterrupt) == ""
        assert "ValueError" in c_code_prints(ValueError)   # only the signal's echoes are dropped
    assert "KeyboardInterrupt" in c_code_prints(KeyboardInterrupt)


# --- limits bound the defaults too (issue 25) ---

def preflighted(argv, monkeypatch, **env):
    from ismb_lab.cli import build_parser
    from ismb_lab.cli._guard import UsageError, preflight

    for name, value in env.items():
        monkeypatch.setenv(name, value)
    args = build_parser().parse_args([str(a) for a in argv])
    preflight(args, UsageError)
    return args


@pytest.mark.parametrize("argv, env, name, value", [
    (["tune", "L", "R", "T"], {"ISMB_LAB_MAX_GENERATIONS": "5"}, "generations", 5),
    (["tune", "L", "R", "T"], {"ISMB_LAB_MAX_POPULATION": "7"}, "population", 7),
    (["match", "L", "R"], {"ISMB_LAB_MAX_CORNERS": "25"}, "n_max", 25),
    (["depth", "L", "R", "L", "R"], {"ISMB_LAB_MAX_CORNERS": "25"}, "n_max", 25),
    (["evaluate", "M"], {"ISMB_LAB_MAX_SEEDS": "2"}, "seeds", 2),
    (["evaluate", "M"], {"ISMB_LAB_MAX_GENERATIONS": "5"}, "generations", 5),
])
def test_a_default_above_its_limit_is_lowered_to_it_with_a_note(monkeypatch, capsys, argv, env, name, value):
    args = preflighted(argv, monkeypatch, **env)
    assert getattr(args, name) == value
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ismb-lab: note:") and f"{next(iter(env))}={value}" in err


def test_a_default_within_its_limit_stays_the_library_default(monkeypatch, capsys):
    args = preflighted(["tune", "L", "R", "T"], monkeypatch, ISMB_LAB_MAX_GENERATIONS="100000")
    assert args.generations is None and capsys.readouterr().err == ""


def test_tune_without_options_runs_within_a_lowered_generation_limit(lab, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("ISMB_LAB_MAX_GENERATIONS", "2")
    out = tmp_path / "p.json"
    assert main(["tune", *map(str, lab), "--out", str(out)]) == 0
    assert json.loads(out.read_text())["generations"] <= 2
    assert "using --generations 2" in capsys.readouterr().err


@pytest.mark.parametrize("value", ["9" * 400, "0", "1000000001", "five"])
def test_every_limit_variable_is_a_bounded_whole_number(monkeypatch, value):
    from ismb_lab.cli._guard import LIMITS, UsageError, limit

    for name, (variable, *_) in LIMITS.items():
        monkeypatch.setenv(variable, value)
        with pytest.raises(UsageError, match=f"{variable} must be a whole number from 1 to 1000000000"):
            limit(name)


# --- render replaces only the regular files it writes ---

def test_render_knows_every_file_it_writes_before_rendering():
    from ismb_lab.scenes.gallery import gallery_files

    images = ROOT / "images"
    committed = {p for p in images.rglob("*") if p.is_file() and p != images / "README.md"}
    assert set(gallery_files(images)) == committed


def test_render_replaces_its_regular_files_and_refuses_a_device(tmp_path):
    from ismb_lab._core.files import OutputError
    from ismb_lab.cli.render import check_outputs
    from ismb_lab.scenes.gallery import gallery_files

    for path in gallery_files(tmp_path):
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"an earlier render")
    check_outputs(tmp_path)   # the normal use: render again into images/
    victim = gallery_files(tmp_path)[-1]
    victim.unlink()
    try:
        os.mknod(victim, stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except (PermissionError, OSError):
        pytest.skip("cannot make a character device here (mknod needs root)")
    with pytest.raises(OutputError, match="character device"):
        check_outputs(tmp_path)
