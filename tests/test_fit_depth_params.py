"""scripts/fit_depth_params.py writes a recipe that ``ismb-lab depth --params-file`` reads."""

import json

import pytest

from ismb_lab._core.files import OutputError
from ismb_lab.depth.pipeline import DEPTH_SOLVER
from ismb_lab.matching.recipe import load_recipe


@pytest.mark.slow
def test_the_fitted_recipe_is_read_as_the_depth_command_reads_it(load_script, tmp_path, capsys):
    out = tmp_path / "depth_params.json"
    load_script("fit_depth_params").main(["--generations", "1", "--population", "4", "--seeds", "1",
                                          "--out", str(out)])
    printed = capsys.readouterr().out
    recipe, note = load_recipe(out, solver=DEPTH_SOLVER, before=DEPTH_SOLVER)
    assert (recipe.method.name, recipe.solver.name, recipe.fit_seeds, note) == ("III", DEPTH_SOLVER, 1, "")
    assert json.loads(out.read_text())["params"] == recipe.params.to_dict()
    assert f"written to {out}" in printed


def test_an_output_that_cannot_be_written_is_refused_before_the_ga(load_script, tmp_path, capsys):
    with pytest.raises(OutputError, match="folder"):
        load_script("fit_depth_params").main(["--generations", "1", "--population", "4", "--seeds", "1",
                                              "--out", str(tmp_path)])
    assert capsys.readouterr().out == ""     # the GA, which prints, never started
