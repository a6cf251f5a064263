"""Real clicks in JupyterLab and Voila: what a student does, checked on the page and on disk."""

import base64
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg", force=True)

import pytest  # noqa: E402
from playwright.sync_api import expect  # noqa: E402


pytestmark = pytest.mark.browser

ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"


def test_label_targets_click_and_save(open_notebook, ui, workspace, artifacts):
    page = open_notebook("04_label_targets.ipynb")
    root = page.locator(".ismb-labeler")
    left_xy, right_xy = ui.label_one_pair(page, root, workspace)
    expect(root.locator(".ismb-dirty")).to_contain_text("unsaved")
    root.locator("button.ismb-save").click()
    expect(root.locator(".ismb-dirty")).to_have_text("saved", timeout=20_000)
    files = sorted((workspace / "notebooks").glob("targets-*-synthetic.json"))   # the student's own file
    assert len(files) == 1 and files[0].name.startswith("targets-") and files[0].name.endswith("-synthetic.json")
    saved = json.loads(files[0].read_text())
    assert [(p["left_xy"], p["right_xy"]) for p in saved["pairs"]] == [(list(left_xy), list(right_xy))]
    root.screenshot(path=artifacts / "04_label_targets.png")


def _data_url(canvas) -> str:
    return canvas.evaluate("c => c.toDataURL()")


def settled(canvas, quiet: float = 1.0, timeout: float = 30.0) -> str:
    """The canvas' image once it has not changed for `quiet` seconds."""
    deadline = time.monotonic() + timeout
    last, since = _data_url(canvas), time.monotonic()
    while time.monotonic() < deadline:
        time.sleep(0.2)
        now = _data_url(canvas)
        if now != last:
            last, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet:
            return now
    raise AssertionError("the canvas kept changing")


def test_hopfield_step_updates_status_and_energy_plot(open_notebook, ui, kernel_exec, artifacts):
    page = open_notebook("02_hopfield_network.ipynb")
    root = page.locator(".ismb-stepper")
    status = root.locator(".ismb-status")
    energy = root.locator(".ismb-energy canvas").first    # the image layer
    ui.wait_sized(page, energy)
    expect(status).to_contain_text("candidate neurons on", timeout=20_000)
    before = settled(energy)
    root.locator("button.ismb-step").click()
    expect(status).to_contain_text("attempt 1,", timeout=20_000)
    assert settled(energy) != before
    for _ in range(8):
        root.locator("button.ismb-step").click()
    expect(status).to_contain_text("attempt 9,", timeout=20_000)
    shown = settled(energy)
    kernel_exec(page, "stepper.energy_pane.draw()")
    assert settled(energy) == shown, "the energy plot after 8 rapid clicks was not the current one"
    root.screenshot(path=artifacts / "02_hopfield_stepper.png")


def test_voila_label_targets(voila, ui, page, workspace, artifacts):
    base = voila("04_label_targets.ipynb")
    page.goto(base, timeout=120_000)
    root = page.locator(".ismb-labeler")
    root.wait_for(timeout=120_000)
    left_xy, right_xy = ui.label_one_pair(page, root, workspace)
    # Voila without a hub serves every visitor under one login: a save needs the visitor's name
    root.locator("button.ismb-save").click()
    expect(root.locator(".ismb-status")).to_contain_text("'Your name' box", timeout=20_000)
    mine = workspace / "notebooks" / "targets-visitor-one-synthetic.json"
    assert not mine.exists()
    root.locator(".ismb-name input").fill("visitor one")
    expect(root.locator(".ismb-path")).to_contain_text(mine.name, timeout=20_000)
    root.locator("button.ismb-save").click()
    expect(root.locator(".ismb-dirty")).to_have_text("saved", timeout=20_000)
    saved = json.loads(mine.read_text())
    assert [(p["left_xy"], p["right_xy"]) for p in saved["pairs"]] == [(list(left_xy), list(right_xy))]
    root.screenshot(path=artifacts / "voila_04_label_targets.png")


