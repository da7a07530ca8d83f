"""The student's JupyterLab as ``./lab.sh`` sets it up: no nbgrader extensions (their Validate
button said "Success" on a notebook with no answer, as the student notebooks carry no graded
test cells) and ``notebooks/solutions/`` out of the file browser, yet open on purpose by path.

``./lab.sh setup`` runs for real in a copy of the repository's set-up files whose ``.venv`` is
this test environment's interpreter (already installed: the stamp says so, so nothing is
downloaded); then the real ``jupyter labextension list`` and a real Jupyter server (loopback,
temporary directories) read the configuration it wrote.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import urllib.error
import urllib.request
from pathlib import Path

import pytest

from tests.support.realros import free_port, skip_or_fail
from tests.flow.test_browser_byteviewer import _stop_server, _wait_http

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
TOKEN = "student-view-test"

pytestmark = [pytest.mark.slow, pytest.mark.timeout(120)]


@pytest.fixture(scope="module")
def lab_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A copy of the set-up files after ``./lab.sh setup``; its .venv is this environment."""
    tmp = tmp_path_factory.mktemp("lab")
    shutil.copy(ROOT / "lab.sh", tmp / "lab.sh")
    shutil.copy(ROOT / "pyproject.toml", tmp / "pyproject.toml")
    shutil.copytree(ROOT / "data", tmp / "data")
    venv = tmp / ".venv"
    (venv / "bin").mkdir(parents=True)
    (venv / "bin" / "python").symlink_to(sys.executable)
    checksum = subprocess.run(["cksum"], stdin=open(tmp / "pyproject.toml", "rb"),
                              capture_output=True, text=True, check=True).stdout.rstrip("\n")
    (venv / ".rosfpga-lab-installed").write_text(f"{checksum} \n")
    proc = subprocess.run(["bash", str(tmp / "lab.sh"), "setup"], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "installing" not in proc.stdout        # nothing fetched: the stamp held
    return tmp


def _env(lab_dir: Path, tmp: Path) -> dict[str, str]:
    """This environment's Jupyter reading the configuration lab.sh wrote into .venv/etc/jupyter."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("JUPYTER", "IPYTHON"))}
    for name in ("JUPYTER_CONFIG_DIR", "JUPYTER_RUNTIME_DIR", "JUPYTER_DATA_DIR", "IPYTHONDIR"):
        path = tmp / name.lower()
        path.mkdir(exist_ok=True)
        env[name] = str(path)
    env["JUPYTER_CONFIG_PATH"] = str(lab_dir / ".venv" / "etc" / "jupyter")
    env["JUPYTER_PLATFORM_DIRS"] = "1"
    return env


def test_lab_sh_installs_the_student_configuration(lab_dir: Path) -> None:
    etc = lab_dir / ".venv" / "etc" / "jupyter"
    page = json.loads((etc / "labconfig" / "page_config.json").read_text())
    assert page["disabledExtensions"]["@jupyter/nbgrader"] is True
    server = json.loads((etc / "jupyter_lab_config.json").read_text())
    assert "solutions" in server["ContentsManager"]["hide_globs"]
    extensions = json.loads((etc / "jupyter_server_config.json").read_text())
    assert extensions["ServerApp"]["jpserver_extensions"][
        "nbgrader.server_extensions.formgrader"] is False
    settings = lab_dir / ".venv" / "share" / "jupyter" / "lab" / "settings" / "overrides.json"
    assert settings.read_text() == (ROOT / "data" / "jupyterlab_overrides.json").read_text()


def test_student_lab_has_no_nbgrader_extension(lab_dir: Path, tmp_path: Path) -> None:
    if not (BIN / "jupyter-labextension").exists():
        skip_or_fail("jupyterlab not installed", "ROSFPGA_REQUIRE_COURSE")
    try:
        import nbgrader  # noqa: F401
    except ImportError:
        skip_or_fail("nbgrader not installed (pip install -e '.[course]')", "ROSFPGA_REQUIRE_COURSE")
    proc = subprocess.run([str(BIN / "jupyter-labextension"), "list"], env=_env(lab_dir, tmp_path),
                          capture_output=True, text=True, timeout=60)
    listing = proc.stdout + proc.stderr
    line = [ln for ln in listing.splitlines() if "@jupyter/nbgrader" in ln]
    assert line, listing                                 # installed in this environment ...
    assert "disabled" in line[0] and "enabled" not in line[0].replace("disabled", ""), listing
    # ... and without the lab's configuration it would be on (what a student saw before). Not
    # checkable where this environment's own prefix already holds the lab's page config (a .venv
    # that ./lab.sh set up, as CI's is): Jupyter always reads <sys.prefix>/etc/jupyter.
    own = Path(sys.prefix) / "etc" / "jupyter" / "labconfig" / "page_config.json"
    if own.exists() and "@jupyter/nbgrader" in own.read_text():
        return
    bare = subprocess.run([str(BIN / "jupyter-labextension"), "list"],
                          env={**_env(lab_dir, tmp_path), "JUPYTER_CONFIG_PATH": str(tmp_path)},
                          capture_output=True, text=True, timeout=60)
    bare_line = [ln for ln in (bare.stdout + bare.stderr).splitlines() if "@jupyter/nbgrader" in ln]
    assert bare_line and "enabled" in bare_line[0]


def test_solutions_are_out_of_the_file_browser_but_open_by_path(lab_dir: Path, tmp_path: Path) -> None:
    if not (BIN / "jupyter-lab").exists():
        skip_or_fail("jupyterlab not installed", "ROSFPGA_REQUIRE_COURSE")
    notebooks = tmp_path / "notebooks"                  # the student's notebooks/ (two of them)
    (notebooks / "solutions").mkdir(parents=True)
    for name in ("01_xmlrpc_handshake.ipynb",):
        shutil.copy(ROOT / "notebooks" / name, notebooks / name)
        shutil.copy(ROOT / "notebooks" / "solutions" / name, notebooks / "solutions" / name)
    port = free_port()
    base = f"http://127.0.0.1:{port}/"
    log = tmp_path / "server.log"
    with open(log, "wb") as out:
        server = subprocess.Popen(
            [str(BIN / "jupyter-lab"), "--no-browser", f"--port={port}", "--port-retries=0",
             "--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={TOKEN}",
             f"--ServerApp.root_dir={notebooks}", *(["--allow-root"] if os.geteuid() == 0 else [])],
            env=_env(lab_dir, tmp_path), cwd=notebooks, stdout=out, stderr=subprocess.STDOUT,
            start_new_session=True)
    try:
        _wait_http(f"{base}api/status?token={TOKEN}", 60, server, log)
        with urllib.request.urlopen(f"{base}api/contents/?token={TOKEN}", timeout=10) as resp:
            listed = [item["name"] for item in json.load(resp)["content"]]
        assert listed == ["01_xmlrpc_handshake.ipynb"]          # no solutions/ in the browser
        url = f"{base}api/contents/solutions/01_xmlrpc_handshake.ipynb?content=0&token={TOKEN}"
        with urllib.request.urlopen(url, timeout=10) as resp:   # ... but open on purpose
            assert json.load(resp)["type"] == "notebook"
        # nbgrader's teacher pages are not served ("Manage Assignments" at /formgrader)
        for page in ("formgrader", "formgrader/manage_assignments"):
            with pytest.raises(urllib.error.HTTPError) as info:
                urllib.request.urlopen(f"{base}{page}?token={TOKEN}", timeout=10)
            assert info.value.code == 404, page
        with urllib.request.urlopen(f"{base}lab?token={TOKEN}", timeout=10) as resp:
            assert resp.status == 200                            # the lab itself is
    finally:
        _stop_server(server, base)
