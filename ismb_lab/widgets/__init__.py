"""Classroom widgets: each a model (plain Python), a matplotlib view and ipywidgets controls.

Display one by ending a notebook cell with it; ``.widget`` is its root container.
"""

from .labeler import LabelModel, TargetLabeler
from .stepper import HopfieldStepper, StepperModel

__all__ = ["HopfieldStepper", "LabelModel", "StepperModel", "TargetLabeler"]
