"""scripts/matching_families.py on a few layouts: it runs, and its pooled figures agree with its spreads."""

import re

import pytest


@pytest.mark.slow
def test_pooled_figures_lie_within_their_spread_over_ga_and_update_seeds(capsys, load_script):
    load_script("matching_families").main(["--count", "4", "--generations", "2", "--ga-seeds", "2",
                                           "--variants", "NM4:network", "III:assign:assign"])
    out = capsys.readouterr().out
    pooled = out.split("pooled over the families")[1]
    for variant in ("NM4:network", "III:assign:assign"):
        block = pooled.split(f"{variant}:")[1].split("\n  ", 3)
        recall, precision = map(float, re.findall(r"([\d.]+)%", block[0])[:2])
        for line in block[1:3]:
            low_r, high_r, low_p, high_p = map(float, re.findall(r"([\d.]+)-([\d.]+)%", line)[0]
                                               + re.findall(r"([\d.]+)-([\d.]+)%", line)[1])
            assert low_r - 0.05 <= recall <= high_r + 0.05, line
            assert low_p - 0.05 <= precision <= high_p + 0.05, line
    assert "over GA seeds" in pooled and "over update seeds" in pooled
    assert re.search(r"mutual-nn: C/T +[\d.]+% +precision", pooled)
    assert re.search(r"hungarian: C/T +[\d.]+% +precision", pooled)


@pytest.mark.slow
@pytest.mark.parametrize("method, one_to_one", [("NM3", True), ("NM4", False)])
def test_the_command_line_alone_gives_the_library_protocol_figures(tmp_path, method, one_to_one, load_script):
    from ismb_lab.tuning.cases import family_cases, protocol

    script = load_script("matching_families")
    cases = family_cases("cameras", 2300, 3)
    cli = script.cli_held_out(cases, method, "anneal", "anneal", 0, 2, 5, tmp_path, one_to_one)
    report = protocol(cases, method, generations=5, seeds=3, solver="anneal", fit_solver="anneal", rng=0,
                      fit_seeds=2, fit_all=False, one_to_one=one_to_one)
    assert cli == [script.figures([s]) for s in report.held_out]
    assert sum(t for _, _, t in cli) > 0
