"""Scene families as registered objects: the registry, each family's own random stream, and a new
family, defined once here, reaching ``families()``, the protocol's cases and both scripts."""

import os
import subprocess
import sys

import numpy as np
import pytest

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.tuning.cases import family_cases
from ismb_lab.scenes import (FAMILIES, Family, Look, families, get_family, object_layout, register_family,
                             unregister_family)


def dim_cameras(rng) -> dict:
    return {"gain": float(rng.uniform(0.5, 0.7)), "offset": 0.0, "noise_std": 3.0}


DIM = Family("dim", "A darker, noisier right camera", Look(camera=dim_cameras))


@pytest.fixture
def dim():
    register_family(DIM)
    yield DIM
    unregister_family(DIM.name)


def pair(layout) -> np.ndarray:
    return np.stack([layout.scene.left, layout.scene.right, layout.background.left])


def test_the_library_registers_its_four_families_in_order():
    assert families() == FAMILIES == ("contrast", "repetitive", "border", "cameras")
    assert all(get_family(name).name == name and get_family(name).description for name in FAMILIES)


def test_a_new_family_is_listed_drawn_and_removed(dim):
    assert families() == FAMILIES + ("dim",)
    layout = object_layout(5, 3, family="dim")
    assert layout.family == "dim" and len(layout.objects) == 3
    assert 0.5 <= layout.scene.gain <= 0.7 and layout.scene.noise_std == 3.0
    assert np.array_equal(pair(object_layout(5, 3, family="dim")), pair(layout))
    unregister_family("dim")
    assert families() == FAMILIES
    with pytest.raises(ParameterError, match="'family' parameter of object_layout must be one of 'contrast'"):
        object_layout(5, 3, family="dim")
    register_family(DIM)      # for the fixture's clean-up


def test_an_unknown_family_names_the_choices():
    with pytest.raises(ParameterError) as caught:
        get_family("stripes")
    assert all(repr(name) in str(caught.value) for name in FAMILIES) and "'stripes'" in str(caught.value)
    with pytest.raises(ParameterError, match="^The 'family' parameter of family_cases"):
        family_cases("stripes", 0, 1)


@pytest.mark.parametrize("make, name, error", [
    (lambda: register_family("dim"), "family", ParameterTypeError),
    (lambda: register_family(Family("contrast", "again")), "family", ParameterError),
    (lambda: unregister_family("dim"), "name", ParameterError),
    (lambda: Family("", "nameless"), "name", ParameterTypeError),
    (lambda: Family("x", None), "description", ParameterTypeError),
    (lambda: Family("x", "y", look=dim_cameras), "look", ParameterTypeError),
    (lambda: Look(camera={"gain": 1.0}), "camera", ParameterTypeError),
    (lambda: DIM.stream(-1), "seed", ParameterError),
])
def test_bad_families_name_the_parameter(make, name, error):
    with pytest.raises(error, match=rf"^The '{name}' parameter of \w[\w.]* must be .* Got .* instead\.$"):
        make()
    assert families() == FAMILIES


def test_a_new_family_has_a_stream_of_its_own():
    draws = {name: Family(name, "").stream(11).integers(2 ** 32, size=4) for name in ("dim", "dim2", "contrast")}
    seed_itself = np.random.default_rng(11).integers(2 ** 32, size=4)
    assert np.array_equal(draws["contrast"], seed_itself)         # the recorded families keep theirs
    assert not np.array_equal(draws["dim"], seed_itself) and not np.array_equal(draws["dim"], draws["dim2"])
    assert np.array_equal(Family("dim", "other words").stream(11).integers(2 ** 32, size=4), draws["dim"])
    rng = np.random.default_rng(3)
    assert DIM.stream(rng) is rng                                  # a Generator is used as it is


@pytest.mark.slow
def test_a_new_familys_layouts_depend_neither_on_the_registration_order_nor_on_the_process(dim):
    first = pair(object_layout(8, 2, family="dim"))
    other = register_family(Family("aaa", "registered after dim", DIM.look))
    try:
        again = pair(object_layout(8, 2, family="dim"))
        twin = pair(object_layout(8, 2, family="aaa"))
    finally:
        unregister_family(other.name)
    assert np.array_equal(first, again)
    assert not np.array_equal(first, twin)     # the same look, another name: another stream
    code = ("from ismb_lab.scenes import Family; "
            "print(Family('dim', '').stream(8).integers(2 ** 62, size=3).tolist())")
    printed = {subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                              env={**os.environ, "PYTHONHASHSEED": salt}).stdout for salt in ("1", "2")}
    assert printed == {f"{DIM.stream(8).integers(2 ** 62, size=3).tolist()}\n"}


def test_matching_families_builds_cases_for_every_registered_family(dim, load_script, monkeypatch):
    script = load_script("matching_families")
    asked = []
    monkeypatch.setattr(script, "family_cases", lambda f, start, count: asked.append((f, start, count)) or [f])
    assert script.family_sets(2000, 12) == {f: [f] for f in FAMILIES + ("dim",)}
    assert asked == [("contrast", 2000, 12), ("repetitive", 2100, 12), ("border", 2200, 12),
                     ("cameras", 2300, 12), ("dim", 2400, 12)]
    cases = family_cases("dim", 2400, 2)
    assert cases and all(c.name.startswith("dim 24") and len(c.targets) >= 3 for c in cases)


def test_depth_layouts_cycles_through_every_registered_family(dim, load_script):
    script = load_script("depth_layouts")
    seen = [(lay.family, len(lay.objects)) for lay in (script.layout_of(1000 + n, n) for n in (0, 4, 5, 9))]
    assert seen == [("contrast", 2), ("dim", 2), ("contrast", 3), ("dim", 3)]
