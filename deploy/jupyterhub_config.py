"""JupyterHub for a class working through ismb_lab's notebooks on one lab server.

Start it from the repository root (as root, so that it can start each student's server
as that student):

    jupyterhub -f deploy/jupyterhub_config.py

Each student logs in with their own account on this machine (PAM), gets their own
single-user JupyterLab, and on first login a copy of ``notebooks/``, ``images/`` and ``manifests/`` in
``~/ismb_lab/``; JupyterLab opens ``00_start_here``.  Everything a student saves,
their targets files included, stays in their own home folder.  See deploy/README.md for
what to change for a real course.
"""

import os
import shutil
from pathlib import Path

c = get_config()  # noqa: F821  (JupyterHub's config loader provides it)

#: The repository whose notebooks and images each student gets a copy of.
PROJECT = Path(os.environ.get("ISMB_LAB_PROJECT", Path(__file__).resolve().parents[1]))
#: Where the copy goes, relative to the student's home folder.
COPY = "ismb_lab"

c.JupyterHub.ip = os.environ.get("ISMB_HUB_IP", "127.0.0.1")   # put TLS or a proxy in front for more
c.JupyterHub.port = int(os.environ.get("ISMB_HUB_PORT", "8000"))
c.JupyterHub.authenticator_class = "pam"          # the lab's own accounts
c.JupyterHub.spawner_class = "localprocess"       # one process per student, as that student
c.Spawner.default_url = f"/lab/tree/{COPY}/notebooks/00_start_here.ipynb"
c.Spawner.notebook_dir = "~"
c.Spawner.start_timeout = 120
c.Spawner.http_timeout = 120
# A kernel with the widgets needs about 200-300 MB (deploy/README.md); ask for room, where
# the spawner enforces it.
c.Spawner.mem_limit = "1G"


def copy_course(spawner) -> None:
    """Give a student their own copy of the notebooks, images and manifests on first login."""
    if hasattr(spawner, "home_dir_template"):      # SimpleLocalProcessSpawner: a folder per user
        home = Path(spawner.home_dir_template.format(username=spawner.user.name))
    else:
        import pwd
        home = Path(pwd.getpwnam(spawner.user.name).pw_dir)
    target = home / COPY
    if target.exists():
        return
    target.mkdir(parents=True)
    for name in ("notebooks", "images", "manifests"):
        shutil.copytree(PROJECT / name, target / name,
                        ignore=shutil.ignore_patterns(".ipynb_checkpoints", "targets-*.json", "my_targets*.json",
                                                     "params-*.json", ".targets-*.lock", "photos-*", "solutions"))
    try:
        shutil.chown(target, spawner.user.name)
        for path in target.rglob("*"):
            shutil.chown(path, spawner.user.name)
    except (LookupError, PermissionError):
        pass   # no such OS user (a test's simple spawner), or not root: the files stay as they are


c.Spawner.pre_spawn_hook = copy_course
