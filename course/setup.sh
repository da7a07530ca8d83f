#!/usr/bin/env bash
# Set up a course server for rosfpga_lab (course/README.md). Run as root, once, from a
# checkout of the lab (again after `git pull` to update it):
#   sudo course/setup.sh
# What it does:
#   1. the shared environment PREFIX/venv (default /opt/rosfpga-lab): the lab with its [course]
#      extra (JupyterHub, nbgrader), installed once for every user;
#   2. JupyterHub's proxy, configurable-http-proxy, from npm into course/node_modules (npm ci);
#   3. the student notebooks in PREFIX/notebooks (every user gets a copy at first login); of
#      nbgrader's JupyterLab panels only the students' Assignments list;
#   4. the Unix groups of jupyterhub_config.py (students, teachers), the hub's state directory
#      STATE (default /srv/rosfpga-lab) and nbgrader's exchange for releasing and collecting.
# Then start the hub with the command it prints. Set PYTHON=/path/to/python3.x (3.11 to 3.13),
# PREFIX, STATE or EXCHANGE to choose other places.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(dirname "$here")"
PREFIX="${PREFIX:-/opt/rosfpga-lab}"
STATE="${STATE:-/srv/rosfpga-lab}"
EXCHANGE="${EXCHANGE:-/srv/nbgrader/exchange}"
COURSE_ID="${COURSE_ID:-rosfpga-lab}"

if [ "$(id -u)" -ne 0 ]; then
  echo "setup.sh: error: run as root (the hub starts each user's server as that user)" >&2
  exit 1
fi
for tool in npm useradd groupadd; do
  command -v "$tool" >/dev/null || { echo "setup.sh: error: $tool not found (Debian: apt-get install nodejs npm passwd)" >&2; exit 1; }
done
umask 022

# The interpreter must be one every user may run (not one under /root, as pyenv's is).
py="${PYTHON:-}"
if [ -z "$py" ]; then
  for candidate in /usr/bin/python3 python3; do
    if "$candidate" -c 'import sys, venv; sys.exit(not (3, 11) <= sys.version_info[:2] <= (3, 13))' 2>/dev/null; then
      py="$candidate"; break
    fi
  done
fi
if [ -z "$py" ] || ! setpriv --reuid="$(id -u nobody)" --regid="$(id -g nobody)" --clear-groups "$py" -c '' 2>/dev/null; then
  echo "setup.sh: error: no Python 3.11 to 3.13 that every user may run (${py:-none found});" \
       "set PYTHON=/usr/bin/python3.x (Debian: apt-get install python3-venv)" >&2
  exit 1
fi
echo "setup.sh: shared environment $PREFIX/venv ($("$py" --version))"
mkdir -p "$PREFIX"
[ -x "$PREFIX/venv/bin/python" ] || "$py" -m venv "$PREFIX/venv"
"$PREFIX/venv/bin/python" -m pip install --quiet --upgrade pip
"$PREFIX/venv/bin/python" -m pip install --quiet -r "$repo/environment.txt" "$repo[course]"
# the lab itself again, so a re-run after `git pull` installs the new version of the same number
"$PREFIX/venv/bin/python" -m pip install --quiet --no-deps --force-reinstall "$repo"

# Students see nbgrader's Assignments list (fetch, validate, submit); the teacher's panels stay
# hidden, as the teacher grades from the command line (course/README.md). So does the notebook toolbar's
# Validate button: on the copies in ~/rosfpga-lab, which carry no graded cells, it said "Success"
# for an unanswered notebook (the Assignments list validates the fetched, graded versions).
"$PREFIX/venv/bin/jupyter" labextension disable --level=sys_prefix @jupyter/nbgrader:formgrader \
    @jupyter/nbgrader:create-assignment @jupyter/nbgrader:course-list \
    @jupyter/nbgrader:validate-assignment >/dev/null 2>&1
"$PREFIX/venv/bin/jupyter" server extension disable --sys-prefix \
    nbgrader.server_extensions.formgrader nbgrader.server_extensions.course_list >/dev/null 2>&1

echo "setup.sh: configurable-http-proxy into $here/node_modules"
(cd "$here" && npm ci --no-audit --no-fund --loglevel=error)

echo "setup.sh: student notebooks into $PREFIX/notebooks"
mkdir -p "$PREFIX/notebooks"
cp "$repo"/notebooks/[0-9][0-9]_*.ipynb "$repo/notebooks/README.md" "$PREFIX/notebooks/"

group_of() { sed -n "s/^$1 = \"\\(.*\\)\"$/\\1/p" "$here/jupyterhub_config.py"; }
for group in "$(group_of STUDENTS_GROUP)" "$(group_of TEACHERS_GROUP)"; do
  groupadd -f "$group"
done

echo "setup.sh: hub state in $STATE, nbgrader exchange in $EXCHANGE"
mkdir -p "$STATE" "$EXCHANGE"
chmod 700 "$STATE"
chmod 1777 "$EXCHANGE"      # nbgrader's exchange: everyone may drop in, nobody may delete others'
mkdir -p /etc/jupyter
cat > /etc/jupyter/nbgrader_config.py <<EOF
# Written by rosfpga_lab's course/setup.sh: the course every user of this server takes part in.
c = get_config()
c.CourseDirectory.course_id = "$COURSE_ID"
c.Exchange.root = "$EXCHANGE"
EOF

cat <<EOF
setup.sh: done. Next:
  add students:  useradd -m -G $(group_of STUDENTS_GROUP) alice && passwd alice
  add a teacher: useradd -m -G $(group_of TEACHERS_GROUP) bob && passwd bob
  start the hub: cd $STATE && ROSFPGA_COURSE_NOTEBOOKS=$PREFIX/notebooks \\
                 $PREFIX/venv/bin/jupyterhub -f $here/jupyterhub_config.py
                 (add --ip 0.0.0.0 --ssl-key KEY --ssl-cert CERT to open it to the network)
EOF
