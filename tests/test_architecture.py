"""The package's shape: no import cycle, one place for each idea, methods that describe themselves."""

import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ismb_lab
from ismb_lab.cli import build_parser, main
from ismb_lab.network.methods import MethodIII, get_method, method_names, register_method, unregister_method
from ismb_lab.network.solvers import SOLVERS

PACKAGE = Path(ismb_lab.__file__).parent
IMAGES = PACKAGE.parent / "images"
MODULES = sorted(PACKAGE.rglob("*.py"))


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """Every ismb_lab module that `path` imports, at any depth of the file (function-level too)."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    known = {module_name(p) for p in MODULES}
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            targets = [base] + [f"{base}.{a.name}" for a in node.names]
        else:
            continue
        found |= {t for t in targets if t in known and t != name}
    return found


def graph() -> dict[str, set[str]]:
    edges = {module_name(p): imports_of(p) for p in MODULES}
    for name in edges:   # importing a.b runs a/__init__.py first; that is not an edge of a's own
        edges[name] = {t for t in edges[name] if not name.startswith(t + ".")}
    return edges


def find_cycle(edges):
    state, stack = {}, []

    def visit(node):
        state[node] = "open"
        stack.append(node)
        for nxt in sorted(edges.get(node, ())):
            if state.get(nxt) == "open":
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        state[node] = "done"
        stack.pop()
        return None

    for node in sorted(edges):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def test_the_package_and_its_widgets_import_in_a_fresh_process():
    proc = subprocess.run([sys.executable, "-c", "import ismb_lab, ismb_lab.widgets"],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr


def test_the_import_graph_has_no_cycle():
    edges = graph()
    assert len(edges) > 25 and "ismb_lab.tuning.cases" in edges["ismb_lab.cli.evaluate"]
    assert find_cycle(edges) is None, " -> ".join(find_cycle(edges))


def test_the_cycle_finder_finds_a_cycle():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


#: The packages in the order the data flows through them: each imports only packages before it.
LAYERS = ("_core", "images", "cameras", "network", "matching", "labels", "depth", "scenes", "tuning",
          "teaching", "plotting", "widgets", "cli")


def package_of(module: str) -> str | None:
    """The package of a module (``ismb_lab.network.hopfield`` -> ``network``); None for ``ismb_lab``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def upward_imports(edges) -> list[str]:
    found = []
    for module, targets in edges.items():
        here = package_of(module)
        for target in targets:
            there = package_of(target)
            if here and there and there != here and LAYERS.index(there) > LAYERS.index(here):
                found.append(f"{module} -> {target}")
    return sorted(found)


def test_every_package_has_a_layer_and_imports_only_the_layers_below_it():
    edges = graph()
    assert {package_of(m) for m in edges} - {None} == set(LAYERS)
    assert not upward_imports(edges)


def test_the_layer_check_sees_an_upward_import():
    assert upward_imports({"ismb_lab.images.io": {"ismb_lab.network.hopfield", "ismb_lab._core.files"},
                           "ismb_lab.cli.match": {"ismb_lab.images.io"}}) == \
        ["ismb_lab.images.io -> ismb_lab.network.hopfield"]


def private_crossings(path: Path, name: str) -> list[str]:
    """Underscore names (not dunders) that module `name` at `path` imports from another package.
    ``_core`` is the base every package shares, so its own name does not count."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    private = lambda part: part.startswith("_") and not part.endswith("__") and part != "_core"  # noqa: E731
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            pairs = [(base, a.name) for a in node.names]
        elif isinstance(node, ast.Import):
            pairs = [(a.name, "") for a in node.names]
        else:
            continue
        for module, imported in pairs:
            if not module.startswith("ismb_lab.") or package_of(module) == package_of(name):
                continue
            if any(private(part) for part in module.split(".")[1:] + [imported]):
                found.append(f"{name}: {module} {imported}".rstrip())
    return found


def test_no_private_name_crosses_a_package_boundary():
    assert not [c for p in MODULES for c in private_crossings(p, module_name(p))]


def test_the_private_name_check_sees_a_crossing(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("from ..network.kernel import _solve, run_network\nfrom .._core.files import safe\n"
                      "from .pipeline import _helper\nfrom ..depth import _grouping\n")
    assert private_crossings(module, "ismb_lab.matching.m") == [
        "ismb_lab.matching.m: ismb_lab.network.kernel _solve", "ismb_lab.matching.m: ismb_lab.depth _grouping"]


def test_the_core_never_imports_pyplot_or_ipywidgets():
    for path in MODULES:
        if "widgets" in path.parts:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [f"{node.module}.{a.name}" for a in node.names] if isinstance(node, ast.ImportFrom) else [])
            assert not [n for n in names if "pyplot" in n or n.startswith("ipywidgets")], path


def test_every_public_module_declares_all():
    missing = [module_name(p) for p in MODULES
               if not p.name.startswith("_") and "__all__" not in p.read_text(encoding="utf-8")]
    assert not missing


# --- one place for each idea -------------------------------------------------------------

STATE_TO_PAIRS = ("flatnonzero(state", "flatnonzero(self.state", "nonzero(state", ".rows[on]", "rows[on],")


def test_a_solved_state_becomes_matches_in_one_function_only():
    places = [(p.name, phrase) for p in MODULES for phrase in STATE_TO_PAIRS
              if phrase in p.read_text(encoding="utf-8")]
    assert sorted({name for name, _ in places}) == ["solvers.py"], places


def solver_name_literals(path: Path):
    """String constants equal to a solver's name, outside docstrings, with their line."""
    names = set(SOLVERS)
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {id(n.body[0].value) for n in ast.walk(tree)
                  if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef)) and n.body
                  and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    lines = path.read_text(encoding="utf-8").splitlines()
    owners = {id(a) for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)
              and (n.func.id.startswith("check_") or n.func.id == "message") for a in n.args[1:]}
    owners |= {id(c) for n in ast.walk(tree) if isinstance(n, ast.Assign)
               and any(isinstance(t, ast.Name) and t.id == "__all__" for t in n.targets)
               for c in ast.walk(n.value)}   # exported function names, e.g. annealing.anneal
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and node.value in names and id(node) not in docstrings | owners:
            line = lines[node.lineno - 1]
            # "exact" is also the name of the Hopfield update rule (rule="exact" | "thesis")
            if node.value == "exact" and ("rule" in line.lower() or '"thesis"' in line):
                continue
            yield node.value, node.lineno


