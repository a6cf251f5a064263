"""Fixtures every test tier shares.

Chromium lives here, not in tests/browser/: the browser tests and the real-account hub test
share one Playwright instance per session (Playwright's sync API refuses to start a second
one in the same thread while the first runs).

The compiled kernels are made ready once, before the first test (:func:`warm_kernels`):
with an empty numba cache (a new checkout, or edited kernel sources) they compile there,
all at once, instead of inside whichever test calls each first.  The summary at the end
says how many had no cached code and how long the warm-up took."""

import importlib.util
import os
import time
from pathlib import Path

import pytest

from ismb_lab.images.datasets import SampleDataMissing, opencv_samples

WARM = {}

CHROMIUM = Path("/usr/bin/chromium")
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]


def kernels() -> dict:
    """The numba kernels of the package's modules imported so far, by dotted name."""
    import sys

    from numba.core.registry import CPUDispatcher

    return {f"{module}.{name}": value for module, m in list(sys.modules.items())
            if module.startswith("ismb_lab.") for name, value in vars(m).items()
            if isinstance(value, CPUDispatcher) and value.py_func.__module__ == module}


def warm_kernels() -> dict:
    """Run every compiled path of the library once on a small pair, so that each kernel is
    compiled, or loaded from numba's cache, here.

    Returns ``{"cold": kernels that had no cached code before, "all": kernels}``."""
    import numpy as np

    from ismb_lab._core.numba_cache import cold
    from ismb_lab.network.annealing import iter_annealing
    from ismb_lab.network.exact import exhaustive_minimum
    from ismb_lab.tuning.genetic import initial_population
    from ismb_lab.network.hopfield import Network
    from ismb_lab.matching.pipeline import MatchConfig, prepare, warm_up
    from ismb_lab.network.methods import get_method, method_names
    from ismb_lab.network.params import Params
    from ismb_lab.tuning.cases import Case
    from ismb_lab.network.solvers import get_solver, solver_names
    from ismb_lab.tuning.fitness import Fitness, evaluate, gene_bounds

    found = kernels()
    before = sum(cold(k) for k in found.values())
    warm_up(tuple(solver_names()))                      # a match with every solver
    texture = np.kron(np.random.default_rng(0).integers(0, 256, (60, 100)), np.ones((2, 2)))
    prepared = prepare(texture, np.roll(texture, -8, axis=1), MatchConfig(roi="full", shift=8))
    case = Case(prepared, np.array([[0, 0], [1, 1]]))
    evaluate([case], "III", Params())
    for method in method_names():                       # the GA's batched fitness of each method
        for rule in ("exact", "thesis"):
            Fitness([case], method, solver=get_solver("network", rule=rule))(
                initial_population(0, gene_bounds(method), 2))
    list(iter_annealing(get_method("III").network(prepared.problem, Params()), rng=0, t_end=1.0))
    exhaustive_minimum(Network.from_arrays(1, 2, [0, 0], [0, 1], [0.5, -0.5], [], [], []))
    return {"cold": before, "all": len(found)}


@pytest.fixture(scope="session", autouse=True)
def warm():
    """:func:`warm_kernels`, once per session before the first test, timed for the summary."""
    start = time.perf_counter()
    WARM.update(warm_kernels(), seconds=time.perf_counter() - start)
    return WARM


def pytest_terminal_summary(terminalreporter):
    if WARM:
        terminalreporter.write_line(
            f"numba kernels: {WARM['cold']} of {WARM['all']} had no cached code; made ready in "
            f"{WARM['seconds']:.1f} s before the first test")


@pytest.fixture(scope="session")
def chromium():
    """Chromium's path: missing fails under CI=true (so a broken install cannot hide), else skips."""
    if not CHROMIUM.exists():
        text = f"{CHROMIUM} is missing (install it: apt-get install -y chromium)"
        if os.environ.get("CI", "").lower() in ("1", "true", "yes"):
            pytest.fail(text)
        pytest.skip(text)
    return str(CHROMIUM)


@pytest.fixture(scope="session")
def browser(chromium):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=chromium, args=ARGS)
        yield b
        b.close()


