"""JupyterHub for a class working through ismb_lab's notebooks on one lab server.

Start it as root (so that it can start each student's server as that student), from the
venv that deploy/README.md has you build, with the class's settings in the environment:

    ISMB_HUB_GROUP=ismbclass ISMB_HUB_ADMINS=teacher nohup /opt/ismb-lab/venv/bin/jupyterhub \\
        -f /opt/ismb-lab/repo/deploy/jupyterhub_config.py >> /var/log/ismb-hub.log 2>&1 &

and stop it with ``kill "$(cat /var/lib/ismb-hub/jupyterhub.pid)"``.

Every setting a course changes is an ``ISMB_HUB_*`` environment variable, listed with its
default in deploy/README.md; nothing else needs editing. Each student logs in with their
own account (PAM) and gets their own JupyterLab, started as them by
``python -m ismb_lab.teaching.hub_start serve``: that command copies the course folder into
``~/ismb_lab`` (mode 700) with the student's own rights, then starts the server. Root
never writes in a home. The course folder's ``config`` is the students' Jupyter config,
its ``teacher-config`` the teachers' (hub admins'), its ``numba`` the compiled kernels that
every student's process copies (all made by ``python -m ismb_lab.teaching.hub_start stage``).
"""

import os
import sys
from pathlib import Path

from jupyterhub.spawner import LocalProcessSpawner

from ismb_lab.teaching import hub_start

c = get_config()  # noqa: F821  (JupyterHub's config loader provides it)


def setting(name: str, default: str) -> str:
    return os.environ.get(f"ISMB_HUB_{name}", default).strip() or default


def names(name: str) -> set:
    return {n for n in os.environ.get(f"ISMB_HUB_{name}", "").replace(",", " ").split() if n}


VENV = Path(setting("VENV", "/opt/ismb-lab/venv"))
COURSE = Path(setting("COURSE", "/opt/ismb-lab/course"))
STATE = Path(setting("STATE", "/var/lib/ismb-hub"))
MEM_LIMIT = hub_start.parse_size(setting("MEM_LIMIT", "2G"))
CULL_TIMEOUT = int(setting("CULL_TIMEOUT", "3600"))
KERNEL_CULL_TIMEOUT = int(setting("KERNEL_CULL_TIMEOUT", "1200"))
for path, what in ((VENV / "bin" / "python", "ISMB_HUB_VENV's python"), (COURSE / "notebooks", "ISMB_HUB_COURSE")):
    if not path.exists():
        sys.exit(f"jupyterhub_config: {path} is missing: set {what} (deploy/README.md)")

# Logins: the machine's accounts, only those of the course group or list; never everyone.
c.JupyterHub.authenticator_class = "pam"
# Admins (the teachers) may log in too; JupyterHub does not let them in by being admins alone.
c.PAMAuthenticator.allowed_groups = names("GROUP") | names("ADMIN_GROUP")
c.Authenticator.allowed_users = names("USERS") | names("ADMINS")
c.Authenticator.admin_users = names("ADMINS")
c.PAMAuthenticator.admin_groups = names("ADMIN_GROUP")
if not (names("GROUP") or names("USERS")):
    sys.exit("jupyterhub_config: set ISMB_HUB_GROUP (the course's group) or ISMB_HUB_USERS (deploy/README.md)")

# Where it listens: the public port, the proxy's API and the hub's own port on loopback.
c.JupyterHub.ip = setting("IP", "127.0.0.1")                # put TLS or a proxy in front for more
c.JupyterHub.port = int(setting("PORT", "8000"))
c.JupyterHub.hub_ip = "127.0.0.1"
c.JupyterHub.hub_port = int(setting("HUB_PORT", "8081"))
c.ConfigurableHTTPProxy.api_url = f"http://127.0.0.1:{int(setting('API_PORT', '8001'))}"

# The hub's state (database, cookie secret, proxy pid) in a folder of root's alone.
os.umask(0o077)
STATE.mkdir(mode=0o700, parents=True, exist_ok=True)
os.chmod(STATE, 0o700)
c.JupyterHub.db_url = f"sqlite:///{STATE / 'jupyterhub.sqlite'}"
c.JupyterHub.cookie_secret_file = str(STATE / "jupyterhub_cookie_secret")
c.ConfigurableHTTPProxy.pid_file = str(STATE / "jupyterhub-proxy.pid")
# The hub's own PID, to stop it (kill "$(cat .../jupyterhub.pid)": it stops the proxy and the servers).
c.JupyterHub.pid_file = str(STATE / "jupyterhub.pid")


