"""Classroom widgets: each a model (plain Python), a matplotlib or k3d view and ipywidgets controls.

Display one by ending a notebook cell with it; ``.widget`` is its root container.
"""

from .cloud import PointCloudView
from .depth_demo import DepthDemo, DepthModel
from .explorer import ExplorerModel, ParameterExplorer
from .ga_runner import GAModel, GARunner
from .labeler import LabelModel, TargetLabeler
from .photos import PhotoLoader, PhotoModel
from .rig_cloud import RigCloud, RigCloudModel
from .stepper import HopfieldStepper, StepperModel

__all__ = ["DepthDemo", "DepthModel", "ExplorerModel", "GAModel", "GARunner", "HopfieldStepper",
           "LabelModel", "ParameterExplorer", "PhotoLoader", "PhotoModel", "PointCloudView", "RigCloud",
           "RigCloudModel", "StepperModel", "TargetLabeler"]
