"""A course on one server: real JupyterHub (course/jupyterhub_config.py), three Unix users at once.

As root, the test creates three Unix users in the course's students group, starts JupyterHub
with the course's own configuration on free loopback ports (plus a test service token, so it can
drive the hub through its REST API), has one user log in through PAM with the password, spawns
the three users' single-user servers (local processes, each as its user) and, through the hub's
proxy, runs notebooks 0, 2 (solved) and 7 in all three servers at the same time: each code cell
goes to a kernel over the Jupyter server's kernel websocket. Every cell must pass, each user's
notebooks must be that user's own copies, and the three users' ROS masters must be three
different ones. A user's node that relies on the default master must not join another user's.
Then the teacher releases notebook 2 with nbgrader, each student fetches and submits it through
JupyterLab's Assignments panel (its REST calls, through the hub), and the teacher collects.
Users, groups and servers are removed afterwards, also on failure.

It needs root and the course server that ``course/setup.sh`` installs (the shared environment in
``/opt/rosfpga-lab`` or ``ROSFPGA_COURSE_PREFIX``, holding this checkout's lab, and
configurable-http-proxy); without them it skips with a reason, with ``ROSFPGA_REQUIRE_COURSE=1``
(CI, whose ``.ci/run`` runs ``course/setup.sh`` first) it fails.
"""

from __future__ import annotations

import asyncio
import datetime
import grp
import json
import os
import pwd
import re
import secrets
import shutil
import signal
import subprocess
import sys
import time
import urllib.parse
import uuid
from collections.abc import Iterator
from pathlib import Path

import nbformat
import pytest

from tests.support.realros import free_port, skip_or_fail
from tests.flow.test_notebooks_exec import check_real_ros_part, text_of
from rosfpga_lab.checks import nbbuild

ROOT = Path(__file__).resolve().parents[2]
COURSE = ROOT / "course"
HUB_CONFIG = COURSE / "jupyterhub_config.py"
#: Where course/setup.sh installed the shared environment and the student notebooks.
SHARED = Path(os.environ.get("ROSFPGA_COURSE_PREFIX", "/opt/rosfpga-lab"))
BIN = SHARED / "venv" / "bin"
#: nbgrader's settings for every user of the server (course id, exchange), by course/setup.sh.
NBGRADER_SERVER_CONFIG = Path("/etc/jupyter/nbgrader_config.py")
REQUIRE = "ROSFPGA_REQUIRE_COURSE"
#: The notebooks every user runs at once: (name in the user's folder, where it comes from).
RUNS = [("00_overview.ipynb", None),
        ("02_tcpros_solved.ipynb", ROOT / "notebooks" / "solutions" / "02_tcpros.ipynb"),
        ("07_workshop_demo.ipynb", None)]
USERS = 3
CELL_TIMEOUT = 180
SPAWN_TIMEOUT = 150

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]


def _proxy_command() -> str | None:
    local = COURSE / "node_modules" / ".bin" / "configurable-http-proxy"
    return str(local) if local.exists() else shutil.which("configurable-http-proxy")


def _missing() -> str | None:
    if sys.platform != "linux":
        return "a course server needs Linux (local Unix users)"
    if os.geteuid() != 0:
        return "not root: the test creates Unix users and JupyterHub spawns servers as them"
    for tool in ("useradd", "userdel", "groupadd", "groupdel", "chpasswd"):
        if shutil.which(tool) is None:
            return f"{tool} not found"
    if not (BIN / "jupyterhub").exists():
        return (f"no course server set up in {SHARED} (run course/setup.sh as root; "
                "ROSFPGA_COURSE_PREFIX names another place)")
    if _proxy_command() is None:
        return "configurable-http-proxy not installed (cd course && npm ci)"
    if not NBGRADER_SERVER_CONFIG.exists():
        return f"no {NBGRADER_SERVER_CONFIG} (nbgrader's exchange): run course/setup.sh as root"
    return _stale()


