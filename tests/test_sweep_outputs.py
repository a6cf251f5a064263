"""No output replaces an input: every command declares what it reads, and its outputs are
checked against all of it (the sweep of issue 42, "An output replaces an input", and the
student folder that links out of the class folder)."""

import hashlib
import json
import os
import shutil
from pathlib import Path

import pytest

from ismb_lab._core.files import OutputError, atomic_write_text, check_output
from ismb_lab.cli import build_parser, main

ROOT = Path(__file__).resolve().parent.parent
LAB = ROOT / "images" / "lab"

#: Path options that name a folder, not a file the command reads (course is another
#: command's folder tool: its COURSE and --repo are folders).
FOLDERS = {("rectify", "out_dir"), ("render", "out"), ("source", "course"), ("source", "repo")}


def digest(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture
def work(tmp_path):
    """images/lab's pair and answer key, a recipe, and a manifest of the pair twice."""
    for name, target in (("left.png", "L.png"), ("right.png", "R.png"), ("answer_key.json", "T.json")):
        shutil.copy(LAB / name, tmp_path / target)
    (tmp_path / "P.json").write_text(json.dumps({"version": 2, "method": "III", "params": {"theta_c": 17.0},
                                                 "solver": "network"}))
    entry = {"left": "L.png", "right": "R.png", "targets": "T.json"}
    (tmp_path / "M.json").write_text(json.dumps({"pairs": [{**entry, "name": "a"}, {**entry, "name": "b"}]}))
    return tmp_path


def refused(argv, capsys, *protected):
    """Run `argv`; it must exit 2 with one line on stderr and leave `protected` as they were."""
    before = {p: digest(p) for p in protected}
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ismb-lab: error:"), err
    assert {p: digest(p) for p in protected} == before
    return err


def _subparsers():
    parser = build_parser()
    for top in parser._subparsers._group_actions[0].choices.values():
        nested = [a for a in top._actions if a.__class__.__name__ == "_SubParsersAction"]
        yield from (nested[0].choices.items() if nested else [(top.prog.split()[-1], top)])


def _path_inputs(p):
    """The options of parser `p` whose values are paths read (type Path), by dest."""
    return [a for a in p._actions if a.type is Path and (p.prog.split()[-1], a.dest) not in FOLDERS]


@pytest.mark.parametrize("name", [name for name, _ in _subparsers()])
def test_every_path_a_command_takes_is_a_declared_input(name, tmp_path):
    """The root of "evaluate --recipe P --json P": a path option the output check did not know.
    Every option of type Path (not a folder) must be among the inputs the command declares."""
    from ismb_lab.cli._guard import files_of

    p = dict(_subparsers())[name]
    argv, given = [], {}
    for action in p._actions:   # a value for every positional, and for every Path option
        if not action.option_strings and action.dest not in ("help",) and action.nargs != 0:
            value = tmp_path / f"{action.dest}.x"
            given[action.dest] = value
            argv.append(str(value))
    for action in _path_inputs(p):
        if action.option_strings:
            value = tmp_path / f"{action.dest}.x"
            given[action.dest] = value
            argv += [action.option_strings[0], str(value)]
    for action in p._actions:   # required options that are not paths read
        if action.required and action.option_strings and action.dest not in given:
            argv += [action.option_strings[0], str(tmp_path / f"{action.dest}.out")]
    prog = p.prog.split()[1:]
    args = build_parser().parse_args(prog + argv)
    if name == "source":
        pytest.skip("course source writes a folder of its own (its files are checked by ismb_lab.teaching.course)")
    declared = files_of(args)
    read = {Path(path) for _, path in declared.inputs} | {Path(path) for path in declared.reads}
    for action in _path_inputs(p):
        assert given[action.dest] in read, f"{name}: {action.dest} is read but not declared"


def test_evaluate_refuses_a_json_over_its_recipe(work, capsys):
    """The sweep's example, and the same file through a symbolic link and a hard link."""
    common = ["evaluate", work / "M.json", "--recipe", work / "P.json", "--generations", "1", "--jobs", "1"]
    refused([*common, "--json", work / "P.json"], capsys, work / "P.json")
    (work / "link.json").symlink_to(work / "P.json")
    refused([*common, "--json", work / "link.json"], capsys, work / "P.json")
    os.link(work / "P.json", work / "hard.json")
    refused([*common, "--json", work / "hard.json"], capsys, work / "P.json")


def test_evaluate_refuses_a_json_over_a_file_its_built_in_source_reads(work, capsys, monkeypatch, opencv_data):
    folder = work / "samples"
    folder.mkdir()
    for name in ("aloeL.jpg", "aloeR.jpg", "aloeGT.png"):
        shutil.copy(opencv_data / name, folder / name)
    monkeypatch.setenv("ISMB_LAB_OPENCV_DATA", str(folder))
    (work / "S.json").write_text(json.dumps({"pairs": [{"source": "middlebury-aloe", "roi": [0, 0, 160, 138]},
                                                       {"source": "middlebury-aloe", "roi": [160, 0, 160, 138]}]}))
    for name in ("aloeL.jpg", "aloeGT.png"):
        err = refused(["evaluate", work / "S.json", "--json", folder / name], capsys, folder / name)
        assert "also an input" in err


def test_a_manifest_declares_the_files_of_its_built_in_sources():
    from ismb_lab.tuning.cases import SOURCES, source_files

    assert set(SOURCES) == {"middlebury-motorcycle", "middlebury-aloe"}
    names = [p.name for p in source_files("middlebury-motorcycle")]
    assert names == ["motorcycle_left.png", "motorcycle_right.png", "motorcycle_disp.npz"]
    assert source_files("no-such-source") == ()


@pytest.mark.parametrize("argv", [
    lambda w: ["match", w / "L.png", w / "R.png", "--json", w / "R.png"],
    lambda w: ["match", w / "L.png", w / "R.png", "--params-file", w / "P.json", "--plot", w / "P.json"],
    lambda w: ["tune", w / "L.png", w / "R.png", w / "T.json", "--out", w / "T.json"],
    lambda w: ["depth", w / "L.png", w / "R.png", w / "L.png", w / "R.png", "--params-file", w / "P.json",
               "--json", w / "P.json"],
    lambda w: ["targets", "merge", w / "T.json", "--answer-key", w / "P.json", "--out", w / "P.json"],
    lambda w: ["calibrate", w / "L.png", w / "R.png", w / "L.png", w / "R.png", w / "L.png", w / "R.png",
               "--out", w / "R.png"],
    lambda w: ["evaluate", w / "M.json", "--json", w / "T.json"],
])
def test_no_command_writes_over_one_of_its_inputs(work, capsys, argv):
    refused(argv(work), capsys, *[work / n for n in ("L.png", "R.png", "T.json", "P.json", "M.json")])


@pytest.mark.parametrize("name", ["out.json/", "out.json/.", "sub/..", ".", "out.json//"])
@pytest.mark.parametrize("command", [
    lambda w, out: ["match", w / "L.png", w / "R.png", "--json", out],
    lambda w, out: ["match", w / "L.png", w / "R.png", "--plot", out],
    lambda w, out: ["tune", w / "L.png", w / "R.png", w / "T.json", "--out", out],
    lambda w, out: ["evaluate", w / "M.json", "--json", out],
    lambda w, out: ["targets", "merge", w / "T.json", "--out", out],
])
def test_an_output_name_written_as_a_folder_is_refused(work, capsys, monkeypatch, name, command):
    """``--json out.json/`` wrote out.json: a trailing slash names a folder, never a file."""
    monkeypatch.chdir(work)
    (work / "sub").mkdir()
    before = sorted(p.name for p in work.iterdir())
    err = refused(command(work, name), capsys)
    assert "names a folder" in err
    assert sorted(p.name for p in work.iterdir()) == before


def test_the_library_refuses_a_folder_name_too(tmp_path):
    from ismb_lab._core.files import refuse_folder_name

    for name in (f"{tmp_path}/p.json/", f"{tmp_path}/p.json/."):
        with pytest.raises(OutputError, match="names a folder"):
            check_output(name)
        with pytest.raises(OutputError, match="names a folder"):
            atomic_write_text(name, "{}")
    assert not (tmp_path / "p.json").exists()
    refuse_folder_name(tmp_path / "p.json")   # a Path has lost its slash: nothing to see
    assert check_output(str(tmp_path / "p.json")).name == "p.json"


# --- a collected class: links never lead out of it ---

@pytest.fixture
def course(tmp_path):
    """submitted/ann and submitted/bob, each with the answer key as their labels; a folder
    outside the class with another targets file."""
    submitted = tmp_path / "course" / "submitted"
    for who in ("ann", "bob"):
        (submitted / who / "labels").mkdir(parents=True)
        shutil.copy(LAB / "answer_key.json", submitted / who / "labels" / f"targets-{who}-lab.json")
    outside = tmp_path / "outside" / "deep"
    outside.mkdir(parents=True)
    shutil.copy(LAB / "answer_key.json", outside / "targets-mallory-lab.json")
    return tmp_path


def test_a_student_folder_that_links_out_of_the_class_is_not_followed(course):
    from ismb_lab.labels.classroom import collected

    submitted = course / "course" / "submitted"
    (submitted / "mallory").symlink_to(course / "outside")          # the sweep's link to /
    (submitted / "eve").symlink_to("/")
    (submitted / "bob" / "labels" / "more").symlink_to(course / "outside")   # a folder below a student's
    (submitted / "ann" / "labels" / "targets-ann-extra.json").symlink_to(
        course / "outside" / "deep" / "targets-mallory-lab.json")        # a file that is a link
    found = collected(course / "course")
    assert sorted(found) == ["ann", "bob"]
    assert [p.name for p in found["ann"]] == ["targets-ann-lab.json"]
    assert [p.name for p in found["bob"]] == ["targets-bob-lab.json"]


def test_a_submitted_folder_that_is_a_link_is_refused(course):
    from ismb_lab import ParameterError
    from ismb_lab.labels.classroom import collected

    (course / "other").mkdir()
    (course / "other" / "submitted").symlink_to(course / "course" / "submitted")
    with pytest.raises(ParameterError, match="not a symbolic link"):
        collected(course / "other")


def test_targets_merge_counts_no_vote_from_a_linked_student_folder(course, capsys):
    submitted = course / "course" / "submitted"
    (submitted / "mallory").symlink_to(course / "outside")
    out = course / "all.json"
    assert main(["targets", "merge", str(course / "course"), "--out", str(out)]) == 0
    report = capsys.readouterr().out
    assert "ann" in report and "bob" in report and "mallory" not in report
