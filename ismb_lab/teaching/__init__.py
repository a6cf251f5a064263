"""The course around the notebooks: exercise checks, the nbgrader course, and the class hub's start.
"""

from .exercises import (check_depth_range, check_disparity, check_energy_derivation, check_error_kinds, check_fitness,
    check_harris_response, check_hopfield_form, check_transfer, Feedback, random_network)
from .course import (ASSIGNMENTS, Assignment, CODE_STUB, course_images, make_source, repository, student_notebook)
from .exchange import GROUND_TRUTH, FeedbackWithoutTests, KeylessRelease, OwnerCollect, PrivateSubmit

__all__ = ["ASSIGNMENTS", "Assignment", "CODE_STUB", "Feedback", "FeedbackWithoutTests", "GROUND_TRUTH",
           "KeylessRelease", "OwnerCollect", "PrivateSubmit", "check_depth_range", "check_disparity",
           "check_energy_derivation", "check_error_kinds", "check_fitness", "check_harris_response",
           "check_hopfield_form", "check_transfer", "course_images", "make_source", "random_network",
           "repository", "student_notebook"]
