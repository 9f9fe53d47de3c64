#!/usr/bin/env bash
# Installs the Debian packages yade-qdem needs (when root), or prints the one
# apt-get line a user must run.  Idempotent: does nothing when all are there.
set -euo pipefail
PKGS="yade cmake g++ make libeigen3-dev libcgal-dev pybind11-dev python3-pybind11 python3-numpy
python3-meshio python3-pytest python3-pytest-xdist python3-matplotlib python3-scipy python3-vtk9 xvfb libgtest-dev libopenmpi-dev openmpi-bin python3-mpi4py python3-hypothesis tetgen python3-gmsh
python3-sphinx furo python3-myst-parser"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
if [ -z "$missing" ]; then
  exit 0
fi
if [ "$(id -u)" = 0 ]; then
  echo "deps: installing:$missing"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q $missing
else
  echo "deps: missing Debian packages. Run as root:"
  echo "  sudo apt-get install -y$missing"
  exit 1
fi
