#!/usr/bin/env bash
# Makes the recordings of the gap suite (made by other engines) that `.ci/run` scores with
# `partscene gap-bench`, under DIR, in the 'suite' environment of VENVS (scripts/ci_venvs.sh).
# `.ci/run` starts it in the background, at the lowest CPU priority, once the environments are
# made: the simulators then run on what the Rust builds leave idle, and the recordings are the same
# as when they ran in the foreground (each generator is seeded and single-threaded).
# Usage: scripts/ci_gap_suites.sh VENVS DIR
set -euo pipefail
cd "$(dirname "$0")/.."
venvs="$1"
suite_dir="$2"
# One environment for every engine: it starts with the first engines' packages
# (scripts/ci_venvs.sh), and each later engine's are added before its generators run. Each
# generator is one single-threaded simulator process, independent of the others: they run one per
# core (scripts/parallel.sh), in the same cumulative environment as when they ran one by one (so
# the recordings are the same).
py="$venvs/suite/bin/python"
suite_pip=("$venvs/suite/bin/pip" install --quiet --disable-pip-version-check)
# Genesis's environment of its own (its requirements, torch among them, would move versions the other
# engines' recordings are made with): mostly download, made in the background while the first
# engines' recordings are made.
(python3 -m venv "$venvs/genesis" &&
  "$venvs/genesis/bin/pip" install --quiet --disable-pip-version-check --only-binary=:all: \
    -r scripts/gap_suite_genesis_requirements.txt) &
genesis_env=$!
scripts/parallel.sh \
  "$py scripts/gap_suite.py --out $suite_dir/objects --seed 0" \
  "$py scripts/gap_suite.py --out $suite_dir/seed1/objects --seed 1" \
  "$py scripts/gap_suite.py --arms --arm-source builtin --out $suite_dir/arms --seed 0" \
  "$py scripts/gap_suite.py --arms --arm-source builtin --out $suite_dir/seed1/arms --seed 1" \
  "$py scripts/gap_suite.py --arms --arm-source builtin --out $suite_dir/seed3/arms --seed 3" \
  "$py scripts/gap_suite.py --stuck-arms --arm-source builtin --out $suite_dir/stuck_arms --seed 0" \
  "$py scripts/gap_suite.py --stuck-arms --arm-source builtin --out $suite_dir/seed1/stuck_arms --seed 1" \
  "$py scripts/gap_suite_bullet_arms.py --out $suite_dir/bullet_arms --seed 0" \
  "$py scripts/gap_suite_bullet_arms.py --out $suite_dir/seed1/bullet_arms --seed 1" \
  "$py scripts/gap_suite_physx.py --out $suite_dir/physx --seed 0"
"${suite_pip[@]}" --only-binary=:all: -r scripts/gap_suite_dart_requirements.txt
scripts/parallel.sh \
  "$py scripts/gap_suite_dart.py --out $suite_dir/dart --seed 0" \
  "$py scripts/gap_suite_dart.py --out $suite_dir/seed1/dart --seed 1" \
  "$py scripts/gap_suite_dart.py --out $suite_dir/seed3/dart --seed 3"
"${suite_pip[@]}" --only-binary=:all: -r scripts/gap_suite_drake_requirements.txt
scripts/parallel.sh \
  "$py scripts/gap_suite_drake.py --out $suite_dir/drake --seed 0" \
  "$py scripts/gap_suite_drake_arms.py --out $suite_dir/drake_arms --seed 0" \
  "$py scripts/gap_suite_drake_arms.py --out $suite_dir/seed1/drake_arms --seed 1"
# Warp compiles Newton's CPU kernels with the system C++ compiler.
if ! command -v g++ >/dev/null; then
  DEBIAN_FRONTEND=noninteractive apt-get update -qq >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq g++ >/dev/null
fi
"${suite_pip[@]}" --only-binary=:all: -r scripts/gap_suite_newton_requirements.txt
"$py" scripts/gap_suite_newton.py --out "$suite_dir/newton" --seed 0
"${suite_pip[@]}" --only-binary=:all: -r scripts/gap_suite_klampt_requirements.txt
scripts/parallel.sh \
  "$py scripts/gap_suite_klampt.py --out $suite_dir/klampt --seed 0" \
  "$py scripts/gap_suite_klampt.py --out $suite_dir/seed1/klampt --seed 1"
# pptree (a jaxsim requirement) exists only as a source archive: built with the venv's own
# setuptools (Python 3.11's bundled one), not a fresh download, so the build is pinned too.
# That setuptools builds wheels only with the `wheel` package beside it (pinned here): without it
# a machine whose pip cache holds no pptree wheel fails with "invalid command 'bdist_wheel'".
"${suite_pip[@]}" --only-binary=:all: wheel==0.45.1
"${suite_pip[@]}" --no-build-isolation --no-binary pptree pptree==3.1
"${suite_pip[@]}" --only-binary=:all: -r scripts/gap_suite_jaxsim_requirements.txt
scripts/parallel.sh \
  "$py scripts/gap_suite_jaxsim.py --out $suite_dir/jaxsim --seed 0" \
  "$py scripts/gap_suite_jaxsim.py --out $suite_dir/seed1/jaxsim --seed 1" \
  "$py scripts/gap_suite_jaxsim.py --out $suite_dir/seed3/jaxsim --seed 3"
# The Robotics Toolbox's PUMA 560 (its published motors and friction; a tenth engine): last, as
# its packages (matplotlib, scipy, Pinocchio) are the ones most likely to move a version the
# others were made with.
"${suite_pip[@]}" --only-binary=:all: -r scripts/gap_suite_rtb_requirements.txt
scripts/parallel.sh \
  "$py scripts/gap_suite_rtb.py --out $suite_dir/rtb --seed 0" \
  "$py scripts/gap_suite_rtb.py --out $suite_dir/seed1/rtb --seed 1"
# Genesis (an eleventh engine, held out until its cases were written): its environment, made in the
# background from the start (above), is waited for here.
if ! wait "$genesis_env"; then
  echo "CI: cannot install the 'genesis' environment from PyPI (scripts/gap_suite_genesis_requirements.txt)" >&2
  exit 1
fi
scripts/parallel.sh \
  "$venvs/genesis/bin/python scripts/gap_suite_genesis_arms.py --out $suite_dir/genesis_arms --seed 0" \
  "$venvs/genesis/bin/python scripts/gap_suite_genesis_arms.py --out $suite_dir/seed1/genesis_arms --seed 1" \
  "$venvs/genesis/bin/python scripts/gap_suite_genesis.py --out $suite_dir/genesis --seed 0" \
  "$venvs/genesis/bin/python scripts/gap_suite_genesis.py --out $suite_dir/seed1/genesis --seed 1"
echo "CI: gap suite recordings made in $SECONDS s"