def _stale() -> str | None:
    """Why the shared environment does not hold this checkout's lab and notebooks, or None."""
    where = subprocess.run([str(BIN / "python"), "-c",
                            "import rosfpga_lab, os; print(os.path.dirname(rosfpga_lab.__file__))"],
                           capture_output=True, text=True, timeout=60)
    if where.returncode != 0:
        return f"the course environment {SHARED} has no rosfpga_lab: {where.stderr.strip()[-300:]}"
    pairs = [(p, Path(where.stdout.strip()) / p.relative_to(ROOT / "rosfpga_lab"))
             for p in (ROOT / "rosfpga_lab").rglob("*.py")]
    pairs += [(p, SHARED / "notebooks" / p.name)
              for p in (ROOT / "notebooks").glob(nbbuild.NOTEBOOK_GLOB)]
    for mine, theirs in pairs:
        if not theirs.exists() or theirs.read_bytes() != mine.read_bytes():
            return f"the course environment {SHARED} holds another version ({theirs}); re-run course/setup.sh"
    return None


def _course_settings() -> dict:
    """The course configuration as JupyterHub loads it (the test reads its groups from it)."""
    from traitlets.config.loader import PyFileConfigLoader

    config = PyFileConfigLoader(HUB_CONFIG.name, str(HUB_CONFIG.parent)).load_config()
    return {"students": sorted(config.PAMAuthenticator.allowed_groups),
            "teachers": sorted(config.PAMAuthenticator.admin_groups)}


def _sh(*cmd: str) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, f"{' '.join(cmd)}: {proc.stderr.strip()}"


@pytest.fixture
def unix_users() -> Iterator[list[tuple[str, str]]]:
    """Three new Unix users (name, password) in the course's students group; removed afterwards."""
    reason = _missing()
    if reason:
        skip_or_fail(reason, REQUIRE)
    settings = _course_settings()
    group = next(g for g in settings["students"] if g not in settings["teachers"])
    made_groups: list[str] = []
    tag = secrets.token_hex(3)
    users: list[tuple[str, str]] = []
    try:
        for name in sorted(set(settings["students"]) | set(settings["teachers"])):
            try:
                grp.getgrnam(name)
            except KeyError:   # as course/setup.sh does
                _sh("groupadd", name)
                made_groups.append(name)
        for i in range(USERS):
            name, password = f"rfl{tag}s{i}", secrets.token_urlsafe(12)
            _sh("useradd", "--create-home", "--shell", "/bin/bash", "--groups", group, name)
            users.append((name, password))
            subprocess.run(["chpasswd"], input=f"{name}:{password}\n", text=True, check=True,
                           timeout=60)
        yield users
    finally:
        for name, _ in users:
            subprocess.run(["userdel", "--remove", name], capture_output=True, timeout=60)
        for name in made_groups:
            subprocess.run(["groupdel", name], capture_output=True, timeout=60)


class Hub:
    """A running JupyterHub driven through its REST API with a service token."""

    def __init__(self, state: Path) -> None:
        self.token = secrets.token_hex(32)
        self.port, hub_port, api_port = free_port(), free_port(), free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        config = state / "test_hub_config.py"
        config.write_text(
            "c = get_config()  # noqa: F821\n"
            f"load_subconfig({str(HUB_CONFIG)!r})  # noqa: F821\n"
            f"c.JupyterHub.port = {self.port}\n"
            f"c.JupyterHub.hub_port = {hub_port}\n"
            f"c.ConfigurableHTTPProxy.api_url = 'http://127.0.0.1:{api_port}'\n"
            f"c.JupyterHub.services = [{{'name': 'course-test', 'api_token': {self.token!r}}}]\n"
            "c.JupyterHub.load_roles = [{'name': 'course-test', 'services': ['course-test'],\n"
            "    'scopes': ['admin:users', 'admin:servers', 'access:servers', 'read:users']}]\n")
        env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}",
                   ROSFPGA_COURSE_NOTEBOOKS=str(SHARED / "notebooks"))
        self.log = state / "jupyterhub.log"
        with open(self.log, "wb") as log:
            self.proc = subprocess.Popen([str(BIN / "jupyterhub"), "-f", str(config)], cwd=state,
                                         env=env, stdout=log, stderr=subprocess.STDOUT,
                                         start_new_session=True)

    def tail(self) -> str:
        return self.log.read_text(errors="replace")[-4000:]

    async def request(self, method: str, path: str, body: object = None, *,
                      ok: tuple[int, ...] = (200, 201, 202, 204), timeout: float = 60) -> object:
        from tornado.httpclient import AsyncHTTPClient, HTTPClientError, HTTPRequest

        req = HTTPRequest(f"{self.url}{path}", method=method, request_timeout=timeout,
                          headers={"Authorization": f"token {self.token}"},
                          body=None if body is None and method in ("GET", "DELETE") else
                          json.dumps(body if body is not None else {}))
        try:
            resp = await AsyncHTTPClient().fetch(req, raise_error=False)
        except (OSError, HTTPClientError) as exc:
            raise AssertionError(f"{method} {path}: {exc}") from None
        assert resp.code in ok, f"{method} {path}: {resp.code} {resp.body[:500]!r}"
        return json.loads(resp.body) if resp.body else None

    async def wait_up(self, timeout: float = 60) -> None:
        deadline = time.monotonic() + timeout
        while True:
            assert self.proc.poll() is None, f"JupyterHub exited:\n{self.tail()}"
            try:
                await self.request("GET", "/hub/api/", timeout=5)
                return
            except AssertionError:
                if time.monotonic() > deadline:
                    raise AssertionError(f"JupyterHub did not answer in {timeout} s:\n{self.tail()}")
                await asyncio.sleep(0.5)

    async def spawn(self, name: str) -> None:
        await self.request("POST", f"/hub/api/users/{name}", ok=(201, 409))
        await self.request("POST", f"/hub/api/users/{name}/server", ok=(201, 202))
        deadline = time.monotonic() + SPAWN_TIMEOUT
        while True:
            model = await self.request("GET", f"/hub/api/users/{name}")
            server = model.get("servers", {}).get("", {})
            if server.get("ready"):
                return
            assert time.monotonic() < deadline, f"{name}'s server not ready:\n{self.tail()}"
            await asyncio.sleep(1)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)   # the hub stops the users' servers too
            try:
                self.proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()


