"""Fixtures every test tier shares."""

import os

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
