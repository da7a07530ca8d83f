#!/usr/bin/env bash
# The lab's set-up in one place. Quick start (see README.md):
#   ./lab.sh          set up (.venv, package installed editable) and open JupyterLab on notebooks/
#                     (options go to JupyterLab: ./lab.sh --port 8889 --no-browser)
#   ./lab.sh test     set up (with the test extras) and run the whole test suite (options go to pytest;
#                     two workers on two or more cores, ROSFPGA_TEST_WORKERS=0 for one)
# Further: ./lab.sh setup [--test]   only set up;   ./lab.sh help
# Set PYTHON=/path/to/python3.x to choose the interpreter (3.11 to 3.13).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"
venv="$here/.venv"

usage() {
  sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'
}

find_python() {
  if [ -n "${PYTHON:-}" ]; then echo "$PYTHON"; return; fi
  for candidate in python3 python3.13 python3.12 python3.11; do
    if command -v "$candidate" >/dev/null 2>&1 &&
       "$candidate" -c 'import sys; sys.exit(not ((3, 11) <= sys.version_info[:2] <= (3, 13)))' 2>/dev/null; then
      echo "$candidate"; return
    fi
  done
  echo "lab.sh: error: no Python 3.11 to 3.13 found; install one, or set PYTHON=/path/to/python3.x" >&2
  exit 1
}

setup() {
  local extras="$1"   # "" or "[test]"
  if [ ! -x "$venv/bin/python" ]; then
    local py; py="$(find_python)"
    echo "lab.sh: creating the virtual environment .venv with $("$py" --version)"
    "$py" -m venv "$venv"
  fi
  # Install only when pyproject.toml or the extras changed, so a set-up machine works offline.
  # The stamp holds "CHECKSUM EXTRAS" lines; an install with [test] also serves the plain one.
  local stamp="$venv/.rosfpga-lab-installed" sum want
  sum="$(cksum < pyproject.toml)"
  want="$sum $extras"
  if ! grep -qxF -e "$want" -e "$sum [test]" "$stamp" 2>/dev/null; then
    echo "lab.sh: installing rosfpga-lab$extras into .venv (editable)"
    "$venv/bin/python" -m pip install --quiet --upgrade pip
    "$venv/bin/python" -m pip install --quiet -e ".$extras"
    if [ "$extras" = "[test]" ]; then   # real ROS 2's wheels: optional (Linux x86_64 only)
      "$venv/bin/python" -m pip install --quiet -e ".[test,ros2]" || echo "lab.sh: note: real" \
        "ROS 2 Jazzy's wheels (the [ros2] extra) do not install here; their tests will skip" >&2
    fi
    echo "$want" >> "$stamp"
  fi
  # JupyterLab's own defaults for this lab: no "get news?" pop-up over the outputs, no update
  # check (the lab runs offline). JupyterLab reads them from its app settings directory.
  local settings="$venv/share/jupyter/lab/settings"
  if ! cmp -s "$here/data/jupyterlab_overrides.json" "$settings/overrides.json"; then
    mkdir -p "$settings"
    cp "$here/data/jupyterlab_overrides.json" "$settings/overrides.json"
  fi
  # The student's lab: no nbgrader panels or Validate button (nbgrader belongs to the course
  # server, where each assignment carries graded checks; here Validate would pass an unanswered
  # notebook), none of nbgrader's server pages either (its teacher page /formgrader), and
  # notebooks/solutions/ out of the file browser (still open on purpose: File > Open from
  # Path..., solutions/01_xmlrpc_handshake.ipynb). Jupyter reads them from the environment's
  # etc/jupyter (jupyter_server_config.json wins over the jupyter_server_config.d/nbgrader.json
  # that nbgrader installs beside it).
  local etc="$venv/etc/jupyter"
  if ! cmp -s "$here/data/jupyterlab_page_config.json" "$etc/labconfig/page_config.json"; then
    mkdir -p "$etc/labconfig"
    cp "$here/data/jupyterlab_page_config.json" "$etc/labconfig/page_config.json"
  fi
  local name
  for name in jupyter_lab_config.json jupyter_server_config.json; do
    if ! cmp -s "$here/data/$name" "$etc/$name"; then
      mkdir -p "$etc"
      cp "$here/data/$name" "$etc/$name"
    fi
  done
}

# No command, or only options for JupyterLab (./lab.sh --port 8889): open the lab.
if [ $# -eq 0 ] || { [[ "$1" == -* ]] && [[ "$1" != "-h" && "$1" != "--help" ]]; }; then
  set -- lab "$@"
fi
cmd="$1"
shift
case "$cmd" in
  lab|open)
    setup ""
    root=()   # a container or a root shell: JupyterLab refuses root unless told (loopback only here)
    if [ "$(id -u)" = 0 ]; then
      echo "lab.sh: running as root (a container?): starting JupyterLab with --allow-root" >&2
      root=(--allow-root)
    fi
    exec "$venv/bin/jupyter" lab --ServerApp.ip=127.0.0.1 --notebook-dir="$here/notebooks" \
      --LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate "${root[@]}" "$@" ;;
  test)
    setup "[test]"
    # On two or more cores, two pytest-xdist workers (a file each at a time: its module fixtures
    # built once); ROSFPGA_TEST_WORKERS=N sets how many, 0 runs in this one process.
    workers="${ROSFPGA_TEST_WORKERS:-$( [ "$(nproc 2>/dev/null || echo 1)" -ge 2 ] && echo 2 || echo 0 )}"
    parallel=()
    if [ "$workers" != 0 ]; then parallel=(-n "$workers" --dist loadfile --no-loadscope-reorder); fi
    exec "$venv/bin/python" -m pytest "${parallel[@]}" "$@" ;;
  setup)
    if [ "${1:-}" = "--test" ]; then setup "[test]"; else setup ""; fi ;;
  help|-h|--help)
    usage ;;
  *)
    echo "lab.sh: error: unknown command '$cmd'" >&2; usage >&2; exit 2 ;;
esac