async def pam_login(hub: Hub, name: str, password: str) -> int:
    """Log in through the hub's login form (PAM); the status of the form's answer."""
    from tornado.httpclient import AsyncHTTPClient, HTTPRequest

    client = AsyncHTTPClient()
    page = await client.fetch(f"{hub.url}/hub/login", raise_error=False)
    xsrf = re.search(r'name="_xsrf" value="([^"]+)"', page.body.decode())
    cookies = "; ".join(c.split(";", 1)[0] for c in page.headers.get_list("Set-Cookie"))
    form = {"username": name, "password": password}
    if xsrf:
        form["_xsrf"] = xsrf[1]
    resp = await client.fetch(HTTPRequest(f"{hub.url}/hub/login", method="POST",
                                          body=urllib.parse.urlencode(form),
                                          headers={"Cookie": cookies}, follow_redirects=False),
                              raise_error=False)
    return resp.code


async def run_notebook(hub: Hub, user: str, path: str, extra: list[str], *,
                       keep: bool = False) -> tuple[list, str]:
    """Run every code cell of the user's notebook ``path`` (then ``extra`` code) in a new kernel
    of the user's server, over its kernel websocket; return the cells with their outputs and
    the session's id (its kernel is shut down unless ``keep``)."""
    from tornado.httpclient import HTTPRequest
    from tornado.websocket import websocket_connect

    base = f"/user/{user}/api"
    model = await hub.request("GET", f"{base}/contents/{path}?content=1")
    nb = nbformat.from_dict(model["content"])
    session = await hub.request("POST", f"{base}/sessions", {
        "path": path, "name": Path(path).name, "type": "notebook", "kernel": {"name": "python3"}})
    kernel = session["kernel"]["id"]
    ws_url = (f"ws://127.0.0.1:{hub.port}{base}/kernels/{kernel}/channels"
              f"?session_id={uuid.uuid4().hex}")
    conn = await websocket_connect(HTTPRequest(  # answers once the kernel runs: slow under load
        ws_url, headers={"Authorization": f"token {hub.token}"}, connect_timeout=CELL_TIMEOUT,
        request_timeout=CELL_TIMEOUT), max_message_size=64 * 2**20)
    session_id = uuid.uuid4().hex

    async def execute(code: str) -> tuple[list[dict], str]:
        msg_id = uuid.uuid4().hex
        conn.write_message(json.dumps({
            "header": {"msg_id": msg_id, "username": user, "session": session_id,
                       "msg_type": "execute_request", "version": "5.3",
                       "date": datetime.datetime.now(datetime.timezone.utc).isoformat()},
            "parent_header": {}, "metadata": {}, "channel": "shell", "buffers": [],
            "content": {"code": code, "silent": False, "store_history": True,
                        "user_expressions": {}, "allow_stdin": False, "stop_on_error": True}}))
        outputs: list[dict] = []
        idle = replied = False
        status = "?"
        while not (idle and replied):
            raw = await asyncio.wait_for(conn.read_message(), CELL_TIMEOUT)
            assert raw is not None, f"{user} {path}: kernel websocket closed"
            if isinstance(raw, bytes):
                continue                                   # binary comm traffic of widgets
            msg = json.loads(raw)
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            kind = msg["header"]["msg_type"]
            if kind == "execute_reply":
                replied, status = True, msg["content"]["status"]
            elif kind == "status" and msg["content"]["execution_state"] == "idle":
                idle = True
            elif kind == "clear_output":
                outputs.clear()
            elif kind in ("stream", "execute_result", "display_data", "error"):
                outputs.append(nbformat.v4.output_from_msg(msg))
        return outputs, status

    try:
        for cell in nb.cells:
            if cell.cell_type != "code":
                continue
            cell.outputs, status = await execute(cell.source)
            errors = [o for o in cell.outputs if o.output_type == "error"]
            assert status == "ok" and not errors, \
                f"{user} {path}: cell failed: {cell.source[:200]!r}: " \
                f"{[(e.ename, e.evalue) for e in errors]}"
        for code in extra:
            outputs, status = await execute(code)
            assert status == "ok", f"{user} {path}: {code!r} failed: {outputs}"
            nb.cells.append(nbformat.v4.new_code_cell(code, outputs=outputs))
    finally:
        conn.close()
        if not keep:
            await hub.request("DELETE", f"{base}/sessions/{session['id']}", ok=(204, 404))
    return nb.cells, session["id"]