def _generation(text: str) -> int:
    import re

    found = re.search(r"generation (\d+)/", text)
    return int(found.group(1)) if found else -1


def test_ga_runs_live_and_stops(open_notebook, kernel_exec, workspace, artifacts):
    # Notebook 05 trains on the student's own labels when there are some.  On the one pair
    # the labelling test above saved, 500 generations take about a second (the status showed
    # generation 36 at its first look), so the run could end before Stop was pressed.
    # Without them it trains on the eleven project pairs: seconds.
    labels = sorted((workspace / "notebooks").glob("targets-*-synthetic.json"))
    aside = [f.rename(f.with_name(f.name + ".aside")) for f in labels]
    try:
        page = open_notebook("06_genetic_algorithm.ipynb")
    finally:
        for moved, original in zip(aside, labels):
            moved.rename(original)
    root = page.locator(".ismb-ga")
    status = root.locator(".ismb-status")
    bar = root.locator(".ismb-progress .progress-bar")
    # Even on the project's pairs a quiet machine can run all 500 generations between the last look
    # below and the click on Stop (the status then read "finished, generation 500/500").  A listener
    # in the kernel holds each generation 50 ms, so the run lasts 25 s or more; the clicks are the
    # student's.
    kernel_exec(page, "import time; runner.model.listeners.append(lambda record: time.sleep(0.05))")
    root.locator("button.ismb-start").click()
    expect(status).to_contain_text("running, generation", timeout=60_000)
    assert "target fitness 1)" not in status.inner_text()   # the project's pairs, not one label
    seen, widths = set(), set()
    deadline = time.monotonic() + 60
    while len(seen) < 3 and time.monotonic() < deadline:   # progress advances while it runs
        text = status.inner_text()
        assert "finished" not in text, f"the GA ended before Stop: {text}"
        seen.add(_generation(text))
        widths.add(bar.evaluate("e => e.style.width"))
        time.sleep(0.2)
    assert len(seen - {-1}) >= 3, seen
    assert len(widths) >= 2, widths
    root.locator("button.ismb-stop").click()
    expect(status).to_contain_text("stopped", timeout=60_000)
    stopped_at = _generation(status.inner_text())
    time.sleep(2)
    assert _generation(status.inner_text()) == stopped_at
    expect(root.locator("button.ismb-start")).to_be_enabled()
    fitness = root.locator(".ismb-fitness canvas").first
    shown = settled(fitness)
    kernel_exec(page, "runner.pane.draw()")
    current = settled(fitness)
    if current != shown:   # keep both pictures to look at
        for what, url in (("shown", shown), ("current", current)):
            (artifacts / f"05_fitness_{what}.png").write_bytes(base64.b64decode(url.split(",", 1)[1]))
    assert current == shown, "the fitness plot after Stop was not the current one"
    root.screenshot(path=artifacts / "06_genetic_algorithm.png")


def test_toy_car_ranking_appears(open_notebook, ui, artifacts):
    page = open_notebook("07_toy_car_depth.ipynb")
    root = page.locator(".ismb-depth")
    ranking = root.locator(".ismb-ranking")
    expect(ranking).to_contain_text("1. object at", timeout=60_000)
    expect(ranking).to_contain_text("Z = ")
    expect(ranking).to_contain_text("nearer")
    expect(ranking).to_contain_text("outline")            # objects by their blobs of change
    ui.wait_sized(page, root.locator(".ismb-scene canvas").first)
    root.screenshot(path=artifacts / "07_toy_car_depth.png")
    root.locator(".ismb-grouping select").select_option(label="features only (thesis)")
    expect(ranking).not_to_contain_text("outline", timeout=60_000)
    expect(ranking).to_contain_text("2. object at")
    root.locator(".ismb-grouping select").select_option(label="outlines and features")
    expect(ranking).to_contain_text("outline", timeout=60_000)
