"""nbgrader's exchange, made private between students (deploy/course/nbgrader_config.py).

* :class:`PrivateSubmit`: a submission's files are 0640 and its folders 2770, with the
  group of the exchange's ``inbound/`` (set-group-id: the teacher's group).  nbgrader's
  own submit leaves them 0644 in a 0777 folder, hidden only by an unguessable name.
* :class:`OwnerCollect`: a submission counts for the account that owns it in the
  exchange, never for the name it claims (``nbgrader submit --student=someone``); the
  folder ``submitted/<student>/`` is therefore who handed the work in.
"""

from __future__ import annotations

import os
import pwd
import shutil

from nbgrader.exchange.default.collect import ExchangeCollect
from nbgrader.exchange.default.submit import ExchangeSubmit
from nbgrader.utils import ignore_patterns

__all__ = ["OwnerCollect", "PrivateSubmit"]

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

        nbgrader's copy ends by giving the submission folder the mode of the student's
        folder, which drops the set-group-id bit it had from ``inbound/`` (a student is not
        in the teacher's group); ``timestamp.txt`` and ``submission_secret.txt``, written
        next, would then have the student's group and, private, be unreadable to the
        teacher.  Made here, the folder keeps the bit; subfolders are nbgrader's copies.
        """
        if os.path.dirname(os.path.abspath(dest)) != os.path.abspath(self.inbound_path):
            return super().do_copy(src, dest, log)     # the student's own cache copy
        limit = 1000 * self.coursedir.max_dir_size
        if self.get_size(src) > limit:
            raise RuntimeError(f"Directory size is too big. Size is {self.get_size(src)}, maximum size is {limit}")
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
    """nbgrader's collect, filing each submission under the account that owns it."""

    def _path_to_record(self, path):
        record = super()._path_to_record(path)
        owner = _owner(path)
        if owner != record["username"]:
            self.log.warning("%s claims to be by %s but %s handed it in: collected as %s's",
                             path, record["username"], owner, owner)
            record["username"] = owner
        return record