def _text(cells: list) -> str:
    return "\n".join(text_of(c) for c in cells if c.cell_type == "code")


async def _course(hub: Hub, users: list[tuple[str, str]]) -> dict[str, dict[str, list]]:
    await hub.wait_up()
    login = await pam_login(hub, users[0][0], users[0][1])
    assert login == 302, f"PAM login of {users[0][0]} answered {login}:\n{hub.tail()}"
    assert await pam_login(hub, users[1][0], "wrong password") != 302
    await asyncio.gather(*(hub.spawn(name) for name, _ in users))

    for name, _ in users:
        listing = await hub.request("GET", f"/user/{name}/api/contents/rosfpga-lab")
        have = {item["name"] for item in listing["content"]}
        want = {p.name for p in (ROOT / "notebooks").glob(nbbuild.NOTEBOOK_GLOB)}
        assert want <= have, f"{name} lacks {sorted(want - have)}"
        owner = (Path(pwd.getpwnam(name).pw_dir) / "rosfpga-lab" / "00_overview.ipynb").stat().st_uid
        assert owner == pwd.getpwnam(name).pw_uid, f"{name}'s copy belongs to uid {owner}"
        for target, source in RUNS:
            if source is not None:   # a student who solved the exercises saves their notebook
                await hub.request("PUT", f"/user/{name}/api/contents/rosfpga-lab/{target}", {
                    "type": "notebook", "format": "json",
                    "content": json.loads(source.read_text(encoding="utf-8"))})

    async def one_user(name: str) -> dict[str, list]:
        done = {}
        for target, _ in RUNS:   # every one of them starts a master, named `master`
            done[target], _ = await run_notebook(hub, name, f"rosfpga-lab/{target}", [
                "import os, tempfile; print('MASTER', master.uri); "
                "print('TMPDIR', tempfile.gettempdir()); print('CWD', os.getcwd())"])
        return done

    runs = await asyncio.gather(*(one_user(name) for name, _ in users))
    results = dict(zip([n for n, _ in users], runs))

    # A node that relies on the default master, in each user's server in turn: the second and
    # third user must get masters of their own, not the first user's (on roscore's 11311 if free).
    probe = ("from rosfpga_lab.graph import Node\nimport warnings\n"
             "with warnings.catch_warnings():\n    warnings.simplefilter('ignore')\n"
             "    node = Node('/probe')\nprint('DEFAULT', node.master_uri)\nnode.shutdown()")
    defaults, kept = [], []
    for name, _ in users:   # each kernel stays up (with its master) while the next user probes
        base = f"/user/{name}/api"
        await hub.request("PUT", f"{base}/contents/rosfpga-lab/probe.ipynb", {
            "type": "notebook", "format": "json",
            "content": nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(probe)])})
        cells, session = await run_notebook(hub, name, "rosfpga-lab/probe.ipynb", [], keep=True)
        kept.append(f"{base}/sessions/{session}")
        found = re.search(r"DEFAULT (\S+)", _text(cells))
        assert found, _text(cells)
        defaults.append(found[1])
    for path in kept:
        await hub.request("DELETE", path, ok=(204, 404))
    assert len(set(defaults)) == USERS, f"users share a default master: {defaults}"

    await _assignments(hub, [name for name, _ in users], state=hub.log.parent)
    return results