def test_solver_names_are_spelled_in_the_registry_only():
    spelled = {f"{p.relative_to(PACKAGE)}:{line}": name for p in MODULES if p.name != "solvers.py"
               for name, line in solver_name_literals(p)}
    assert not spelled


def test_the_solver_name_check_sees_a_stray_name(tmp_path):
    stray = tmp_path / "stray.py"
    stray.write_text('"""A docstring naming "anneal" is fine."""\nSOLVER = "anneal"\nrule = "exact"\n'
                     'check_rng(rng, "rng", "anneal")\n')
    assert list(solver_name_literals(stray)) == [("anneal", 2)]


# --- methods describe themselves ----------------------------------------------------------

class MethodFlat(MethodIII):
    """Method-III without the similarity term: a method defined in one place."""

    name, section = "FLAT", "a test"
    description = "Method-III with S = 0"

    def similarity(self, problem, params):
        return np.zeros(problem.n_neurons)


@pytest.fixture
def flat_method():
    register_method(MethodFlat())
    yield "FLAT"
    unregister_method("FLAT")


def test_a_method_defined_once_appears_in_match_tune_and_the_explorer(flat_method, tmp_path, capsys):
    pair = [IMAGES / "lab" / "left.png", IMAGES / "lab" / "right.png"]
    assert "FLAT" in method_names()
    for command in ("match", "tune"):
        assert "FLAT" in build_parser()._subparsers._group_actions[0].choices[command].format_help()
    out = tmp_path / "m.json"
    assert main(["match", *map(str, pair), "--method", "FLAT", "--json", str(out)]) == 0
    assert json.loads(out.read_text())["method"] == "FLAT"
    params = tmp_path / "p.json"
    assert main(["tune", *map(str, pair), str(IMAGES / "lab" / "answer_key.json"), "--method", "FLAT",
                 "--generations", "2", "--population", "4", "--out", str(params)]) == 0
    assert json.loads(params.read_text())["method"] == "FLAT"
    assert main(["match", *map(str, pair), "--params-file", str(params)]) == 0
    assert capsys.readouterr().out.count("Method-FLAT") >= 2

    pytest.importorskip("ipywidgets")
    from ismb_lab.matching.pipeline import prepare
    from ismb_lab.widgets import ParameterExplorer

    explorer = ParameterExplorer(prepare(*pair))
    assert "FLAT" in explorer.method_menu.options
    explorer.method_menu.value = "FLAT"
    assert explorer.model.method == "FLAT" and explorer.model.result.method == "FLAT"
    used = get_method("FLAT").gene_names
    assert all(s.disabled == (g not in used) for g, s in explorer.sliders.items())


def test_unregistered_methods_are_gone_from_the_command_line():
    from ismb_lab.cli import UsageError

    with pytest.raises(UsageError, match="invalid choice: 'FLAT'"):
        build_parser().parse_args(["match", "l.png", "r.png", "--method", "FLAT"])


# --- the command line and the library agree ---------------------------------------------

def test_depth_command_writes_exactly_the_library_json(tmp_path):
    from ismb_lab.depth.pipeline import relative_depth

    bg = [IMAGES / "lab" / "left.png", IMAGES / "lab" / "right.png"]
    cars = [IMAGES / "toy_cars" / "left.png", IMAGES / "toy_cars" / "right.png"]
    out = tmp_path / "d.json"
    assert main(["depth", *map(str, bg + cars), "--json", str(out)]) == 0
    expected = json.loads(json.dumps(relative_depth(bg, cars).to_dict()))
    written = json.loads(out.read_text())
    # the command adds the candidate window it used (the demo's own, as --shift was not given)
    assert written.pop("candidate_window") == {"shift": 20.0, "width": 40.0, "height": 30.0, "auto": False}
    assert written == expected and expected["objects"]


def test_the_code_notebooks_and_scripts_pass_the_linter():
    """pyproject's ruff rules (unused imports, undefined names, ...) hold everywhere, notebooks included."""
    root = PACKAGE.parent
    done = subprocess.run([sys.executable, "-m", "ruff", "check", "--no-cache", "--quiet", str(root)],
                          capture_output=True, text=True, cwd=root, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr


#: Modules whose "III" defaults are changed on other branches (the peers' signatures, the explorer).
_DEFAULT_METHOD_ELSEWHERE = {"ismb_lab.matching.peers", "ismb_lab.widgets.explorer"}


def test_the_default_method_is_declared_once():
    """No function spells the default method out: each refers to ``methods.DEFAULT_METHOD``."""
    from ismb_lab.network.methods import DEFAULT_METHOD

    spelled = []
    for path in MODULES:
        if module_name(path) in _DEFAULT_METHOD_ELSEWHERE:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                args = node.args
                for default in (*args.defaults, *args.kw_defaults):
                    if isinstance(default, ast.Constant) and default.value == DEFAULT_METHOD:
                        spelled.append(f"{module_name(path)}.{node.name}")
    assert spelled == []