class CourseSpawner(LocalProcessSpawner):
    """LocalProcessSpawner whose servers start inside the student's cgroups (where the machine
    has writable cgroup v1) and under RLIMIT_DATA, before they drop root; a teacher's (a hub
    admin's) server reads the teachers' Jupyter config folder, with the Formgrader on."""

    cgroups = []

    def get_env(self):
        env = super().get_env()
        if self.user.admin and (COURSE / "teacher-config").is_dir():
            env["JUPYTER_CONFIG_PATH"] = str(COURSE / "teacher-config")
            if os.environ.get("ISMB_COURSE_ROOT"):
                env["ISMB_COURSE_ROOT"] = os.environ["ISMB_COURSE_ROOT"]
        return env

    async def start(self):
        self.cgroups = hub_start.make_cgroups(self.user.name, MEM_LIMIT)
        if not self.cgroups:
            self.log.warning("no writable cgroup v1 memory controller: %s is limited by RLIMIT_DATA alone",
                             self.user.name)
        return await super().start()

    def make_preexec_fn(self, name):
        become_student, cgroups = super().make_preexec_fn(name), list(self.cgroups)

        def preexec():
            hub_start.enter(cgroups, MEM_LIMIT)
            become_student()
        return preexec

    async def stop(self, now=False):
        await super().stop(now=now)
        busy = hub_start.remove_cgroups(hub_start.cgroup_dirs(self.user.name))
        if busy:
            self.log.warning("cgroups of %s still hold processes: %s", self.user.name, busy)


# Servers: one per student, started as that student from the class venv.
c.JupyterHub.spawner_class = CourseSpawner
c.Spawner.cmd = [str(VENV / "bin" / "python"), "-m", "ismb_lab.teaching.hub_start", "serve"]
c.Spawner.environment = {
    "ISMB_HUB_COURSE": str(COURSE),
    # nbgrader's course and exchange (deploy/course/), teacher tools hidden: staged by hub_start.
    "JUPYTER_CONFIG_PATH": str(COURSE / "config"),
    # The kernels the teacher compiled once (hub_start stage): each student's process copies them.
    "ISMB_NUMBA_SHARED": str(COURSE / "numba"),
    **{name: os.environ[name] for name in ("ISMB_COURSE_ID", "ISMB_NBGRADER_EXCHANGE") if name in os.environ},
    "PATH": f"{VENV / 'bin'}:/usr/local/bin:/usr/bin:/bin",
    # Activity reports often enough for the culler's timeout.
    "JUPYTERHUB_ACTIVITY_INTERVAL": str(max(5, min(300, CULL_TIMEOUT // 4))),
}
# A kernel whose tab closed (no connection) and that has been idle is shut down. Kernels talk
# to their server over Unix sockets in the student's private runtime folder (hub_start serve
# makes it), not TCP ports: thirty kernels starting at once raced for free ports ("Address
# already in use", kernel died), and a port on 127.0.0.1 is open to every account.
c.Spawner.args = [f"--MappingKernelManager.cull_idle_timeout={KERNEL_CULL_TIMEOUT}",
                  f"--MappingKernelManager.cull_interval={max(5, min(300, KERNEL_CULL_TIMEOUT // 4))}",
                  "--MappingKernelManager.cull_connected=False",
                  "--KernelManager.transport=ipc"]
c.Spawner.default_url = f"/lab/tree/{hub_start.COPY}/notebooks/00_start_here.ipynb"
c.Spawner.notebook_dir = "~"
c.Spawner.start_timeout = 120
c.Spawner.http_timeout = 120
c.JupyterHub.last_activity_interval = max(5, min(300, CULL_TIMEOUT // 4))

# Idle servers are stopped by jupyterhub-idle-culler, a service of the hub.
c.JupyterHub.services = [{
    "name": "idle-culler",
    "command": [sys.executable, "-m", "jupyterhub_idle_culler", f"--timeout={CULL_TIMEOUT}",
                f"--cull-every={max(5, min(300, CULL_TIMEOUT // 4))}"],
}]
c.JupyterHub.load_roles = [{
    "name": "idle-culler",
    "scopes": ["list:users", "read:users:activity", "read:servers", "delete:servers"],
    "services": ["idle-culler"],
}]
