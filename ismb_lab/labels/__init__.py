"""Target pairs a person labelled: the file format, and each student's own files in a class.
"""

from .targets import (MAX_BYTES, MAX_PAIRS, VERSION, check_one_to_one, load_targets, many_to_one, save_targets, snap,
    Snapped, targets_from_matches, TargetSet)
from .classroom import (collected, Merged, Pool, pool, save_merging, SIBLINGS, targets_path, user_name, voila_without_hub)

__all__ = ["MAX_BYTES", "MAX_PAIRS", "Merged", "Pool", "SIBLINGS", "Snapped", "TargetSet", "VERSION",
           "check_one_to_one", "collected", "load_targets", "many_to_one", "pool", "save_merging",
           "save_targets", "snap", "targets_from_matches", "targets_path", "user_name", "voila_without_hub"]
