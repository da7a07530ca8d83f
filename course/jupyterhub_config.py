# JupyterHub for a rosfpga_lab course: one server, many Unix users (course/README.md).
#
# Run as root from the hub's state directory (it keeps jupyterhub.sqlite and the cookie secret
# there), with the shared environment that course/setup.sh made:
#     cd /srv/rosfpga-lab && /opt/rosfpga-lab/venv/bin/jupyterhub -f /path/to/course/jupyterhub_config.py
# Students log in with their Unix name and password (PAM) if they are in STUDENTS_GROUP; members
# of TEACHERS_GROUP log in as hub admins. Each user's single-user JupyterLab runs as that user,
# from the shared environment, in their home directory; on every start the student notebooks
# they do not have yet are copied into ~/rosfpga-lab (their own copies are never overwritten).
#
# Many students on one machine share its loopback interface: the notebooks start their ROS
# masters and nodes on free ports (port 0), never on roscore's 11311, and each user gets a
# private TMPDIR, so one user's notebook can neither join nor disturb another's.
import os
import sys
from pathlib import Path

c = get_config()  # noqa: F821 (JupyterHub defines it)

HERE = Path(__file__).resolve().parent
#: Unix group whose members may log in; setup.sh creates it.
STUDENTS_GROUP = "rosfpga-students"
#: Unix group whose members log in as hub admins (teachers); setup.sh creates it.
TEACHERS_GROUP = "rosfpga-teachers"
#: The student notebooks every user gets a copy of (setup.sh installs them there).
NOTEBOOKS = Path(os.environ.get("ROSFPGA_COURSE_NOTEBOOKS", "/opt/rosfpga-lab/notebooks"))
#: Where each user's copies go, relative to their home directory.
WORKDIR = "rosfpga-lab"
#: The environment the hub runs in is the shared one the single-user servers run from.
ENV_BIN = Path(sys.prefix) / "bin"

# The hub listens on loopback by default; on a server, open it to the students with TLS:
#   jupyterhub -f ... --ip 0.0.0.0 --port 443 --ssl-key KEY --ssl-cert CERT
c.JupyterHub.ip = "127.0.0.1"
c.JupyterHub.port = 8000

# JupyterHub's proxy from npm: course/node_modules (`npm ci` in course/), else the PATH.
_proxy = HERE / "node_modules" / ".bin" / "configurable-http-proxy"
if _proxy.exists():
    c.ConfigurableHTTPProxy.command = [str(_proxy)]

c.JupyterHub.authenticator_class = "pam"
c.PAMAuthenticator.allowed_groups = {STUDENTS_GROUP, TEACHERS_GROUP}
c.PAMAuthenticator.admin_groups = {TEACHERS_GROUP}

c.JupyterHub.spawner_class = "localprocess"
c.Spawner.cmd = [str(ENV_BIN / "jupyterhub-singleuser")]
c.Spawner.notebook_dir = "~"
c.Spawner.default_url = f"/lab/tree/{WORKDIR}"
c.Spawner.start_timeout = 120
c.Spawner.http_timeout = 120
# The hub passes almost nothing of its own environment on: PATH puts the shared environment
# first (jupyter, python) and keeps the system's tools (Debian's rostopic, g++) reachable.
c.Spawner.environment = {
    "PATH": os.pathsep.join([str(ENV_BIN), "/usr/local/bin", "/usr/bin", "/bin"]),
    "LANG": os.environ.get("LANG", "C.UTF-8"),
    "TMPDIR": lambda spawner: str(Path(_home(spawner)) / ".cache" / WORKDIR / "tmp"),
}

# Run as the user, so nothing is written into a home directory with root's rights.
_PREPARE = """
import os, shutil, sys
from pathlib import Path
src, work, tmp = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
work.mkdir(exist_ok=True)
tmp.mkdir(parents=True, exist_ok=True)
tmp.chmod(0o700)
for nb in sorted(src.glob("[0-9][0-9]_*.ipynb")):
    if not (work / nb.name).exists():
        shutil.copyfile(nb, work / nb.name)
"""


def _home(spawner) -> str:
    import pwd

    return pwd.getpwnam(spawner.user.name).pw_dir


def prepare_home(spawner) -> None:
    """Copy the notebooks the user lacks into ~/rosfpga-lab and make their TMPDIR (as the user)."""
    import pwd
    import subprocess

    entry = pwd.getpwnam(spawner.user.name)
    home = Path(entry.pw_dir)
    subprocess.run(
        [sys.executable, "-c", _PREPARE, str(NOTEBOOKS), str(home / WORKDIR),
         str(home / ".cache" / WORKDIR / "tmp")],
        user=entry.pw_uid, group=entry.pw_gid, extra_groups=[], cwd=home,
        env={"HOME": str(home), "PATH": "/usr/bin:/bin"}, check=True, timeout=60)


c.Spawner.pre_spawn_hook = prepare_home
