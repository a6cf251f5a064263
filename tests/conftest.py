"""Fixtures every test tier shares."""

import importlib.util
import os
from pathlib import Path

import pytest

from ismb_lab.datasets import SampleDataMissing, opencv_samples


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
