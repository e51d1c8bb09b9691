#!/usr/bin/env bash
# Makes CI's Python environments under DIR, each pinned as the check that uses it was tested:
# .ci/run starts this in the background while the Rust builds run (most of it is download) and
# waits for it before the first check that needs one. Usage: scripts/ci_venvs.sh DIR
#   browser   Playwright for web/check_browser.py
#   sim       PyBullet, MuJoCo and SAPIEN for the exports (check_sim_clients, check_self_collision)
#   usd       Pixar's usd-core (check_usd)
#   py        numpy, pytest and Ray for the Python package's tests (its wheel is added by .ci/run)
#   dynamics  Pinocchio and MuJoCo (check_dynamics)
#   ros       MCAP and rosbags (check_mcap)
#   suite     the gap suite's first engines (MuJoCo, Bullet, PhysX); .ci/run adds the others
set -euo pipefail
cd "$(dirname "$0")/.."
dir="$1"
make_venv() {
  local name="$1"
  shift
  python3 -m venv "$dir/$name"
  if ! "$dir/$name/bin/pip" install --quiet --disable-pip-version-check "$@"; then
    echo "CI: cannot install the '$name' environment from PyPI for $(python3 --version) (is PyPI reachable?): $*" >&2
    exit 1
  fi
}
make_venv browser playwright==1.65.2 pillow==13.0.0
make_venv sim --only-binary=:all: pybullet==3.2.7 mujoco==4.0.0 numpy==2.4.6 sapien==3.0.3
make_venv usd --only-binary=:all: usd-core==26.11
make_venv py --only-binary=:all: numpy==2.4.6 pytest==9.2.0 ray==2.60.0
make_venv dynamics --only-binary=:all: -r scripts/check_dynamics_requirements.txt
make_venv ros --only-binary=:all: mcap==1.6.0 mcap-ros2-support==0.6.0 rosbags==0.11.9 numpy==2.4.6
make_venv suite --only-binary=:all: -r scripts/gap_suite_physx_requirements.txt
echo "CI: Python environments made in $SECONDS s"
