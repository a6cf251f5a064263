"""nbgrader's exchange, made private between students (deploy/course/nbgrader_config.py).

* :class:`PrivateSubmit`: a submission is readable by its owner and the teacher's group only.
* :class:`OwnerCollect`: a submission counts for the account that owns it, never for the name it
  claims (``nbgrader submit --student=someone``); every collect takes the latest one.
* :class:`KeylessRelease`: a released assignment holds no ground truth that none of its notebooks reads.
* :class:`FeedbackWithoutTests`: feedback never shows the hidden tests, which nbgrader's does by
  design (jupyter/nbgrader#917).
"""

from __future__ import annotations

import os
import pwd
import shutil

from nbgrader.exchange.default.collect import ExchangeCollect
from nbgrader.exchange.default.release_assignment import ExchangeReleaseAssignment
from nbgrader.exchange.default.submit import ExchangeSubmit
from nbgrader.preprocessors import ClearHiddenTests
from nbgrader.utils import ignore_patterns
from traitlets import Bool

__all__ = ["GROUND_TRUTH", "FeedbackWithoutTests", "KeylessRelease", "OwnerCollect", "PrivateSubmit"]

#: An image pair's ground truth (ismb_lab.scenes.gallery.PAIR_FILES): the answer key, the disparity map
#: it is computed from, and the scene's description.
GROUND_TRUTH = ("answer_key.json", "disparity.png", "scene.json")

FILE_MODE, FOLDER_MODE = 0o640, 0o2770


def _owner(path: str) -> str:
    uid = os.lstat(path).st_uid
    try:
        return pwd.getpwuid(uid).pw_name
    except KeyError:
        return f"uid{uid}"


class PrivateSubmit(ExchangeSubmit):
    """nbgrader's submit, with the submission readable by its owner and the teacher's group only."""

    def set_perms(self, dest, fileperms, dirperms):
        super().set_perms(dest, FILE_MODE, FOLDER_MODE)

    def do_copy(self, src, dest, log=None):
        """Copy into a submission folder made here, inside ``inbound/``.

        nbgrader's copy ends by giving the submission folder the mode of the student's folder, which drops
        the set-group-id bit it had from ``inbound/``; ``timestamp.txt`` and ``submission_secret.txt`` would
        then have the student's group and be unreadable to the teacher.  Subfolders are nbgrader's copies.
        """
        if os.path.dirname(os.path.abspath(dest)) != os.path.abspath(self.inbound_path):
            return super().do_copy(src, dest, log)     # the student's own cache copy
        size, limit = self.get_size(src), 1000 * self.coursedir.max_dir_size
        if size > limit:
            raise RuntimeError(f"Directory size is too big. Size is {size}, maximum size is {limit}")
        names = os.listdir(src)
        skip = ignore_patterns(exclude=self.coursedir.ignore, include=self.coursedir.include,
                               max_file_size=self.coursedir.max_file_size, log=self.log)(src, names)
        os.mkdir(dest)
        for name in sorted(set(names) - set(skip)):
            source, target = os.path.join(src, name), os.path.join(dest, name)
            if os.path.isdir(source):
                super().do_copy(source, target)
            else:
                shutil.copy2(source, target)

    def copy_files(self):
        super().copy_files()
        # nbgrader opens the submission's top folder to everyone (0777) so that the teacher
        # can delete it; the teacher's group can, with 2770.
        os.chmod(os.path.join(self.inbound_path, self.assignment_filename), FOLDER_MODE)


class OwnerCollect(ExchangeCollect):
    """nbgrader's collect, filing each submission under the account that owns it, and taking
    a newer submission than the one collected before."""

    update = Bool(True, help="Replace a collected submission by a newer one (nbgrader's --update; "
                             "on by default: collect always takes the latest)").tag(config=True)

    def _path_to_record(self, path):
        record = super()._path_to_record(path)
        owner = _owner(path)
        if owner != record["username"]:
            self.log.warning("%s claims to be by %s but %s handed it in: collected as %s's",
                             path, record["username"], owner, owner)
            record["username"] = owner
        return record


def _unread(folder: str) -> list:
    """The ground-truth file names that no notebook in `folder` names (notebook 00 scores a
    match with the answer key, so its assignment keeps it)."""
    texts = []
    for top, _, names in os.walk(folder):
        for name in names:
            if name.endswith(".ipynb"):
                with open(os.path.join(top, name), encoding="utf-8") as text:
                    texts.append(text.read())
    return [name for name in GROUND_TRUTH if not any(name in text for text in texts)]


class KeylessRelease(ExchangeReleaseAssignment):
    """nbgrader's release, leaving out an image pair's ground truth that no notebook of the
    assignment reads (the labels assignment asks the students for what the answer key holds)."""

    def do_copy(self, src, dest, log=None):
        unread = _unread(src) if os.path.abspath(dest) == os.path.abspath(self.dest_path) else []
        if not unread:
            return super().do_copy(src, dest, log)
        kept = list(self.coursedir.ignore)
        self.coursedir.ignore = [*kept, *unread]
        try:
            super().do_copy(src, dest, log)
        finally:
            self.coursedir.ignore = kept
        self.log.info("Left out %s: no notebook of %s reads them", ", ".join(unread), self.coursedir.assignment_id)


class FeedbackWithoutTests(ClearHiddenTests):
    """A preprocessor of nbgrader's feedback (``GenerateFeedback.preprocessors``): each hidden
    test region is cleared again, and a failed test cell's traceback, which quotes the test, is cut to
    its last line."""

    def preprocess_cell(self, cell, resources, cell_index):
        if cell.cell_type == "code" and self._remove_hidden_test_region(cell):
            for output in cell.get("outputs", []):
                if output.get("output_type") == "error":
                    output["traceback"] = [f"{output.get('ename', 'Error')}: {output.get('evalue', '')}"]
        return cell, resources
