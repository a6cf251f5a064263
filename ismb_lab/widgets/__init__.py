"""Classroom widgets: each a model (plain Python), a matplotlib view and ipywidgets controls.

Display one by ending a notebook cell with it; ``.widget`` is its root container.
"""

from .labeler import LabelModel, TargetLabeler
from .ga_runner import GAModel, GARunner
from .stepper import HopfieldStepper, StepperModel

__all__ = ["GAModel", "GARunner", "HopfieldStepper", "LabelModel", "StepperModel", "TargetLabeler"]