def _nbgrader(args: list[str], cwd: Path) -> None:
    env = dict(os.environ, PATH=f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}")
    proc = subprocess.run([str(BIN / "nbgrader"), *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=240)
    assert proc.returncode == 0, f"nbgrader {' '.join(args)}:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}"


async def _assignments(hub: Hub, names: list[str], state: Path) -> None:
    """The teacher releases notebook 2 (nbgrader, server-wide exchange of course/setup.sh); each
    student fetches and submits it in JupyterLab (nbgrader's Assignments panel, through the hub);
    the teacher collects all three."""
    from traitlets.config.loader import PyFileConfigLoader

    exchange = Path(PyFileConfigLoader(NBGRADER_SERVER_CONFIG.name, str(
        NBGRADER_SERVER_CONFIG.parent)).load_config().Exchange.root)
    course_id, assignment = f"{names[0]}-course", "02_tcpros"
    course = state / "course"
    subprocess.run([str(BIN / "rosfpga-lab"), "notebooks", "nbgrader", str(course), assignment,
                    "--source", str(ROOT / "notebooks" / "solutions")], check=True, timeout=120,
                   capture_output=True)
    where = [f"--CourseDirectory.course_id={course_id}"]
    try:
        _nbgrader(["generate_assignment", assignment] + where, course)
        _nbgrader(["release_assignment", assignment] + where, course)
        query = urllib.parse.urlencode({"course_id": course_id, "assignment_id": assignment})
        for name in names:
            listed = await hub.request("GET", f"/user/{name}/assignments?course_id={course_id}")
            assert any(a["assignment_id"] == assignment and a["status"] == "released"
                       for a in listed["value"]), listed
            fetched = await hub.request("POST", f"/user/{name}/assignments/fetch?{query}")
            assert fetched["success"], fetched
            copy = Path(pwd.getpwnam(name).pw_dir) / assignment / f"{assignment}.ipynb"
            assert copy.stat().st_uid == pwd.getpwnam(name).pw_uid, f"{copy} is not {name}'s"
            submitted = await hub.request("POST", f"/user/{name}/assignments/submit?{query}")
            assert submitted["success"], submitted
        _nbgrader(["collect", assignment] + where, course)
        for name in names:
            assert (course / "submitted" / name / assignment / f"{assignment}.ipynb").exists(), name
    finally:
        shutil.rmtree(exchange / course_id, ignore_errors=True)


def test_three_users_run_notebooks_0_2_7_at_once_through_jupyterhub(
        unix_users: list[tuple[str, str]], tmp_path: Path) -> None:
    state = tmp_path / "hub"
    state.mkdir()
    hub = Hub(state)
    try:
        results = asyncio.run(_course(hub, unix_users))
    finally:
        hub.stop()

    masters, tmpdirs = set(), set()
    for name, _ in unix_users:
        home = pwd.getpwnam(name).pw_dir
        for target, _ in RUNS:
            text = _text(results[name][target])
            cwd = re.search(r"CWD (\S+)", text)
            assert cwd and cwd[1] == f"{home}/rosfpga-lab", f"{name} {target} ran in {cwd}"
            masters.add(re.search(r"MASTER (\S+)", text)[1])
            tmpdir = re.search(r"TMPDIR (\S+)", text)[1]
            assert tmpdir.startswith(f"{home}/"), f"{name} {target}: TMPDIR {tmpdir}"
            tmpdirs.add(tmpdir)
        solved = results[name]["02_tcpros_solved.ipynb"]
        assert sum("\u2714 Exercise" in _text([c]) for c in solved) == 3, f"{name}: notebook 2"
        # real rostopic and a rospy node joined each user's graph (when ROS 1 is installed)
        check_real_ros_part(nbformat.v4.new_notebook(cells=results[name]["07_workshop_demo.ipynb"]))
    # notebooks 0, 2 and 7 of three users: nine masters, all different, none on roscore's port
    assert len(masters) == len(RUNS) * USERS, masters
    assert not any(m.endswith(":11311/") for m in masters), masters
    assert len(tmpdirs) == USERS, tmpdirs