@pytest.fixture(scope="session")
def rendered():
    """A scene of :mod:`ismb_lab.scenes`, rendered once per session and shared by the tests that
    ask for it: ``rendered(synthetic_scene, 0)`` is ``synthetic_scene(0)``.  A scene's arrays are
    read-only, so no test can change what another sees; one takes about half a second to render,
    and a few seeds serve many tests."""
    import inspect

    made = {}

    def get(maker, *args, **kwargs):
        key = (maker.__module__, maker.__qualname__,
               tuple(inspect.signature(maker).bind(*args, **kwargs).arguments.items()))
        if key not in made:
            made[key] = maker(*args, **kwargs)
        return made[key]

    return get


@pytest.fixture(scope="module")
def pair(tmp_path_factory, rendered):
    """The rendered synthetic scene (seed 3) as two PNG files: [left, right]."""
    import cv2
    import numpy as np

    from ismb_lab.scenes import synthetic_scene

    folder = tmp_path_factory.mktemp("pair")
    scene = rendered(synthetic_scene, seed=3)
    paths = []
    for name, image in (("left.png", scene.left), ("right.png", scene.right)):
        cv2.imwrite(str(folder / name), np.clip(np.rint(image), 0, 255).astype(np.uint8))
        paths.append(folder / name)
    return paths


@pytest.fixture(scope="session")
def opencv_data():
    """The folder of OpenCV's sample photos (Debian's opencv-doc). Without it the test is
    skipped, except under CI=true, where .ci/run installs it: a missing install step fails."""
    try:
        return opencv_samples()
    except SampleDataMissing:
        if os.environ.get("CI") == "true":
            raise
        pytest.skip("opencv-doc is not installed")


@pytest.fixture(scope="session")
def load_script():
    """Import a file of ``scripts/`` as a module: ``load_script("depth_layouts")``."""
    folder = Path(__file__).resolve().parents[1] / "scripts"

    def load(name):
        spec = importlib.util.spec_from_file_location(name, folder / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module

    return load


@pytest.fixture
def hard_lab(tmp_path):
    """images/lab's pair copied, with targets whose first two partners are swapped: the GA never
    reaches the target fitness, so a fit stops only when told.  [left, right, hard.json] as str."""
    import json
    import shutil

    lab = Path(__file__).resolve().parent.parent / "images" / "lab"
    for name in ("left.png", "right.png"):
        shutil.copy(lab / name, tmp_path / name)
    data = json.loads((lab / "answer_key.json").read_text())
    p = data["pairs"]
    p[0]["right_xy"], p[1]["right_xy"] = p[1]["right_xy"], p[0]["right_xy"]
    (tmp_path / "hard.json").write_text(json.dumps(data))
    return [str(tmp_path / n) for n in ("left.png", "right.png", "hard.json")]


@pytest.fixture
def work(tmp_path):
    """images/lab's pair as L.png, R.png and its answer key as T.json, with manifests of two
    pairs (M.json, "a" and "b") and of one (M1.json): the command sweeps' working folder."""
    import json
    import shutil

    lab = Path(__file__).resolve().parent.parent / "images" / "lab"
    for name, target in (("left.png", "L.png"), ("right.png", "R.png"), ("answer_key.json", "T.json")):
        shutil.copy(lab / name, tmp_path / target)
    entry = {"left": "L.png", "right": "R.png", "targets": "T.json"}
    (tmp_path / "M.json").write_text(json.dumps({"pairs": [{**entry, "name": "a"}, {**entry, "name": "b"}]}))
    (tmp_path / "M1.json").write_text(json.dumps({"pairs": [{**entry, "name": "a"}]}))
    return tmp_path


@pytest.fixture
def hard_manifest(hard_lab, tmp_path):
    """A manifest of two pairs, "a" and "b", both :func:`hard_lab`'s."""
    import json

    entry = {"left": "left.png", "right": "right.png", "targets": "hard.json"}
    path = tmp_path / "m.json"
    path.write_text(json.dumps({"pairs": [{**entry, "name": "a"}, {**entry, "name": "b"}]}))
    return path
